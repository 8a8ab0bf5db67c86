"""The motion relative to a viewframe while following a route: Z-infinity down a threshold ladder.

Route following (``behaviours.route.FollowRoute``) and the search for a lost trail
(``behaviours.search.SearchPattern``) both ask the same two questions of the landmarks that
matched a viewframe, and this module answers them:

- **Enough to follow?** :func:`lost_threshold`. "Fewer than 50 landmarks match" is read as fewer
  than ``min_matches``, or than half the viewframe's landmarks when it holds fewer than
  ``2 * min_matches`` (a map of the simulator's ideal sensor in a room of 24 landmarks never
  reaches 50), but never fewer than Z-infinity's minimum of 8.
- **Which way, and how turned?** :func:`zinf_motion`: Z-infinity (eqs. 2-6,
  :func:`perception.zinf.estimate_motion`) with a ladder of far thresholds. Why a ladder: the
  paper separates far landmarks (unmoved after the rotation) at one threshold, but indoors few
  landmarks are far enough to move less than 1 degree over the tens of centimetres between
  viewframes, and the ideal sensor's noise alone moves a bearing by that much. So when no far
  set separates a rotation at 1 degree, the estimate is tried again at 2, 4 and 8 degrees
  (:data:`FAR_THRESHOLDS`), the farthest landmarks there standing in for the ones at infinity.
  When none does (a pruned viewframe with few landmarks left), a visual compass
  (:func:`compass_motion`: the rotation of all matched landmarks) keeps the robot going rather
  than stopping it.
- **How far from it?** :func:`change_since`: eq. 1 (:func:`perception.similarity.delta_t`) of
  the landmarks Z-infinity keeps as inliers (far ones and near ones consistent with the
  translation), its rotation removed. Eq. 1 as written weighs a mismatched landmark up to
  about 4 b, over 2000 times a 3 degree change, so one mismatch in a few hundred would decide
  alone; the inliers leave mismatches out. Teaching (when to make a viewframe) and following
  (when one is reached) measure it the same way.
- **Which rule made it?** Every estimate says so (:class:`RuledMotion`, :data:`RULES`): the
  rung of the ladder whose far set gave the rotation (``zinf_1deg`` .. ``zinf_8deg``) or the
  ``compass``, so route following can count how often it went beyond the paper's 1 degree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from perception.similarity import DEFAULT_SCALE, delta_t
from perception.zinf import ZinfResult, ZinfStatus, estimate_motion, estimate_translation

ZINF_MIN_LANDMARKS = 8  # perception.zinf.estimate_motion's default minimum
FAR_THRESHOLDS = tuple(np.radians((1.0, 2.0, 4.0, 8.0)))  # rad: "unmoved after rotation", tightest first
COMPASS = "compass"
RULES = (*(f"zinf_{round(math.degrees(t))}deg" for t in FAR_THRESHOLDS), COMPASS)  # zinf_1deg, ..., compass


@dataclass(frozen=True, slots=True)
class RuledMotion:
    """An estimate and the rule that made it (one of :data:`RULES`)."""

    motion: ZinfResult
    rule: str

    @property
    def compass(self) -> bool:
        return self.rule == COMPASS


def lost_threshold(viewframe_size: int, min_matches: int) -> int:
    """Fewest matches to follow a viewframe of ``viewframe_size`` landmarks (see the module doc)."""
    small = viewframe_size < 2 * min_matches
    return max(ZINF_MIN_LANDMARKS, math.ceil(viewframe_size / 2) if small else min_matches)


def zinf_motion(ref: np.ndarray, cur: np.ndarray, rng: np.random.Generator) -> RuledMotion:
    """Z-infinity (eqs. 2-6) with the tightest far threshold that separates a rotation, else the
    compass (see the module doc); with the rule that made the estimate."""
    for rule, threshold in zip(RULES, FAR_THRESHOLDS, strict=False):
        motion = estimate_motion(ref, cur, rng=rng, far_threshold=threshold)
        if motion.status is not ZinfStatus.NO_ROTATION:
            return RuledMotion(motion, rule)
    return RuledMotion(compass_motion(ref, cur, rng), COMPASS)


def change_since(ref: np.ndarray, cur: np.ndarray, motion: ZinfResult, scale: float = DEFAULT_SCALE) -> float:
    """Eq. 1 from a viewframe's bearings ``ref`` to ``cur`` over ``motion``'s inliers (all when it has
    none), its rotation removed; ``inf`` when it found no rotation (see the module doc)."""
    if not motion.rotation_ok:
        return float("inf")
    weights = motion.inliers.astype(np.float64) if motion.inliers.any() else None
    return delta_t(ref, cur, rotation=motion.rotation, weights=weights, scale=scale)  # eq. 1


def compass_motion(ref: np.ndarray, cur: np.ndarray, rng: np.random.Generator) -> ZinfResult:
    """A visual compass, for comparison only: the rotation fitted to ALL matched landmarks, near
    ones included (no far/near separation), then the translation as Z-infinity finds it."""
    ref, cur = np.asarray(ref, dtype=np.float64), np.asarray(cur, dtype=np.float64)
    none = np.zeros(len(ref), dtype=bool)
    if len(ref) < ZINF_MIN_LANDMARKS:
        return ZinfResult(np.eye(3), np.zeros(3), none, none, 0.0, ZinfStatus.NOT_ENOUGH_LANDMARKS)
    rotation = Rotation.align_vectors(cur, ref)[0].as_matrix()
    everything = np.ones(len(ref), dtype=bool)
    moved = estimate_translation(ref, cur @ rotation, np.ones(len(ref)), rng=rng, threshold=np.radians(1.0),
                                 iterations=200, min_near=5)
    if moved is None:
        return ZinfResult(rotation, np.zeros(3), everything, everything, 0.0, ZinfStatus.NO_TRANSLATION)
    t, inliers, confidence = moved
    return ZinfResult(rotation, t, everything, inliers, confidence, ZinfStatus.OK)
