"""The values roadmap nodes hand each other through their ports (frozen dataclasses).

Poses named ``odometry`` are in the odometry frame of the run (they drift with it); poses in the
*reference frame* (the room estimate's, :mod:`maps.room`) are what maps store. Every port that
carries one of these says which frame it is in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from perception.features import Features
from perception.geometry import Pose2D


@dataclass(frozen=True, eq=False)
class TargetView:
    """One image the robot can home to: a user's target image, or the reference image.

    ``features`` are upright SIFT (roadmap paper); ``camera`` is the model the image was taken
    with, None for an image file (it was taken with the camera that homes to it, whose model
    comes with the live frames); ``source`` says where it came from (a path, or ``camera:NAME``)
    and ``stamp`` when (clock seconds; NaN for files).
    """

    name: str
    image: np.ndarray
    features: Features
    camera: Any = None
    source: str = ""
    stamp: float = math.nan


@dataclass(frozen=True, eq=False)
class TargetImages:
    """The target images of a mission, by name (file stem), in a stable order."""

    views: tuple[TargetView, ...] = ()

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self.views)

    def __len__(self) -> int:
        return len(self.views)

    def get(self, name: str) -> TargetView:
        for view in self.views:
            if view.name == name:
                return view
        raise KeyError(f"no target image named {name!r} (have: {', '.join(self.names) or 'none'})")


@dataclass(frozen=True, slots=True)
class Sighting:
    """A target matched in a camera image: which, from where, how well.

    ``odometry``: the robot's odometry pose when the image was taken; ``bearing``: azimuth (rad,
    robot frame, left-positive) of the displacement towards where the target image was taken;
    ``turn``: how far (rad, counter-clockwise) the robot would turn to face as the target image
    does; ``inliers``: correspondences that agree with the planar motion.
    """

    target: str
    odometry: Pose2D
    bearing: float
    turn: float
    inliers: int
    matches: int


@dataclass(frozen=True, slots=True)
class HomingResult:
    """Where homing put a target: ``pose`` is the robot pose of the target image in the odometry
    frame (the robot was driven there), ``distance`` the last measured distance to it (m),
    ``iterations`` the triangulation rounds used, ``stamp`` when homing ended."""

    target: str
    pose: Pose2D
    distance: float
    iterations: int
    inliers: int
    stamp: float


@dataclass(frozen=True, slots=True)
class ScanRecord:
    """Images taken at one position (reference frame): where, with which headings (rad), and the
    target found there ('' if none). ``seq`` numbers the scans of a run from 1."""

    seq: int
    x: float
    y: float
    headings: tuple[float, ...]
    found: str = ""


@dataclass(frozen=True, slots=True)
class NavigationResult:
    """How ``NavigateToTarget`` went: ``reached``; the first target matched from the unknown start;
    the targets visited in order; random moves made; rescans; edges whose drive was held short and
    homed from there; why it stopped when it failed."""

    goal: str
    reached: bool
    localised_at: str = ""
    visited: tuple[str, ...] = ()
    random_moves: int = 0
    rescans: int = 0
    homed_short: int = 0  # edges whose drive was held short, then homed from there
    reason: str = ""
