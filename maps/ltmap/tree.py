"""The LT-map itself: landmarks in a tree whose root-to-leaf branches are the viewframes of a route.

Jäger, Mair et al., IROS 2013 (docs/design.md, method 1). A *landmark* is a descriptor (a binary
ORB row, or the id of the simulator's ideal bearings sensor) with a unit bearing in the route
frame (compensated for the robot's rotation, :func:`maps.ltmap.learner.compensate`). A
*viewframe* is the set of landmarks seen from one place of a taught route: the union of the
nodes on a branch from the root to a leaf. Each landmark lives in exactly one node, so a
landmark seen from many places is stored once; far, persistent landmarks sit near the root and
short-lived local ones near the leaves. Pure: numpy arrays and dataclasses, no I/O
(:mod:`maps.ltmap.file` saves and loads). How the paper is read here (where it is vague):

- **One bearing per landmark.** A landmark stored once and shared by several viewframes has one
  bearing, the one it was stored with. A tracked landmark is shared with the new viewframe only
  while its current bearing stays within ``share_angle`` of the stored one (the learner's
  default: about 3 deg). A landmark that moved further (a near landmark, after some travel)
  counts as lost for the tree, and its current sighting is stored again in the new leaf with
  its current bearing.
- **Levels.** Every leaf is at the same depth, the tree's *height*: a level is a time scale, the
  leaves hold what was seen from one place only, their parents what a run of neighbouring places
  shared, and so on up to the root, what the whole route saw. "Cut the lowest level" then drops
  the most local landmarks of the whole route at once, as the paper's memory table shows (a few
  heights between the full tree and a lost robot), not one viewframe at a time
  (:mod:`maps.ltmap.prune`).
- **Learning (algorithm 1).** The landmarks new since the last viewframe go into the new leaf.
  The new branch shares the top of the last viewframe's branch ``n_0 .. n_(j-1)`` (``j = 0``: a
  new root above the old one) and continues with fresh nodes down to the leaf level. The tracked
  landmarks of the last branch below the shared part move up into its lowest shared node
  ``n_(j-1)`` where that adds no viewframe that never saw them: in a run of viewframes that
  started at the last one this is the paper's "the landmarks still tracked move one level up".
  Where moving up would put a landmark into earlier viewframes that never saw it (the paper
  leaves this open; a tree cannot hold every overlap of landmark lifetimes), its current
  sighting is stored in the new leaf instead, as for a landmark whose bearing moved: one more
  stored row instead of wrong landmarks in other viewframes, whose homing would match them at
  bearings from elsewhere. The paper does not say where the new branch leaves the old one:
  ``j`` (:func:`attach_level`) minimises the lost landmarks left in shared nodes (they stay in
  the new viewframe though it no longer sees them) plus the tracked landmarks stored again,
  both counted as one landmark row; ties go to the deeper ``j`` (the branches stay apart). So
  every viewframe holds exactly the landmarks it saw, except lost ones of shared nodes, and
  every stored bearing is within ``share_angle`` of the landmark's bearing at every viewframe
  that tracked it. On a synthetic corridor (tests, benchmark) over 99% of a viewframe's
  landmarks are visible from it within 5 deg of their stored bearing, for 5-10% more memory
  than moving every tracked landmark up (which leaves about a third of them wrong).
- **Gap filling** (:meth:`LandmarkTree.fill_gaps`, :mod:`maps.ltmap.gaps`): a landmark stored
  twice within ``share_angle`` (it dropped out of tracking and was stored again) becomes one, in
  the common node of its two copies, when that node gives it only to a short gap of viewframes
  between its sightings. With it, a viewframe may hold a landmark it did not see in that gap.
- **Memory** (:meth:`LandmarkTree.memory_bytes`) is exactly what :meth:`LandmarkTree.to_arrays`
  holds (:mod:`maps.ltmap.arrays`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from maps.ltmap.arrays import (
    BEARING_DTYPE,
    ID_DTYPE,
    IDS,
    INDEX_DTYPE,
    NODE_BYTES,
    PLACE_BYTES,
    PLACE_DTYPE,
    PLACES,
    VIEWFRAME_BYTES,
    check_kind,
    checked_arrays,
    data_name,
    empty_data,
    preorder,
    readonly,
)
from maps.ltmap.gaps import DEFAULT_GAPS, GapConfig, GapFill, found_again, plan_shifts
from maps.ltmap.matching import Viewframe, ViewframeCache, match_viewframe, stack_viewframe
from maps.ltmap.prune import (
    DEFAULT_MIN_LANDMARKS,
    LevelCut,
    PruneReport,
    PruneStep,
    cut_lowest_level,
    cut_quiet_levels,
    earliest_sources,
    follow,
    quiet_levels,
)
from perception.matching import LandmarkMatches
from perception.observation import Observation
from perception.similarity import DEFAULT_SCALE, bearing_angles, default_threshold

DEFAULT_THRESHOLD = default_threshold()  # eq. 1: the cost of a 3 deg bearing change (1.085e-6)
NO_GATE = float("inf")  # share every tracked landmark, whatever its bearing now


def _unit(vectors: np.ndarray) -> np.ndarray:
    v = np.asarray(vectors, dtype=np.float64)
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-30)


@dataclass(frozen=True, slots=True, eq=False)
class LandmarkSet:
    """Landmarks as rows: route-frame unit ``bearings`` (N x 3) with ``descriptors`` (N x W) or ``ids`` (N,)."""

    bearings: np.ndarray
    descriptors: np.ndarray | None = None
    ids: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.bearings)

    def take(self, index: np.ndarray) -> LandmarkSet:
        """The rows ``index`` (indices or a boolean mask)."""
        return LandmarkSet(np.asarray(self.bearings).reshape(-1, 3)[index],
                           None if self.descriptors is None else self.descriptors[index],
                           None if self.ids is None else self.ids[index])

    @classmethod
    def from_observation(cls, observation: Observation, bearings: np.ndarray, index: np.ndarray) -> LandmarkSet:
        """The observed landmarks ``index``, with ``bearings`` (one row per observed landmark) instead of
        the observation's own (e.g. compensated for the heading)."""
        index = np.asarray(index, dtype=np.int64)
        chosen = np.asarray(bearings, dtype=np.float64).reshape(-1, 3)[index]
        if observation.ids is not None:
            return cls(chosen, ids=np.asarray(observation.ids, dtype=ID_DTYPE)[index])
        if observation.features is None:
            raise ValueError("the observation has neither descriptors nor ids")
        return cls(chosen, descriptors=observation.features.descriptors[index])


@dataclass(frozen=True, slots=True)
class MapSummary:
    """What ``bearings map info`` prints and a mission report's ``ltmap`` section holds."""

    kind: str
    viewframes: int
    landmarks: int
    nodes: int
    height: int
    memory_bytes: int
    landmarks_per_level: tuple[int, ...]
    threshold: float


def shared_cover(leaves: np.ndarray) -> np.ndarray:
    """Per branch point ``j``: how many viewframes lie under the lowest shared node ``n_(j-1)``
    (under the old root for ``j = 0``, which the new root covers)."""
    leaves = np.asarray(leaves, dtype=np.int64)
    return np.concatenate((leaves[:1], leaves[:-1]))


def attach_level(lost: np.ndarray, tracked: np.ndarray, leaves: np.ndarray) -> int:
    """Where a new viewframe's branch leaves the last one's (``j``: it shares ``n_0 .. n_(j-1)``).

    ``lost``, ``tracked`` and ``leaves`` are per node of the last branch (root first): its
    landmarks lost and tracked now, and how many viewframes lie under it. Cost of ``j``: the lost
    landmarks left in the shared nodes plus the tracked landmarks below them that cannot move up
    without joining viewframes that never saw them (they are stored again). Ties: the deepest ``j``.
    """
    lost, tracked, leaves = (np.asarray(a, dtype=np.int64) for a in (lost, tracked, leaves))
    stale = np.concatenate(([0], np.cumsum(lost)[:-1]))
    below = np.arange(len(leaves))[None, :] >= np.arange(len(leaves))[:, None]  # [j, i]: i >= j
    stored_again = (below & (leaves[None, :] < shared_cover(leaves)[:, None])) @ tracked
    cost = stale + stored_again
    return int(len(cost) - 1 - np.argmin(cost[::-1]))


def _resolve(index: np.ndarray, alive: np.ndarray) -> np.ndarray:
    """``index`` holds, for a deleted row, the OLD row it merged into (which may be deleted too):
    follow to a surviving row and give its new index."""
    renumbered = np.where(alive, np.cumsum(alive) - 1, -1)
    out = renumbered.copy()
    for row in np.flatnonzero(~alive).tolist():
        target = int(index[row])
        while not alive[target]:
            target = int(index[target])
        out[row] = renumbered[target]
    return out


def _carried_places(places: list[tuple[float, float]] | None, viewframe_index: np.ndarray
                    ) -> list[tuple[float, float]] | None:
    """The places after a cut: a kept viewframe keeps the place of the earliest viewframe merged
    into it (``viewframe_index``: each old viewframe's new index, -1 when deleted)."""
    return None if places is None else [places[old] for old in earliest_sources(viewframe_index)]


@dataclass
class _Rows:
    """The landmark rows of a tree (mutable storage): node, unit bearing, and ``data``, the
    descriptor row (N x W) or the id (N,) depending on the tree's kind."""

    node: np.ndarray
    bearings: np.ndarray
    data: np.ndarray

    def take(self, index: np.ndarray) -> _Rows:
        return _Rows(self.node[index], self.bearings[index], self.data[index])

    def copy(self) -> _Rows:
        return _Rows(self.node.copy(), self.bearings.copy(), self.data.copy())


class LandmarkTree:
    """An LT-map: landmarks in a tree whose root-to-leaf branches are the viewframes of a route.

    Viewframes are numbered in route order (0: start, last: goal). Built by
    :class:`~maps.ltmap.learner.RouteLearner` (or :meth:`add_viewframe`), shrunk by
    :meth:`prune_level` / :meth:`prune_to`, matched against observations by :meth:`match` (the hot
    path of route following, cached per viewframe).
    """

    def __init__(self, kind: str, *, threshold: float = DEFAULT_THRESHOLD, scale: float = DEFAULT_SCALE) -> None:
        check_kind(kind)
        for name, value in (("threshold", threshold), ("scale", scale)):
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value}")
        self.kind = kind
        self.threshold = float(threshold)
        self.scale = float(scale)  # eq. 1's b: delta_t against ``threshold`` is measured with it
        self._parent: list[int] = []
        self._leaves: list[int] = []
        self._places: list[tuple[float, float]] | None = None  # per viewframe, where teach odometry put it
        self._rows = _Rows(np.zeros(0, dtype=np.int64), np.zeros((0, 3), dtype=BEARING_DTYPE), empty_data(kind))
        self._cache = ViewframeCache()

    # ----- size and shape ---------------------------------------------------------------------

    @property
    def viewframe_count(self) -> int:
        return len(self._leaves)

    @property
    def landmark_count(self) -> int:
        return len(self._rows.node)

    @property
    def node_count(self) -> int:
        return len(self._parent)

    @property
    def root(self) -> int:
        """The root node (-1 for an empty map)."""
        return self.branch_nodes(0)[0] if self._leaves else -1

    @property
    def height(self) -> int:
        """Depth of the leaves (every leaf is at the same depth); 0 for one viewframe or none."""
        return len(self.branch_nodes(0)) - 1 if self._leaves else 0

    def memory_bytes(self) -> int:
        """Bytes of the map's content: exactly the ``nbytes`` of :meth:`to_arrays` (see :mod:`maps.ltmap.arrays`)."""
        data = self._rows.data
        row = 3 * np.dtype(BEARING_DTYPE).itemsize + int(np.prod(data.shape[1:], dtype=np.int64)) * data.itemsize
        per_viewframe = VIEWFRAME_BYTES + (PLACE_BYTES if self._places is not None else 0)
        return self.landmark_count * row + self.node_count * NODE_BYTES + self.viewframe_count * per_viewframe

    def depths(self) -> np.ndarray:
        """Depth of every node (root 0)."""
        depth = np.full(self.node_count, -1, dtype=np.int64)
        for start in range(self.node_count):
            chain, node = [], start
            while node >= 0 and depth[node] < 0:
                chain.append(node)
                node = self._parent[node]
            base = depth[node] if node >= 0 else -1
            for offset, n in enumerate(reversed(chain), start=1):
                depth[n] = base + offset
        return depth

    def landmarks_per_level(self) -> tuple[int, ...]:
        """How many landmarks are stored at each depth, root first."""
        if not self._leaves:
            return ()
        per_node = np.bincount(self._rows.node, minlength=self.node_count)
        return tuple(int(c) for c in np.bincount(self.depths(), weights=per_node, minlength=self.height + 1))

    def summary(self) -> MapSummary:
        return MapSummary(self.kind, self.viewframe_count, self.landmark_count, self.node_count, self.height,
                          self.memory_bytes(), self.landmarks_per_level(), self.threshold)

    # ----- landmarks and viewframes -----------------------------------------------------------

    @property
    def bearings(self) -> np.ndarray:
        """Per landmark its stored unit bearing (N x 3 float32, route frame)."""
        return readonly(self._rows.bearings)

    @property
    def descriptors(self) -> np.ndarray | None:
        return None if self.kind == IDS else readonly(self._rows.data)

    @property
    def ids(self) -> np.ndarray | None:
        return readonly(self._rows.data) if self.kind == IDS else None

    @property
    def landmark_nodes(self) -> np.ndarray:
        """The node each landmark lives in."""
        return readonly(self._rows.node)

    @property
    def node_parents(self) -> tuple[int, ...]:
        """The parent of each node (-1: the root)."""
        return tuple(self._parent)

    @property
    def viewframe_leaves(self) -> tuple[int, ...]:
        """The leaf node of each viewframe, in route order."""
        return tuple(self._leaves)

    def node_landmarks(self, node: int) -> np.ndarray:
        """Map indices of the landmarks stored in ``node``."""
        return np.flatnonzero(self._rows.node == node)

    def branch_nodes(self, index: int) -> tuple[int, ...]:
        """The nodes of viewframe ``index``'s branch, root first."""
        node = self._leaves[index]
        chain = []
        while node >= 0:
            chain.append(node)
            node = self._parent[node]
        return tuple(reversed(chain))

    @property
    def has_places(self) -> bool:
        """The map knows where each viewframe was taught (teach odometry); False for maps taught
        without odometry or read from files written before places were kept (version 2)."""
        return self._places is not None

    def place(self, index: int) -> np.ndarray | None:
        """Where viewframe ``index`` was taught: (x, y) in the teach's odometry frame (m), None
        when the map has no places."""
        if self._places is None:
            return None
        return np.array(self._places[index], dtype=float)

    def viewframe(self, index: int, *, cached: bool = True) -> Viewframe:
        """The landmarks of viewframe ``index`` (negative: from the goal), stacked for matching."""
        index = range(self.viewframe_count)[index]
        return self._cache.get(index, self._build_viewframe) if cached else self._build_viewframe(index)

    def match(self, index: int, observation: Observation, *, bearings: np.ndarray | None = None,
              ratio: float | None = None, cached: bool = True) -> LandmarkMatches:
        """Match an observation against viewframe ``index``: ``ref`` the viewframe's bearings, ``cur``
        the observation's (``bearings`` replaces them, e.g. compensated), ``landmark`` indexes the
        viewframe (``viewframe(index).landmarks[m.landmark]`` are map indices). ``cached=False``
        builds the viewframe's stack again (only to measure what the cache saves)."""
        cur = np.asarray(observation.bearings if bearings is None else bearings, dtype=np.float64).reshape(-1, 3)
        return match_viewframe(self.viewframe(index, cached=cached), observation, cur, kind=self.kind, ratio=ratio)

    def _build_viewframe(self, index: int) -> Viewframe:
        landmarks = np.flatnonzero(np.isin(self._rows.node, self.branch_nodes(index)))
        depth = self.depths()[self._rows.node[landmarks]] if self.kind == IDS else None
        return stack_viewframe(index, self.kind, landmarks, self._rows.bearings, self._rows.data, depth)

    # ----- learning ---------------------------------------------------------------------------

    def add_viewframe(self, tracked: np.ndarray, sightings: LandmarkSet, new: LandmarkSet, *,
                      share_angle: float = NO_GATE, place: tuple[float, float] | None = None) -> int:
        """Append a viewframe at the end of the route (algorithm 1, see the module doc); its index.

        ``tracked``: map indices of the last viewframe's landmarks seen now, ``sightings`` how
        (one row each: current route-frame bearing and descriptor or id); ``new``: the landmarks
        seen since the last viewframe. A tracked landmark is shared when its sighting is within
        ``share_angle`` (rad) of its stored bearing and it can move up without joining viewframes
        that never saw it; otherwise its sighting is stored in the new leaf. The new leaf's rows
        are appended: map indices from the old ``landmark_count`` on, stored sightings first.
        ``place``: where odometry put the viewframe; a map has a place for every viewframe or none.
        """
        tracked = np.asarray(tracked, dtype=np.int64).ravel()
        for rows in (sightings, new):
            self._check_rows(rows)
        if len(sightings) != len(tracked) or len(np.unique(tracked)) != len(tracked):
            raise ValueError("tracked landmarks must be distinct, with one sighting each")
        if (place is None) != (self._places is None) and self._leaves:
            raise ValueError("a map has a place for every viewframe or for none")
        if not self._leaves:
            if len(tracked):
                raise ValueError("the first viewframe cannot track landmarks: the map is empty")
            leaf, again = self._new_node(-1), np.zeros(0, dtype=bool)
        else:
            if len(tracked) and (tracked.min() < 0 or tracked.max() >= self.landmark_count):
                raise ValueError("tracked landmarks must belong to the last viewframe")
            turned = bearing_angles(self._rows.bearings[tracked], sightings.bearings) > share_angle
            leaf, again = self._grow_branch(tracked[~turned])
            again = np.isin(tracked, tracked[~turned][again]) | turned
        self._append_rows(sightings.take(again), leaf)
        self._append_rows(new, leaf)
        self._leaves.append(leaf)
        if place is not None:
            self._places = [*(self._places or []), (float(place[0]), float(place[1]))]
        self._cache.clear()
        return len(self._leaves) - 1

    def fill_gaps(self, share_angle: float, config: GapConfig = DEFAULT_GAPS, *,
                  ratio: float | None = None) -> GapFill:
        """Find the last viewframe's landmarks again among the map's other rows and shift each found
        within ``share_angle`` to the common node of its two copies (:mod:`maps.ltmap.gaps`)."""
        if not self._leaves:
            return GapFill(0, 0, None, np.arange(0))
        candidates = np.flatnonzero(np.isin(self._rows.node, self.branch_nodes(-1)))
        pairs = found_again(self.kind, self._rows.data, self._rows.bearings, candidates, share_angle, ratio=ratio)
        plan = plan_shifts(self._parent, self._leaves, self._rows.node, pairs, config, viewframe_size=len(candidates))
        index = np.arange(self.landmark_count)
        if len(plan.drop):
            self._rows.node[plan.keep] = plan.node
            alive = np.ones(self.landmark_count, dtype=bool)
            alive[plan.drop] = False
            merged_into = np.arange(self.landmark_count)
            merged_into[plan.drop] = plan.keep  # a kept row may itself merge later in the batch: _resolve follows
            index = _resolve(merged_into, alive)
            self._rows = self._rows.take(alive)
            self._cache.clear()
        return GapFill(len(pairs), len(plan.drop), plan.loop, index)

    def _check_rows(self, new: LandmarkSet) -> None:
        data = new.ids if self.kind == IDS else new.descriptors
        if data is None:
            raise ValueError(f"this map holds {'landmark ids' if self.kind == IDS else self.kind + ' descriptors'}")
        if np.asarray(new.bearings).shape != (len(data), 3):
            raise ValueError("new landmarks need one bearing (3 components) each")
        if np.asarray(data).shape[1:] != self._rows.data.shape[1:]:
            raise ValueError(f"{self.kind} descriptors are {self._rows.data.shape[1]} wide")

    def _grow_branch(self, tracked: np.ndarray) -> tuple[int, np.ndarray]:
        """Share the top of the last branch, move up the tracked landmarks that can, add fresh nodes.

        Returns the new leaf and which of ``tracked`` could not move (to be stored again)."""
        path = np.array(self.branch_nodes(-1))
        level = np.full(self.node_count, -1, dtype=np.int64)
        level[path] = np.arange(len(path))
        landmark_level = level[self._rows.node]
        if np.any(landmark_level[tracked] < 0):
            raise ValueError("tracked landmarks must belong to the last viewframe")
        total = np.bincount(landmark_level[landmark_level >= 0], minlength=len(path))
        seen = np.bincount(landmark_level[tracked], minlength=len(path))
        leaves = self._leaf_counts()[path]
        j = attach_level(total - seen, seen, leaves)
        if j == 0:  # a new root above the old one: the whole tree goes one level down
            shared = self._new_node(-1)
            self._parent[path[0]] = shared
        else:
            shared = int(path[j - 1])
        below = landmark_level[tracked] >= j
        again = below & (leaves[landmark_level[tracked]] < shared_cover(leaves)[j])
        self._rows.node[tracked[below & ~again]] = shared
        node = shared
        for _ in range(len(path) - j):  # fresh nodes down to the leaf level (the last is the leaf)
            node = self._new_node(node)
        return node, again

    def _new_node(self, parent: int) -> int:
        self._parent.append(int(parent))
        return len(self._parent) - 1

    def _leaf_counts(self) -> np.ndarray:
        counts = np.zeros(self.node_count, dtype=np.int64)
        for leaf in self._leaves:
            node = leaf
            while node >= 0:
                counts[node] += 1
                node = self._parent[node]
        return counts

    def _append_rows(self, new: LandmarkSet, node: int) -> None:
        rows = self._rows
        rows.node = np.concatenate((rows.node, np.full(len(new), node, dtype=np.int64)))
        bearings = _unit(np.asarray(new.bearings).reshape(-1, 3)).astype(BEARING_DTYPE)
        rows.bearings = np.concatenate((rows.bearings, bearings))
        data = new.ids if self.kind == IDS else new.descriptors
        data = np.asarray(data, dtype=rows.data.dtype).reshape(-1, *rows.data.shape[1:])
        rows.data = np.concatenate((rows.data, data))

    # ----- pruning ----------------------------------------------------------------------------

    def prune_level(self, min_landmarks: int = DEFAULT_MIN_LANDMARKS) -> PruneStep | None:
        """Cut the lowest level (see :mod:`maps.ltmap.prune`); None when there is one level only."""
        if min_landmarks < 0:
            raise ValueError(f"min_landmarks must be >= 0, got {min_landmarks}")
        if self.height == 0:
            return None
        return self._apply(cut_lowest_level(self._parent, self._leaves, self._rows.node, min_landmarks), 1)

    def _prune_quiet_levels(self, budget_bytes: int, min_landmarks: int) -> PruneStep | None:
        """Cut at once the levels whose one-by-one cuts change only the chains at the bottom
        (:func:`maps.ltmap.prune.quiet_levels`): the same map as :meth:`prune_level` repeated, in
        one pass; None when fewer than two levels are quiet."""
        data = self._rows.data
        row = 3 * np.dtype(BEARING_DTYPE).itemsize + int(np.prod(data.shape[1:], dtype=np.int64)) * data.itemsize
        levels, chains = quiet_levels(self._parent, self._leaves, self._rows.node, min_landmarks,
                                      excess_bytes=self.memory_bytes() - budget_bytes, row_bytes=row,
                                      node_bytes=NODE_BYTES)
        if levels < 2:
            return None
        return self._apply(cut_quiet_levels(self._parent, self._leaves, self._rows.node, chains, levels), levels)

    def _apply(self, cut: LevelCut, levels: int) -> PruneStep:
        before = (self.height, self.memory_bytes(), self.landmark_count)
        self._parent, self._leaves = cut.node_parent, cut.viewframe_leaves
        self._places = _carried_places(self._places, cut.viewframe_index)
        self._rows = self._rows.take(cut.keep)
        self._rows.node = cut.landmark_nodes
        self._cache.clear()
        return PruneStep(before[0], self.height, before[1], self.memory_bytes(), before[2] - self.landmark_count,
                         cut.merged, cut.deleted, cut.landmark_index, cut.viewframe_index, levels)

    def prune_to(self, budget_bytes: int, min_landmarks: int = DEFAULT_MIN_LANDMARKS) -> PruneReport:
        """Cut levels until :meth:`memory_bytes` <= ``budget_bytes``; the map is unchanged when it cannot."""
        if budget_bytes < 0:
            raise ValueError(f"budget must be >= 0 bytes, got {budget_bytes}")
        before = self.memory_bytes()
        work, steps = self.copy(), list[PruneStep]()
        index, viewframes = np.arange(self.landmark_count), np.arange(self.viewframe_count)
        while work.memory_bytes() > budget_bytes:
            step = work._prune_quiet_levels(budget_bytes, min_landmarks) or work.prune_level(min_landmarks)
            if step is None:
                return PruneReport(budget_bytes, False, before, before, work.memory_bytes(), tuple(steps),
                                   np.arange(self.landmark_count), np.arange(self.viewframe_count))
            steps.append(step)
            index, viewframes = follow(index, step.landmark_index), follow(viewframes, step.viewframe_index)
        if steps:
            self._parent, self._leaves, self._rows, self._places = work._parent, work._leaves, work._rows, work._places
            self._cache.clear()
        after = self.memory_bytes()
        return PruneReport(budget_bytes, True, before, after, after, tuple(steps), index, viewframes)

    def copy(self) -> LandmarkTree:
        """An independent copy (its own arrays and cache)."""
        twin = LandmarkTree(self.kind, threshold=self.threshold, scale=self.scale)
        twin._parent, twin._leaves, twin._rows = list(self._parent), list(self._leaves), self._rows.copy()
        twin._places = None if self._places is None else list(self._places)
        return twin

    # ----- arrays (what a map file holds) -----------------------------------------------------

    def to_arrays(self) -> dict[str, np.ndarray]:
        """The map as plain arrays in canonical order (nodes in preorder, children in route order,
        landmarks grouped by node): ``descriptors`` (N x W) or ``ids`` (N,), ``bearings`` (N x 3
        float32), ``node_parent`` and ``node_size`` (M, int32; the root's parent is -1),
        ``viewframe_leaf`` (V, int32, route order) and, when the map has places,
        ``viewframe_place`` (V x 2 float32). Equal maps give equal arrays."""
        parent = np.array(self._parent, dtype=np.int64)
        order = preorder(parent, np.ones(len(parent), dtype=bool), self._leaves)
        renumber = np.full(len(parent), -1, dtype=np.int64)
        renumber[order] = np.arange(len(order))
        node = renumber[self._rows.node]
        grouped = np.argsort(node, kind="stable")
        places = {} if self._places is None else {PLACES: np.array(self._places, dtype=PLACE_DTYPE).reshape(-1, 2)}
        return {
            data_name(self.kind): self._rows.data[grouped],
            "bearings": np.ascontiguousarray(self._rows.bearings[grouped], dtype=BEARING_DTYPE),
            "node_parent": np.array([renumber[parent[n]] if parent[n] >= 0 else -1 for n in order],
                                    dtype=INDEX_DTYPE).reshape(-1),
            "node_size": np.bincount(node, minlength=len(order)).astype(INDEX_DTYPE),
            "viewframe_leaf": renumber[np.asarray(self._leaves, dtype=np.int64)].astype(INDEX_DTYPE).reshape(-1),
            **places,
        }

    @classmethod
    def from_arrays(cls, arrays: Mapping[str, np.ndarray], *, kind: str, threshold: float = DEFAULT_THRESHOLD,
                    scale: float = DEFAULT_SCALE) -> LandmarkTree:
        """The map :meth:`to_arrays` describes; ``ValueError`` naming the first inconsistency."""
        tree = cls(kind, threshold=threshold, scale=scale)
        checked = checked_arrays(arrays, kind)
        node = np.repeat(np.arange(len(checked.node_parent), dtype=np.int64), checked.node_size)
        tree._parent, tree._leaves = [int(p) for p in checked.node_parent], [int(v) for v in checked.viewframe_leaf]
        tree._rows = _Rows(node, checked.bearings, checked.data)
        if checked.viewframe_place is not None:
            tree._places = [(float(x), float(y)) for x, y in checked.viewframe_place]
        return tree

