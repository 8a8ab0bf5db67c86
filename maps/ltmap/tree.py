"""The Landmark-Tree map (LT-map): viewframes as branches of one tree of landmarks.

Jäger, Mair et al., IROS 2013 (DESIGN.md, algorithm 1). A *landmark* is a descriptor (a binary
ORB row, or the id of the simulator's ideal bearings sensor) with a unit bearing compensated for
the robot's rotation. A *viewframe* is the set of landmarks seen from one place of a taught route:
the union of the nodes on a branch from the root to a leaf. Each landmark lives in exactly one
node, so a landmark seen from many places is stored once; far, persistent landmarks sit near the
root and short-lived local ones near the leaves. Pure: numpy arrays and dataclasses, no I/O
(``maps/ltmap_file.py`` saves and loads).

How the paper is read here (where it is vague, the choice and why):

- **Route frame.** Stored bearings are body-frame bearings rotated by the camera's heading in the
  route frame (odometry heading plus pan), given by the caller: "compensated for the robot's
  rotation". Route following estimates the remaining rotation with Z-infinity, so heading drift
  along the route costs nothing there; while teaching it adds to ``delta_t``.
- **Tracking.** A landmark of the last viewframe is *tracked* when the current observation
  matches it (ratio test and mutual check on descriptors, equal ids for the ideal sensor)
  against the viewframe's cached landmark stack. Features that match no viewframe landmark are
  candidates for the next viewframe; candidates not matched against the previous image are
  *volatile* and rejected.
- **New viewframe** when ``delta_t`` (eq. 1, :func:`perception.similarity.delta_t`: mean
  Pseudo-Huber cost of bearing changes) of the landmarks tracked since the last viewframe
  exceeds the threshold. The change is measured from the bearings they had when that viewframe
  was made (the learner keeps them), so ``delta_t`` starts at 0 at every viewframe. Nothing
  tracked is ``inf``: losing every landmark also makes a viewframe (but seeing nothing at all,
  say in the dark, makes no empty ones).
- **One bearing per landmark.** A landmark stored once and shared by several viewframes has one
  bearing, the one it was stored with. A tracked landmark is shared with the new viewframe only
  while its current bearing stays within ``share_angle`` of the stored one; by default the angle
  whose eq. 1 cost equals the threshold (about 3 deg), so that at a viewframe's own place
  ``delta_t`` stays under the threshold and route following can switch there. A landmark that
  moved further (a near landmark, after some travel) counts as lost for the tree, and its current
  sighting is stored again in the new leaf with its current bearing.
- **Levels.** Every leaf is at the same depth, the tree's *height*: a level is a time scale, the
  leaves hold what was seen from one place only, their parents what a run of neighbouring places
  shared, and so on up to the root, what the whole route saw. "Cut the lowest level" then drops
  the most local landmarks of the whole route at once, as the paper's memory table shows (a few
  heights between the full tree and a lost robot), not one viewframe at a time.
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
- **Pruning (``prune_level``).** The lowest level (every leaf) is cut: the first and the last
  viewframe (start and goal) shift their leaf's landmarks into the parent, every other leaf's
  landmarks are deleted; viewframes that now end in the same node are one viewframe (the
  earliest keeps its place in the route). Viewframes left with fewer than ``min_landmarks`` (50,
  the paper's minimum for homing) are deleted, except the first and the last (the route must
  keep its start and goal), and with them every node no viewframe passes through; viewframes
  whose landmark sets became identical (they differ only by empty nodes) are merged; a root with
  a single child is merged into it, which lowers the height again (the tree is compressed).
  ``prune_to(budget)`` cuts levels until the map fits, or reports that it cannot and leaves the
  map as it was. Surviving landmarks keep their order; a prune reports the new index of every
  old landmark, so callers holding landmark indices (the learner) can follow.
- **Memory** (``memory_bytes``) is exactly what :meth:`LandmarkTree.to_arrays` holds, i.e. what a
  saved map stores besides its header: per landmark its descriptor row (32 bytes for ORB) or id
  (8 bytes) and its unit bearing (3 x float32, 12 bytes); per node its parent and its landmark
  count (2 x int32); per viewframe its leaf (int32). Landmarks are stored grouped by node, so a
  landmark's node costs nothing. Caches and the learner's bookkeeping are not map content.
- **Matching cache.** Each viewframe's landmark stack (descriptors or ids, bearings, map indices)
  is built once and kept until the map changes; a change (a new viewframe, pruning) clears every
  entry. With ids, a branch holding one id twice (a landmark stored again after its bearing
  moved) keeps the deepest, most local copy. With descriptors both copies stay, and the ratio
  test discards the pair: an ambiguous landmark is better unused than matched to a stale bearing.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from perception.matching import LandmarkMatches, Landmarks, match_features, match_landmarks
from perception.observation import Observation
from perception.similarity import DEFAULT_SCALE, bearing_angles, delta_t

IDS = "ids"  # the kind of a map built from the ideal bearings sensor (landmark ids, no descriptors)
DESCRIPTOR_KINDS = {"orb": (32, np.uint8), "brisk": (64, np.uint8), "sift": (128, np.float32)}
DEFAULT_MIN_LANDMARKS = 50  # the paper's minimum for homing: smaller viewframes are pruned away
# eq. 1 threshold (rad^2; mean Pseudo-Huber cost, delta 2 deg): about 3 deg of mean bearing change
DEFAULT_THRESHOLD = 1.0e-3
NO_GATE = float("inf")  # share every tracked landmark, whatever its bearing now
BEARING_DTYPE = np.float32
INDEX_DTYPE = np.int32
ID_DTYPE = np.int64
NODE_BYTES = 2 * np.dtype(INDEX_DTYPE).itemsize  # parent + landmark count
VIEWFRAME_BYTES = np.dtype(INDEX_DTYPE).itemsize  # the viewframe's leaf
STRUCTURE_ARRAYS = ("bearings", "node_parent", "node_size", "viewframe_leaf")


def compensate(bearings: np.ndarray, heading: float) -> np.ndarray:
    """Body-frame unit bearings (N x 3) seen with the camera at ``heading`` (rad, counter-clockwise
    about z), in the route frame: what "compensated for the robot's rotation" means here."""
    return Rotation.from_euler("z", heading).apply(np.asarray(bearings, dtype=np.float64).reshape(-1, 3))


def _unit(vectors: np.ndarray) -> np.ndarray:
    v = np.asarray(vectors, dtype=np.float64)
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-30)


def _readonly(array: np.ndarray) -> np.ndarray:
    view = array.view()
    view.flags.writeable = False
    return view


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


@dataclass(frozen=True, slots=True, eq=False)
class Viewframe:
    """The landmarks of one viewframe stacked for matching (built once, kept until the map changes).

    ``landmarks`` are map indices; ``bearings`` unit (K x 3, route frame, float64); ``descriptors``
    (K x W) or ``ids`` (K,, sorted); ``matchable``: the descriptor set :func:`match_landmarks` takes.
    """

    index: int
    landmarks: np.ndarray
    bearings: np.ndarray
    descriptors: np.ndarray | None
    ids: np.ndarray | None
    matchable: Landmarks | None

    def __len__(self) -> int:
        return len(self.landmarks)


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


@dataclass(frozen=True, slots=True, eq=False)
class PruneStep:
    """One level cut by :meth:`LandmarkTree.prune_level`; ``landmark_index[i]`` is the new index of
    old landmark ``i`` (-1: deleted), ``viewframe_index[v]`` the new index of old viewframe ``v``
    (merged ones: the viewframe they merged into; -1: deleted)."""

    height_before: int
    height_after: int
    bytes_before: int
    bytes_after: int
    landmarks_removed: int
    viewframes_merged: int
    viewframes_deleted: int
    landmark_index: np.ndarray
    viewframe_index: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class PruneReport:
    """What :meth:`LandmarkTree.prune_to` did. ``fits`` False: even height 0 exceeds the budget and
    the map was left unchanged (``smallest_bytes`` is what it would have reached)."""

    budget_bytes: int
    fits: bool
    bytes_before: int
    bytes_after: int
    smallest_bytes: int
    steps: tuple[PruneStep, ...]
    landmark_index: np.ndarray
    viewframe_index: np.ndarray

    @property
    def levels_cut(self) -> int:
        return len(self.steps) if self.fits else 0


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

    Viewframes are numbered in route order (0: start, last: goal). Built by :class:`RouteLearner`
    (or :meth:`add_viewframe`), shrunk by :meth:`prune_level` / :meth:`prune_to`, matched against
    observations by :meth:`match` (the hot path of route following, cached per viewframe).
    """

    def __init__(self, kind: str, *, threshold: float = DEFAULT_THRESHOLD) -> None:
        if kind != IDS and kind not in DESCRIPTOR_KINDS:
            raise ValueError(f"unknown landmark kind {kind!r} (expected {IDS} or one of {', '.join(DESCRIPTOR_KINDS)})")
        if not (np.isfinite(threshold) and threshold > 0):
            raise ValueError(f"threshold must be a positive number, got {threshold}")
        self.kind = kind
        self.threshold = float(threshold)
        self._parent: list[int] = []
        self._leaves: list[int] = []
        self._rows = _empty_rows(kind)
        self._cache: dict[int, Viewframe] = {}

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
        """Bytes of the map's content: exactly the ``nbytes`` of :meth:`to_arrays` (see the module doc)."""
        data = self._rows.data
        row = 3 * np.dtype(BEARING_DTYPE).itemsize + int(np.prod(data.shape[1:], dtype=np.int64)) * data.itemsize
        return self.landmark_count * row + self.node_count * NODE_BYTES + self.viewframe_count * VIEWFRAME_BYTES

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
        return _readonly(self._rows.bearings)

    @property
    def descriptors(self) -> np.ndarray | None:
        return None if self.kind == IDS else _readonly(self._rows.data)

    @property
    def ids(self) -> np.ndarray | None:
        return _readonly(self._rows.data) if self.kind == IDS else None

    @property
    def landmark_nodes(self) -> np.ndarray:
        """The node each landmark lives in."""
        return _readonly(self._rows.node)

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

    def viewframe(self, index: int, *, cached: bool = True) -> Viewframe:
        """The landmarks of viewframe ``index`` (negative: from the goal), stacked for matching."""
        index = range(self.viewframe_count)[index]
        if not cached:
            return self._build_viewframe(index)
        found = self._cache.get(index)
        if found is None:
            found = self._cache[index] = self._build_viewframe(index)
        return found

    def match(self, index: int, observation: Observation, *, bearings: np.ndarray | None = None,
              ratio: float | None = None, cached: bool = True) -> LandmarkMatches:
        """Match an observation against viewframe ``index``: ``ref`` the viewframe's bearings, ``cur``
        the observation's (``bearings`` replaces them, e.g. compensated), ``landmark`` indexes the
        viewframe (``viewframe(index).landmarks[m.landmark]`` are map indices). ``cached=False``
        builds the viewframe's stack again (only to measure what the cache saves)."""
        found = self.viewframe(index, cached=cached)
        cur = np.asarray(observation.bearings if bearings is None else bearings, dtype=np.float64).reshape(-1, 3)
        if found.ids is not None:
            if observation.ids is None:
                raise ValueError("this map holds landmark ids; the observation has descriptors")
            return _match_ids(np.asarray(observation.ids), found.ids, cur, found.bearings)
        if observation.features is None or found.matchable is None:
            raise ValueError(f"this map holds {self.kind} descriptors; the observation has landmark ids")
        return match_landmarks(observation.features, cur, found.matchable, ratio=ratio)

    def _build_viewframe(self, index: int) -> Viewframe:
        landmarks = np.flatnonzero(np.isin(self._rows.node, self.branch_nodes(index)))
        if self.kind == IDS:  # one row per id: the deepest (most local) copy, sorted by id
            depth = self.depths()[self._rows.node[landmarks]]
            order = np.lexsort((-depth, self._rows.data[landmarks]))
            _, first = np.unique(self._rows.data[landmarks[order]], return_index=True)
            landmarks = landmarks[order[first]]
        bearings = _readonly(self._rows.bearings[landmarks].astype(np.float64))
        data = _readonly(np.ascontiguousarray(self._rows.data[landmarks]))
        if self.kind == IDS:
            return Viewframe(index, _readonly(landmarks), bearings, None, data, None)
        return Viewframe(index, _readonly(landmarks), bearings, data, None, Landmarks(data, bearings, self.kind))

    # ----- learning ---------------------------------------------------------------------------

    def add_viewframe(self, tracked: np.ndarray, sightings: LandmarkSet, new: LandmarkSet, *,
                      share_angle: float = NO_GATE) -> int:
        """Append a viewframe at the end of the route (algorithm 1, see the module doc); its index.

        ``tracked``: map indices of the last viewframe's landmarks seen now, ``sightings`` how
        (one row each: current route-frame bearing and descriptor or id); ``new``: the landmarks
        seen since the last viewframe. A tracked landmark is shared when its sighting is within
        ``share_angle`` (rad) of its stored bearing and it can move up without joining viewframes
        that never saw it; otherwise its sighting is stored in the new leaf. The new leaf's rows
        are appended: map indices from the old ``landmark_count`` on, stored sightings first.
        """
        tracked = np.asarray(tracked, dtype=np.int64).ravel()
        for rows in (sightings, new):
            self._check_rows(rows)
        if len(sightings) != len(tracked) or len(np.unique(tracked)) != len(tracked):
            raise ValueError("tracked landmarks must be distinct, with one sighting each")
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
        self._cache.clear()
        return len(self._leaves) - 1

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
        """Cut the lowest level (see the module doc); None when there is one level only."""
        if min_landmarks < 0:
            raise ValueError(f"min_landmarks must be >= 0, got {min_landmarks}")
        if self.height == 0:
            return None
        before = (self.height, self.memory_bytes(), self.landmark_count)
        parent = np.array(self._parent, dtype=np.int64)
        node = self._rows.node.copy()
        for terminal in {self._leaves[0], self._leaves[-1]}:  # start and goal keep their landmarks
            node[node == terminal] = parent[terminal]
        keep = ~np.isin(node, self._leaves)
        old_ends = [int(parent[leaf]) for leaf in self._leaves]
        ends = list(dict.fromkeys(old_ends))  # same end: one viewframe
        merged = len(self._leaves) - len(ends)
        counts = np.bincount(node[keep], minlength=len(parent))
        sizes = _branch_sizes(parent, counts, ends)
        weak = {k for k in range(1, len(ends) - 1) if sizes[k] < min_landmarks}
        candidates = [e for k, e in enumerate(ends) if k not in weak]
        ends, identical = _merge_identical(parent, counts, candidates)
        viewframes = _viewframe_index(parent, counts, old_ends, candidates, ends)
        index = self._restructure(parent, node, keep, ends)
        return PruneStep(before[0], self.height, before[1], self.memory_bytes(), before[2] - self.landmark_count,
                         merged + identical, len(weak), index, viewframes)

    def prune_to(self, budget_bytes: int, min_landmarks: int = DEFAULT_MIN_LANDMARKS) -> PruneReport:
        """Cut levels until :meth:`memory_bytes` <= ``budget_bytes``; the map is unchanged when it cannot."""
        if budget_bytes < 0:
            raise ValueError(f"budget must be >= 0 bytes, got {budget_bytes}")
        before = self.memory_bytes()
        work, steps = self.copy(), list[PruneStep]()
        index, viewframes = np.arange(self.landmark_count), np.arange(self.viewframe_count)
        while work.memory_bytes() > budget_bytes:
            step = work.prune_level(min_landmarks)
            if step is None:
                return PruneReport(budget_bytes, False, before, before, work.memory_bytes(), tuple(steps),
                                   np.arange(self.landmark_count), np.arange(self.viewframe_count))
            steps.append(step)
            index = np.where(index >= 0, step.landmark_index[np.maximum(index, 0)], -1)
            viewframes = np.where(viewframes >= 0, step.viewframe_index[np.maximum(viewframes, 0)], -1)
        if steps:
            self._parent, self._leaves, self._rows = work._parent, work._leaves, work._rows
            self._cache.clear()
        after = self.memory_bytes()
        return PruneReport(budget_bytes, True, before, after, after, tuple(steps), index, viewframes)

    def _restructure(self, parent: np.ndarray, node: np.ndarray, keep: np.ndarray, ends: list[int]) -> np.ndarray:
        """Keep the nodes some viewframe passes through, merge a single-child root, renumber the
        nodes canonically; landmarks keep their order. Returns the new index of each old landmark."""
        alive = np.zeros(len(parent), dtype=bool)
        for end in ends:
            n = end
            while n >= 0 and not alive[n]:
                alive[n] = True
                n = parent[n]
        keep = keep & alive[node]
        root = int(np.flatnonzero(alive & (parent < 0))[0])
        while np.count_nonzero(alive & (parent == root)) == 1:  # a root with one child merges into it
            child = int(np.flatnonzero(alive & (parent == root))[0])
            node = np.where(node == root, child, node)
            alive[root], parent[child], root = False, -1, child
        order = _preorder(parent, alive, ends)
        renumber = np.full(len(parent), -1, dtype=np.int64)
        renumber[order] = np.arange(len(order))
        self._parent = [int(renumber[parent[n]]) if parent[n] >= 0 else -1 for n in order]
        self._leaves = [int(renumber[e]) for e in ends]
        self._rows = self._rows.take(keep)
        self._rows.node = renumber[node[keep]]
        self._cache.clear()
        return np.where(keep, np.cumsum(keep) - 1, -1)

    def copy(self) -> LandmarkTree:
        """An independent copy (its own arrays and cache)."""
        twin = LandmarkTree(self.kind, threshold=self.threshold)
        twin._parent, twin._leaves, twin._rows = list(self._parent), list(self._leaves), self._rows.copy()
        return twin

    # ----- arrays (what a map file holds) -----------------------------------------------------

    def to_arrays(self) -> dict[str, np.ndarray]:
        """The map as plain arrays in canonical order (nodes in preorder, children in route order,
        landmarks grouped by node): ``descriptors`` (N x W) or ``ids`` (N,), ``bearings`` (N x 3
        float32), ``node_parent`` and ``node_size`` (M, int32; the root's parent is -1),
        ``viewframe_leaf`` (V, int32, route order). Equal maps give equal arrays."""
        parent = np.array(self._parent, dtype=np.int64)
        order = _preorder(parent, np.ones(len(parent), dtype=bool), self._leaves)
        renumber = np.full(len(parent), -1, dtype=np.int64)
        renumber[order] = np.arange(len(order))
        node = renumber[self._rows.node]
        grouped = np.argsort(node, kind="stable")
        return {
            (IDS if self.kind == IDS else "descriptors"): self._rows.data[grouped],
            "bearings": np.ascontiguousarray(self._rows.bearings[grouped], dtype=BEARING_DTYPE),
            "node_parent": np.array([renumber[parent[n]] if parent[n] >= 0 else -1 for n in order],
                                    dtype=INDEX_DTYPE).reshape(-1),
            "node_size": np.bincount(node, minlength=len(order)).astype(INDEX_DTYPE),
            "viewframe_leaf": renumber[np.asarray(self._leaves, dtype=np.int64)].astype(INDEX_DTYPE).reshape(-1),
        }

    @classmethod
    def from_arrays(cls, arrays: Mapping[str, np.ndarray], *, kind: str, threshold: float = DEFAULT_THRESHOLD
                    ) -> LandmarkTree:
        """The map :meth:`to_arrays` describes; ``ValueError`` naming the first inconsistency."""
        tree = cls(kind, threshold=threshold)
        data_name = IDS if kind == IDS else "descriptors"
        unknown = sorted(set(arrays) - {data_name, *STRUCTURE_ARRAYS})
        if unknown:
            raise ValueError(f"unexpected arrays for a {kind} map: {', '.join(unknown)}")
        data = _checked_data(arrays, kind)
        bearings = _checked_bearings(arrays, len(data))
        parent, size, leaves = _checked_structure(arrays, len(data))
        node = np.repeat(np.arange(len(parent), dtype=np.int64), size)
        tree._parent, tree._leaves = [int(p) for p in parent], [int(v) for v in leaves]
        tree._rows = _Rows(node, bearings, data)
        return tree


def _empty_rows(kind: str) -> _Rows:
    node = np.zeros(0, dtype=np.int64)
    bearings = np.zeros((0, 3), dtype=BEARING_DTYPE)
    if kind == IDS:
        return _Rows(node, bearings, np.zeros(0, dtype=ID_DTYPE))
    width, dtype = DESCRIPTOR_KINDS[kind]
    return _Rows(node, bearings, np.zeros((0, width), dtype=dtype))


def _match_ids(ids: np.ndarray, stored: np.ndarray, cur: np.ndarray, ref: np.ndarray) -> LandmarkMatches:
    """Correspondences by equal ids (the ideal sensor): observed ``ids`` with bearings ``cur``
    against ``stored`` ids with bearings ``ref``."""
    _, feature, landmark = np.intersect1d(ids, stored, return_indices=True)
    feature, landmark = feature.astype(np.int64), landmark.astype(np.int64)
    return LandmarkMatches(ref=ref[landmark], cur=cur[feature], feature=feature, landmark=landmark,
                           distance=np.zeros(len(feature)))


def _branch_sizes(parent: np.ndarray, counts: np.ndarray, ends: Sequence[int]) -> list[int]:
    sizes = []
    for end in ends:
        total, n = 0, end
        while n >= 0:
            total += int(counts[n])
            n = parent[n]
        sizes.append(total)
    return sizes


def _merge_identical(parent: np.ndarray, counts: np.ndarray, ends: Sequence[int]) -> tuple[list[int], int]:
    """Keep the first of viewframes whose non-empty nodes are the same (their landmark sets are equal)."""
    kept: dict[tuple[int, ...], int] = {}
    for end in ends:
        kept.setdefault(_signature(parent, counts, end), end)
    return list(kept.values()), len(ends) - len(kept)


def _signature(parent: np.ndarray, counts: np.ndarray, end: int) -> tuple[int, ...]:
    """The non-empty nodes of the branch ending in ``end`` (equal signatures: equal landmark sets)."""
    signature, n = [], end
    while n >= 0:
        if counts[n]:
            signature.append(int(n))
        n = parent[n]
    return tuple(signature)


def _viewframe_index(parent: np.ndarray, counts: np.ndarray, old_ends: Sequence[int], candidates: Sequence[int],
                     ends: Sequence[int]) -> np.ndarray:
    """Per old viewframe (its branch now ending in ``old_ends[v]``), the index among the kept ``ends``
    of the viewframe it became (the one with its landmark set), or -1 when it was deleted (its end
    is not among the ``candidates`` that survived the landmark minimum)."""
    kept = {_signature(parent, counts, end): k for k, end in enumerate(ends)}
    survivors = set(candidates)
    return np.array([kept[_signature(parent, counts, end)] if end in survivors else -1 for end in old_ends],
                    dtype=np.int64).reshape(-1)


def _preorder(parent: np.ndarray, alive: np.ndarray, ends: Sequence[int]) -> list[int]:
    """The alive nodes in preorder, children ordered by the first viewframe below them."""
    first = np.full(len(parent), len(ends), dtype=np.int64)
    for k in range(len(ends) - 1, -1, -1):
        n = ends[k]
        while n >= 0:
            first[n] = k
            n = parent[n]
    children: dict[int, list[int]] = {}
    roots: list[int] = []
    for n in np.flatnonzero(alive).tolist():
        (roots if parent[n] < 0 else children.setdefault(int(parent[n]), [])).append(n)
    order: list[int] = []
    stack = sorted(roots, key=lambda n: -int(first[n]))
    while stack:
        node = stack.pop()
        order.append(node)
        stack.extend(sorted(children.get(node, ()), key=lambda c: -int(first[c])))
    return order


def _checked_data(arrays: Mapping[str, np.ndarray], kind: str) -> np.ndarray:
    if kind == IDS:
        ids = _required(arrays, IDS)
        if ids.ndim != 1 or ids.dtype != ID_DTYPE:
            raise ValueError(f"ids must be a 1-d int64 array, got {ids.dtype} {ids.shape}")
        return ids.copy()
    descriptors = _required(arrays, "descriptors")
    width, dtype = DESCRIPTOR_KINDS[kind]
    if descriptors.ndim != 2 or descriptors.shape[1] != width or descriptors.dtype != dtype:
        raise ValueError(f"{kind} descriptors must be N x {width} {np.dtype(dtype)}, got {descriptors.dtype} "
                         f"{descriptors.shape}")
    return np.ascontiguousarray(descriptors).copy()


def _checked_bearings(arrays: Mapping[str, np.ndarray], count: int) -> np.ndarray:
    bearings = _required(arrays, "bearings")
    if bearings.shape != (count, 3) or bearings.dtype != BEARING_DTYPE:
        raise ValueError(f"bearings must be {count} x 3 float32 (one per landmark), got {bearings.dtype} "
                         f"{bearings.shape}")
    if not np.all(np.isfinite(bearings)) or np.any(np.abs(np.linalg.norm(bearings, axis=1) - 1.0) > 1e-3):
        raise ValueError("bearings must be finite unit vectors")
    return bearings.copy()


def _checked_structure(arrays: Mapping[str, np.ndarray], count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    parent, size, leaves = (_required(arrays, name) for name in ("node_parent", "node_size", "viewframe_leaf"))
    for name, array in (("node_parent", parent), ("node_size", size), ("viewframe_leaf", leaves)):
        if array.ndim != 1 or array.dtype != INDEX_DTYPE:
            raise ValueError(f"{name} must be a 1-d int32 array, got {array.dtype} {array.shape}")
    if len(size) != len(parent) or np.any(size < 0) or int(size.sum(dtype=np.int64)) != count:
        raise ValueError("node_size must give each node's landmark count (one per node, summing to the landmarks)")
    if len(parent) == 0:
        if len(leaves):
            raise ValueError("viewframes need nodes")
        return parent, size, leaves
    if parent[0] != -1 or np.any(parent[1:] < 0) or np.any(parent[1:] >= np.arange(1, len(parent))):
        raise ValueError("node_parent must list the root first and every parent before its children")
    _check_leaves(parent, leaves)
    return parent, size, leaves


def _check_leaves(parent: np.ndarray, leaves: np.ndarray) -> None:
    has_child = np.zeros(len(parent), dtype=bool)
    has_child[parent[1:]] = True
    actual = np.flatnonzero(~has_child)
    if len(np.unique(leaves)) != len(leaves) or not np.array_equal(np.sort(leaves), actual):
        raise ValueError("viewframe_leaf must name every leaf node once")
    depth = np.zeros(len(parent), dtype=np.int64)
    for n in range(1, len(parent)):
        depth[n] = depth[parent[n]] + 1
    if len(np.unique(depth[actual])) > 1:
        raise ValueError("every leaf must be at the same depth")


def _required(arrays: Mapping[str, np.ndarray], name: str) -> np.ndarray:
    if name not in arrays:
        raise ValueError(f"the array {name!r} is missing")
    return np.asarray(arrays[name])


# ----- teaching a route -----------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class LearnConfig:
    """How a route is taught: the eq. 1 ``threshold`` (rad^2) and Pseudo-Huber ``scale`` (rad), the
    ``share_angle`` (rad) within which a tracked landmark keeps its stored bearing and is shared
    (None: the angle whose eq. 1 cost is the threshold), the matching ``ratio`` (None: the kind's
    default), an optional memory budget (bytes, pruned online) and the smallest viewframe
    pruning keeps."""

    threshold: float = DEFAULT_THRESHOLD
    scale: float = DEFAULT_SCALE
    share_angle: float | None = None
    ratio: float | None = None
    budget_bytes: int | None = None
    min_landmarks: int = DEFAULT_MIN_LANDMARKS

    def __post_init__(self) -> None:
        for name in ("threshold", "scale", "share_angle"):
            value = getattr(self, name)
            if value is not None and not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value}")
        if self.budget_bytes is not None and self.budget_bytes <= 0:
            raise ValueError(f"budget_bytes must be positive, got {self.budget_bytes}")
        if self.min_landmarks < 0:
            raise ValueError(f"min_landmarks must be >= 0, got {self.min_landmarks}")


def threshold_angle(threshold: float, scale: float = DEFAULT_SCALE) -> float:
    """The bearing change (rad) whose eq. 1 cost is ``threshold``: the inverse of the Pseudo-Huber cost."""
    return float(scale * np.sqrt((1.0 + threshold / scale**2) ** 2 - 1.0))


@dataclass(frozen=True, slots=True)
class LearnStep:
    """What one observation did to the map while teaching.

    ``viewframe``: index of the last viewframe (-1 before the first); ``created``: this observation
    made it; ``delta_t``: eq. 1 since the previous viewframe (``inf`` when nothing was tracked or
    there was none); ``tracked``: landmarks of the previous viewframe seen now; ``stored``:
    landmarks stored in the new leaf (new ones and sightings not shared); ``volatile``: features
    rejected because the previous image lacked them; ``pruned``: the online pruning this step
    ran (a budget is set and was exceeded).
    """

    viewframe: int
    created: bool
    delta_t: float
    tracked: int
    stored: int = 0
    volatile: int = 0
    pruned: PruneReport | None = None

    @property
    def over_budget(self) -> bool:
        """Online pruning could not bring the map under the budget."""
        return self.pruned is not None and not self.pruned.fits


@dataclass(frozen=True, slots=True)
class _Seen:
    observation: Observation
    bearings: np.ndarray  # route frame


@dataclass(frozen=True, slots=True)
class _Tracked:
    """An observation matched against the last viewframe: map indices and current bearings."""

    matches: LandmarkMatches
    landmarks: np.ndarray


@dataclass
class _Anchor:
    """The landmarks seen when the last viewframe was made, with their bearings then (eq. 1's reference)."""

    landmarks: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    bearings: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))


class RouteLearner:
    """Teaches an LT-map: feed it every new observation with the camera heading (algorithm 1).

    ``observe`` matches the observation against the last viewframe (cached), computes ``delta_t``
    (eq. 1) of the landmarks tracked since that viewframe and, past the threshold, appends a
    viewframe; ``finish`` makes the last place (the goal) a viewframe. With
    ``config.budget_bytes`` the map is pruned online whenever it outgrows the budget, so the
    route length need not be known in advance. ``tree`` is None until the first observation,
    whose kind (descriptors or ids) the map takes.
    """

    def __init__(self, config: LearnConfig | None = None) -> None:
        self.config = config or LearnConfig()
        self.tree: LandmarkTree | None = None
        self._latest: _Seen | None = None
        self._before: _Seen | None = None
        self._at_viewframe = False
        self._anchor = _Anchor()
        angle = self.config.share_angle
        self.share_angle = threshold_angle(self.config.threshold, self.config.scale) if angle is None else angle

    def observe(self, observation: Observation, heading: float) -> LearnStep:
        """One new observation, seen with the camera at ``heading`` (rad) in the route frame."""
        if self.tree is None:
            self.tree = LandmarkTree(_kind_of(observation), threshold=self.config.threshold)
        tree, seen = self.tree, _Seen(observation, compensate(observation.bearings, heading))
        self._before, self._latest = self._latest, seen
        if tree.viewframe_count == 0:
            self._at_viewframe = self._before is not None  # the first viewframe needs a previous image
            if not self._at_viewframe:
                return LearnStep(-1, False, np.inf, 0)
            return self._make_viewframe(tree, seen, np.inf, 0)
        tracked = self._track(tree, seen)
        change, count = self._change(tracked)
        self._at_viewframe = change > self.config.threshold
        if self._at_viewframe:
            return self._make_viewframe(tree, seen, change, count, tracked)
        return LearnStep(tree.viewframe_count - 1, False, change, count)

    def finish(self) -> LearnStep:
        """Make the latest observation's place the last viewframe (the goal), unless it already is."""
        tree, seen = self.tree, self._latest
        if seen is None or tree is None:
            raise ValueError("nothing was observed: there is no route to finish")
        if self._at_viewframe:
            return LearnStep(tree.viewframe_count - 1, False, 0.0, 0)
        self._at_viewframe = True
        if tree.viewframe_count == 0:
            return self._make_viewframe(tree, seen, np.inf, 0)
        tracked = self._track(tree, seen)
        return self._make_viewframe(tree, seen, *self._change(tracked), tracked)

    def _track(self, tree: LandmarkTree, seen: _Seen) -> _Tracked:
        matches = tree.match(-1, seen.observation, bearings=seen.bearings, ratio=self.config.ratio)
        return _Tracked(matches, tree.viewframe(-1).landmarks[matches.landmark])

    def _change(self, tracked: _Tracked) -> tuple[float, int]:
        """Eq. 1 over the landmarks tracked since the last viewframe, from their bearings then."""
        _, then, now = np.intersect1d(self._anchor.landmarks, tracked.landmarks, return_indices=True)
        change = delta_t(self._anchor.bearings[then], tracked.matches.cur[now], scale=self.config.scale)  # eq. 1
        return change, len(then)

    def _make_viewframe(self, tree: LandmarkTree, seen: _Seen, change: float, count: int,
                        tracked: _Tracked | None = None) -> LearnStep:
        stable = self._stable(seen)
        landmarks, features = np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        if tracked is not None:
            landmarks, features = tracked.landmarks, tracked.matches.feature
        new = np.setdiff1d(stable, features)
        volatile = seen.observation.count - len(stable)
        if len(new) == 0 and len(landmarks) == 0:  # nothing seen (a blind spell): no empty viewframes
            self._at_viewframe = False
            return LearnStep(tree.viewframe_count - 1, False, float(change), count, volatile=volatile)
        before = tree.landmark_count
        sightings = LandmarkSet.from_observation(seen.observation, seen.bearings, features)
        tree.add_viewframe(landmarks, sightings, LandmarkSet.from_observation(seen.observation, seen.bearings, new),
                           share_angle=self.share_angle)
        stored = np.arange(before, tree.landmark_count)
        self._anchor = _Anchor(np.concatenate((landmarks, stored)),
                               np.vstack((sightings.bearings, tree.bearings[stored])))
        pruned = self._prune_online(tree)
        return LearnStep(tree.viewframe_count - 1, True, float(change), count, len(stored), volatile, pruned)

    def _prune_online(self, tree: LandmarkTree) -> PruneReport | None:
        budget = self.config.budget_bytes
        if budget is None or tree.memory_bytes() <= budget:
            return None
        report = tree.prune_to(budget, self.config.min_landmarks)
        index = report.landmark_index[self._anchor.landmarks]
        self._anchor = _Anchor(index[index >= 0], self._anchor.bearings[index >= 0])
        return report

    def _stable(self, seen: _Seen) -> np.ndarray:
        """Indices of the observation's landmarks also seen in the previous image (not volatile)."""
        cur = seen.observation
        if self._before is None:
            return np.arange(cur.count)
        previous = self._before.observation
        if cur.ids is not None and previous.ids is not None:
            return np.sort(np.intersect1d(cur.ids, previous.ids, return_indices=True)[1]).astype(np.int64)
        if cur.features is not None and previous.features is not None:
            return np.sort(match_features(cur.features, previous.features, ratio=self.config.ratio).query)
        raise ValueError("observations mix landmark ids and descriptors")


def _kind_of(observation: Observation) -> str:
    if observation.ids is not None:
        return IDS
    if observation.features is None:
        raise ValueError("the observation has neither descriptors nor ids")
    return observation.features.kind
