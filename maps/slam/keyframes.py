"""Keyframes: what the stereo pair saw at a few chosen instants, kept to recognise the place later.

A keyframe keeps the base pose estimated when it was taken, the head's angles, and its features:
descriptors, their points in the BASE frame (the head's angles folded in: two keyframes taken
with the head turned differently compare directly), their covariances, and the landmark each
feature is (or -1). A new one is taken when the current view is no longer well covered by the
map (:func:`wants_keyframe`): when the landmarks found are fewer than ``min_found``, or fewer than
``found_ratio`` of the frame's usable features (those close enough to be mapped); and at most
every ``min_interval`` seconds. Only at keyframes do new landmarks join the map (from the features
that were not associated), so the map grows with the places seen, not with time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class Keyframe:
    """One keyframe (see the module docstring); ``pose`` (x, y, theta) as estimated when it was taken,
    ``covariance`` its uncertainty in the odometry frame (:mod:`maps.slam.slam`: the map's own drift
    included)."""

    index: int
    stamp: float
    pose: np.ndarray
    covariance: np.ndarray
    pan: float
    tilt: float
    points: np.ndarray
    covariances: np.ndarray
    descriptors: np.ndarray
    landmark_ids: np.ndarray

    def __len__(self) -> int:
        return len(self.points)

    @property
    def view_direction(self) -> float:
        """The world azimuth the camera looked along (rad): base heading plus pan."""
        return float(self.pose[2]) + self.pan


@dataclass(frozen=True, slots=True)
class KeyframePolicy:
    """When to take a keyframe (see the module docstring)."""

    min_found: int = 40
    found_ratio: float = 0.5
    min_interval: float = 0.3  # s


def wants_keyframe(found: int, usable: int, since_last: float, policy: KeyframePolicy) -> bool:
    """True when the view is not well covered by the map and the last keyframe is old enough."""
    if since_last < policy.min_interval:
        return False
    return found < policy.min_found or found < policy.found_ratio * usable


def view_overlap(a: Keyframe, b: Keyframe, *, max_distance: float, max_turn: float) -> bool:
    """Could ``a`` and ``b`` see the same things: positions within ``max_distance`` (m), view
    directions within ``max_turn`` (rad)."""
    close = math.hypot(float(a.pose[0] - b.pose[0]), float(a.pose[1] - b.pose[1])) <= max_distance
    turn = abs(math.remainder(a.view_direction - b.view_direction, 2.0 * math.pi))
    return close and turn <= max_turn
