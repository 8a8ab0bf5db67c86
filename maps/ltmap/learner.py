"""Teaching an LT-map: :class:`RouteLearner` turns the observations of a driven route into a tree.

Jäger, Mair et al., IROS 2013 (docs/design.md, method 1). Feed the learner every new observation
with the camera's heading; it decides where viewframes are and hands the tree
(:class:`maps.ltmap.tree.LandmarkTree`) what each one saw. How the paper is read here:

- **Route frame.** Stored bearings are body-frame bearings rotated by the camera's heading in the
  route frame (odometry heading plus pan), given by the caller: "compensated for the robot's
  rotation" (:func:`compensate`). Route following estimates the remaining rotation with
  Z-infinity, so heading drift along the route costs nothing there; while teaching it adds to
  ``delta_t``.
- **Tracking.** A landmark of the last viewframe is *tracked* when the current observation
  matches it (ratio test and mutual check on descriptors, equal ids for the ideal sensor)
  against the viewframe's cached landmark stack. Features that match no viewframe landmark are
  candidates for the next viewframe; candidates not matched against the previous image are
  *volatile* and rejected.
- **New viewframe** when ``delta_t`` (eq. 1 as written, :func:`perception.similarity.delta_t`:
  the mean Pseudo-Huber cost of ``1 - l^T l'``) of the landmarks tracked since the last viewframe
  exceeds the threshold (by default the cost of a 3 deg bearing change). It is measured as route
  following measures it (:func:`perception.viewframe_motion.change_since`): over Z-infinity's
  inliers between the bearings then and now, its rotation removed. Eq. 1 weighs a mismatched
  landmark up to 2000 times a 3 deg change, and with descriptors a single mismatch among
  hundreds of tracked landmarks made almost every viewframe outdoors; the inliers leave it out.
  Fewer tracked landmarks than Z-infinity needs: eq. 1 over all of them. The change is measured
  from the bearings they had when that viewframe was made (the learner keeps them), so
  ``delta_t`` starts at 0 at every viewframe. Nothing
  tracked is ``inf``: losing every landmark also makes a viewframe (but seeing nothing at all,
  say in the dark, makes no empty ones).
- **Share angle.** A tracked landmark is shared with the new viewframe only while its current
  bearing stays within ``share_angle`` of the stored one; by default the angle whose eq. 1 cost
  equals the threshold (:func:`threshold_angle`, 3 deg by default), so that at a viewframe's own
  place ``delta_t`` stays under the threshold and route following can switch there.
- **Gap filling** (``gap_filling``, on by default): after each new viewframe its landmarks are
  looked for among the map's other rows; one found again within ``share_angle`` is shifted to
  the common node of its two copies, and a route back past an earlier place is reported as a
  loop (:mod:`maps.ltmap.gaps` says how the paper is read there).
- **Online pruning.** With a memory budget the map is pruned whenever it outgrows it
  (:mod:`maps.ltmap.prune`), so the route's length need not be known in advance.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from maps.ltmap.arrays import IDS
from maps.ltmap.gaps import DEFAULT_GAPS, GapConfig, GapFill, Loop
from maps.ltmap.prune import DEFAULT_MIN_LANDMARKS, PruneReport
from maps.ltmap.tree import LandmarkSet, LandmarkTree
from perception.matching import LandmarkMatches, match_features
from perception.observation import Observation
from perception.similarity import DEFAULT_SCALE, angle_of_cost, default_threshold, delta_t
from perception.viewframe_motion import ZINF_MIN_LANDMARKS, change_since, zinf_motion


def compensate(bearings: np.ndarray, heading: float) -> np.ndarray:
    """Body-frame unit bearings (N x 3) seen with the camera at ``heading`` (rad, counter-clockwise
    about z), in the route frame: what "compensated for the robot's rotation" means here."""
    return Rotation.from_euler("z", heading).apply(np.asarray(bearings, dtype=np.float64).reshape(-1, 3))


@dataclass(frozen=True, slots=True)
class LearnConfig:
    """How a route is taught: the eq. 1 ``threshold`` (None: the cost of a 3 deg bearing change at
    ``scale``) and eq. 1's ``scale`` ``b``, the ``share_angle`` (rad) within which a tracked
    landmark keeps its stored bearing and is shared (None: the angle whose eq. 1 cost is the
    threshold), the matching ``ratio`` (None: the kind's default), an optional memory budget
    (bytes, pruned online), the smallest viewframe pruning keeps, and whether landmarks found
    again are shifted to a common node (``gap_filling``, with ``gaps``: :mod:`maps.ltmap.gaps`)."""

    threshold: float | None = None
    scale: float = DEFAULT_SCALE
    share_angle: float | None = None
    ratio: float | None = None
    budget_bytes: int | None = None
    min_landmarks: int = DEFAULT_MIN_LANDMARKS
    gap_filling: bool = True
    gaps: GapConfig = DEFAULT_GAPS

    def __post_init__(self) -> None:
        for name in ("threshold", "scale", "share_angle"):
            value = getattr(self, name)
            if value is not None and not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value}")
        if self.budget_bytes is not None and self.budget_bytes <= 0:
            raise ValueError(f"budget_bytes must be positive, got {self.budget_bytes}")
        if self.min_landmarks < 0:
            raise ValueError(f"min_landmarks must be >= 0, got {self.min_landmarks}")

    @property
    def eq1_threshold(self) -> float:
        """The threshold in use: the one given, or the cost of a 3 deg change at ``scale``."""
        return default_threshold(self.scale) if self.threshold is None else self.threshold


def threshold_angle(threshold: float, scale: float = DEFAULT_SCALE) -> float:
    """The bearing change (rad) whose eq. 1 cost is ``threshold``: the inverse of the cost."""
    return angle_of_cost(threshold, scale)


@dataclass(frozen=True, slots=True)
class LearnStep:
    """What one observation did to the map while teaching.

    ``viewframe``: index of the last viewframe (-1 before the first); ``created``: this observation
    made it; ``delta_t``: eq. 1 since the previous viewframe (``inf`` when nothing was tracked or
    there was none); ``tracked``: landmarks of the previous viewframe seen now; ``stored``:
    landmarks stored in the new leaf (new ones and sightings not shared); ``volatile``: features
    rejected because the previous image lacked them; ``pruned``: the online pruning this step
    ran (a budget is set and was exceeded); ``shifted``: landmarks found again and merged into a
    common node (gap filling); ``loop``: the loop this viewframe closed.
    """

    viewframe: int
    created: bool
    delta_t: float
    tracked: int
    stored: int = 0
    volatile: int = 0
    pruned: PruneReport | None = None
    shifted: int = 0
    loop: Loop | None = None

    @property
    def over_budget(self) -> bool:
        """Online pruning could not bring the map under the budget."""
        return self.pruned is not None and not self.pruned.fits


@dataclass(frozen=True, slots=True)
class _Seen:
    observation: Observation
    bearings: np.ndarray  # route frame
    place: tuple[float, float] | None = None  # odometry (x, y) it was seen at


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
        self._rng = np.random.default_rng(0)  # Z-infinity's RANSAC: the same route teaches the same map
        angle = self.config.share_angle
        self.threshold = self.config.eq1_threshold
        self.share_angle = threshold_angle(self.threshold, self.config.scale) if angle is None else angle

    def observe(self, observation: Observation, heading: float, place: tuple[float, float] | None = None
                ) -> LearnStep:
        """One new observation, seen with the camera at ``heading`` (rad) in the route frame, at
        ``place`` (odometry x, y; the viewframe it makes keeps it: :meth:`LandmarkTree.place`).
        Give a place with every observation or with none."""
        if self.tree is None:
            self.tree = LandmarkTree(_kind_of(observation), threshold=self.threshold, scale=self.config.scale)
        tree, seen = self.tree, _Seen(observation, compensate(observation.bearings, heading), place)
        self._before, self._latest = self._latest, seen
        if tree.viewframe_count == 0:
            self._at_viewframe = self._before is not None  # the first viewframe needs a previous image
            if not self._at_viewframe:
                return LearnStep(-1, False, np.inf, 0)
            return self._make_viewframe(tree, seen, np.inf, 0)
        tracked = self._track(tree, seen)
        change, count = self._change(tracked)
        self._at_viewframe = change > self.threshold
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
        """Eq. 1 over the landmarks tracked since the last viewframe, from their bearings then
        (over Z-infinity's inliers when there are enough for it: see the module doc)."""
        _, then, now = np.intersect1d(self._anchor.landmarks, tracked.landmarks, return_indices=True)
        ref, cur = self._anchor.bearings[then], tracked.matches.cur[now]
        if len(then) < ZINF_MIN_LANDMARKS:
            return delta_t(ref, cur, scale=self.config.scale), len(then)  # eq. 1
        motion = zinf_motion(ref, cur, self._rng).motion
        return change_since(ref, cur, motion, self.config.scale), len(then)

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
                           share_angle=self.share_angle, place=seen.place)
        stored = np.arange(before, tree.landmark_count)
        self._anchor = _Anchor(np.concatenate((landmarks, stored)),
                               np.vstack((sightings.bearings, tree.bearings[stored])))
        filled = self._fill_gaps(tree)
        stored_now = len(tree.node_landmarks(tree.viewframe_leaves[-1]))  # gap filling may have merged some away
        pruned = self._prune_online(tree)
        return LearnStep(tree.viewframe_count - 1, True, float(change), count, stored_now, volatile, pruned,
                         filled.shifted if filled else 0, filled.loop if filled else None)

    def _fill_gaps(self, tree: LandmarkTree) -> GapFill | None:
        if not self.config.gap_filling:
            return None
        filled = tree.fill_gaps(self.share_angle, self.config.gaps, ratio=self.config.ratio)
        if filled.shifted:  # the anchor follows: a deleted copy is its kept twin now (once)
            landmarks, first = np.unique(filled.landmark_index[self._anchor.landmarks], return_index=True)
            self._anchor = _Anchor(landmarks, self._anchor.bearings[first])
        return filled

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
