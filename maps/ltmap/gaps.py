"""Gap filling and loop closing: landmarks found again are shifted to a common node (paper, section IV).

The paper couples the map and Z-infinity both ways. One way: the upper nodes give Z-infinity its
candidate far landmarks. The other, here: "the set of translation-invariant features returned by
Z-infinity can be used to find correspondences in the upper nodes of all viewframes. The
resulting matches allow to identify loop closures or viewframes where some far distant landmarks
could not be tracked and, thus, are missing. If such gaps are detected, they can be filled by
shifting the respective landmark to a common node in a higher level of the tree."
:meth:`maps.ltmap.tree.LandmarkTree.fill_gaps` does it for the newest viewframe, while teaching
(:class:`maps.ltmap.learner.RouteLearner`, ``LearnConfig.gap_filling``). How the paper is read:

- **Found again.** Every landmark of the new viewframe (its whole branch) is looked for among the
  rows of the whole map: equal ids for the ideal sensor, else the nearest other descriptor with
  the ratio test (:func:`perception.matching.match_within`). A copy whose route-frame bearing is
  within ``share_angle`` of the new one is the same landmark found again: translation-invariant
  between the two places, Z-infinity's test for a far landmark with the far threshold widened to
  the tree's unit of "the same bearing" (one stored bearing serves every viewframe within
  ``share_angle``, so a merged landmark keeps the tree's guarantee to within one more angle).
  The bearings are compared as stored, compensated by odometry's heading: Z-infinity's own
  rotation between the two sets was tried and is not used, because most correspondences of a
  viewframe's landmarks with the rest of the map are near landmarks stored again after they
  moved; on the synthetic corridor its far set gave rotations of 3 to 5 deg where the truth was
  0, and the gate then merged 1091 copies of moved landmarks (viewframes held bearings up to
  30 % wrong) instead of 171. Heading drift between two passes of a loop is not removed: a loop
  with more drift than ``share_angle`` is not found.
- **Common node.** Two copies of a landmark are one landmark in the lowest common ancestor of
  their nodes, the node that covers every viewframe that saw either: the older row moves there
  (its bearing stays), the newer row is deleted. The common node also covers the viewframes
  that saw neither, between the two sightings (the gap) and, depending on the tree's shape,
  before or after them.
- **When a shift is made.** Only when the common node fills a gap and nothing else: it covers
  no viewframe before the first sighting or after the last, and at most ``max_gap`` (2)
  viewframes between them saw neither copy (a landmark that dropped out of tracking for a few
  frames: a person walking past, a door). When the two copies are far apart in the tree the
  common node would give the landmark to a long stretch of route that never saw it, and both
  copies stay. Measured on the synthetic corridor with 5 % dropout (41 viewframes): this rule
  shifts 23 landmarks and the tree is 5 levels high (4 without gap filling). Letting the common
  node also cover up to ``max_gap`` viewframes beside the sightings shifted 171, but early in
  the route, when the root covers only a few viewframes, it put near landmarks into the root;
  lost later, they made every following branch start a new root, and the tree grew to 10
  levels, 6 of them empty. Shifting, whatever the stretch, every copy found again in upper
  nodes (each seen from two viewframes or more: "far") shifted 144, left a viewframe with 12 %
  landmarks invisible from its place (1.3 % with the rule above) and made the tree 15 levels
  high: "seen unmoved from two places" does not make a landmark visible from everywhere between.
- **Loops.** A landmark found again whose two copies were seen with more than ``max_gap``
  viewframes between them (seen, then not, then again) means the route came back past an
  earlier place. The earlier viewframe that holds most of them is the loop's other end; as many
  of them as homing needs make a loop (:class:`Loop`: the viewframe pair and the landmarks
  shared): ``min_loop``, the paper's 50, or half a small viewframe, never under Z-infinity's 8
  (:func:`perception.viewframe_motion.lost_threshold`, the rule route following loses a
  viewframe by). Z-infinity's 8 alone was tried: on the lab's tour, which never comes back,
  landmarks that ORB missed for 4 or 5 viewframes and found again made 1.2 "loops" per teach
  (8 to 11 landmarks each), while on the route back past the tour (``route=back`` of the
  evaluation) the true ones share 30 to 160. A route back past several places closes a loop at
  each of its viewframes; the teach report lists them all and counts consecutive ones as one
  closure. By the rule above they are not shifted: the common node of two
  passes of one place covers the whole way between, which never saw them. A loop is reported
  (the teach's ``ltmap.loops``), the map does not hold it, and route following does not use it.

Pure structure and matching: :func:`found_again` finds the pairs, :func:`plan_shifts` decides,
the tree applies (:class:`GapFill`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from maps.ltmap.arrays import IDS
from maps.ltmap.prune import DEFAULT_MIN_LANDMARKS
from perception.matching import match_within
from perception.similarity import bearing_angles
from perception.viewframe_motion import lost_threshold


@dataclass(frozen=True, slots=True)
class GapConfig:
    """``max_gap``: viewframes a shift may give a landmark they did not see; ``min_loop``: landmarks
    found again from one earlier place that make a loop (the paper's 50 for homing; a small
    viewframe needs half its landmarks: :func:`perception.viewframe_motion.lost_threshold`)."""

    max_gap: int = 2
    min_loop: int = DEFAULT_MIN_LANDMARKS

    def __post_init__(self) -> None:
        if self.max_gap < 0 or self.min_loop < 1:
            raise ValueError(f"max_gap must be >= 0 and min_loop >= 1, got {self.max_gap} and {self.min_loop}")


DEFAULT_GAPS = GapConfig()


@dataclass(frozen=True, slots=True)
class Loop:
    """The route came back past an earlier place: viewframe ``earlier`` and the new one, ``later``
    (route order at the time), and ``shared`` landmarks found again there (stored twice)."""

    earlier: int
    later: int
    shared: int


@dataclass(frozen=True, slots=True, eq=False)
class GapFill:
    """What :meth:`LandmarkTree.fill_gaps` did: ``found`` landmarks found again, ``shifted`` of them
    merged into a common node (one row deleted each), the ``loop`` detected (or None);
    ``landmark_index[i]``: the new index of old row ``i`` (a deleted copy: its kept twin's)."""

    found: int
    shifted: int
    loop: Loop | None
    landmark_index: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class ShiftPlan:
    """:func:`plan_shifts`' decision: per shift the row kept, the row deleted and the kept row's new node."""

    keep: np.ndarray
    drop: np.ndarray
    node: np.ndarray
    loop: Loop | None


def node_cover(parent: Sequence[int], leaves: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
    """Per node the first and last viewframe under it (-1: none). Viewframes under a node are
    consecutive (a new branch leaves the last one), so the range is what the node covers."""
    first = np.full(len(parent), -1, dtype=np.int64)
    last = np.full(len(parent), -1, dtype=np.int64)
    for k, leaf in enumerate(leaves):
        node = leaf
        while node >= 0:
            if first[node] < 0:
                first[node] = k
            last[node] = k
            node = parent[node]
    return first, last


def common_node(parent: Sequence[int], a: int, b: int) -> int:
    """The lowest common ancestor of nodes ``a`` and ``b`` (a node is its own ancestor)."""
    ancestors = set()
    while a >= 0:
        ancestors.add(a)
        a = parent[a]
    while b not in ancestors:
        b = parent[b]
    return b


def found_again(kind: str, data: np.ndarray, bearings: np.ndarray, candidates: np.ndarray, share_angle: float,
                *, ratio: float | None = None) -> np.ndarray:
    """Pairs of rows (P x 2, the lower index first) that are one landmark stored twice: a
    ``candidates`` row and another row of the same id or descriptor whose route-frame bearing is
    within ``share_angle`` (see the module doc)."""
    candidates = np.asarray(candidates, dtype=np.int64).reshape(-1)
    if kind == IDS:
        pairs = _same_ids(data, candidates)
    else:
        found = match_within(data, candidates, kind, ratio=ratio)
        pairs = np.column_stack((found.query, found.train))
    if not len(pairs):
        return np.zeros((0, 2), dtype=np.int64)
    ref = np.asarray(bearings[pairs[:, 1]], dtype=np.float64)
    cur = np.asarray(bearings[pairs[:, 0]], dtype=np.float64)
    same = pairs[bearing_angles(ref, cur) <= share_angle]
    return np.unique(np.sort(same, axis=1), axis=0)


def _same_ids(ids: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """Each candidate row with every other row of its id."""
    ids = np.asarray(ids)
    order = np.argsort(ids, kind="stable")
    start = np.searchsorted(ids[order], ids[candidates], side="left")
    stop = np.searchsorted(ids[order], ids[candidates], side="right")
    pairs = [(row, int(other)) for row, lo, hi in zip(candidates.tolist(), start.tolist(), stop.tolist(), strict=True)
             for other in order[lo:hi] if other != row]
    return np.array(pairs, dtype=np.int64).reshape(-1, 2)


def plan_shifts(parent: Sequence[int], leaves: Sequence[int], landmark_nodes: np.ndarray, pairs: np.ndarray,
                config: GapConfig, *, viewframe_size: int | None = None) -> ShiftPlan:
    """Which of ``pairs`` (rows stored twice, found by :func:`found_again` for the last viewframe,
    of ``viewframe_size`` landmarks) become one landmark in their common node, and the loop they
    show (see the module doc)."""
    first, last = node_cover(parent, leaves)
    later = len(leaves) - 1
    node = np.array(landmark_nodes, dtype=np.int64)
    kept: dict[int, int] = {}  # a deleted row -> the row it merged into

    def resolve(row: int) -> int:
        while row in kept:
            row = kept[row]
        return row

    shifts: list[tuple[int, int, int]] = []
    evidence: list[tuple[int, int]] = []  # the viewframes of the earlier copy of each landmark found again
    for a, b in np.asarray(pairs, dtype=np.int64).reshape(-1, 2).tolist():
        keep, drop = sorted((resolve(a), resolve(b)))
        if keep == drop:
            continue
        na, nb = int(node[keep]), int(node[drop])
        common = common_node(parent, na, nb)
        seen = _span(first[na], last[na]) + _span(first[nb], last[nb]) - _overlap(first, last, na, nb)
        unseen = _span(first[common], last[common]) - seen
        within = first[common] >= min(first[na], first[nb]) and last[common] <= max(last[na], last[nb])
        shift = within and unseen <= config.max_gap  # fill a gap, never extend the landmark's span
        earlier, newer = (na, nb) if last[na] < last[nb] else (nb, na)
        if last[newer] == later and first[newer] - last[earlier] - 1 > config.max_gap:  # seen, then not, now again
            evidence.append((int(first[earlier]), int(last[earlier])))
        if shift:
            node[keep], kept[drop] = common, keep
            shifts.append((keep, drop, common))
    rows = np.array(shifts, dtype=np.int64).reshape(-1, 3)
    min_loop = config.min_loop if viewframe_size is None else lost_threshold(viewframe_size, config.min_loop)
    return ShiftPlan(rows[:, 0], rows[:, 1], rows[:, 2], _loop(evidence, later, min_loop))


def _span(first: int, last: int) -> int:
    return int(last - first + 1) if first >= 0 else 0


def _overlap(first: np.ndarray, last: np.ndarray, a: int, b: int) -> int:
    return max(0, int(min(last[a], last[b]) - max(first[a], first[b]) + 1))


def _loop(evidence: list[tuple[int, int]], later: int, min_loop: int) -> Loop | None:
    """The earlier viewframe most of the landmarks found again from far back were seen from."""
    if len(evidence) < min_loop:
        return None
    ranges = np.array(evidence, dtype=np.int64).reshape(-1, 2)
    cover = (ranges[:, :1] <= np.arange(later)) & (np.arange(later) <= ranges[:, 1:])  # [pair, viewframe]
    counts = cover.sum(axis=0)
    earlier = int(len(counts) - 1 - np.argmax(counts[::-1]))  # ties: the latest
    if counts[earlier] < min_loop:
        return None
    return Loop(earlier, later, int(counts[earlier]))
