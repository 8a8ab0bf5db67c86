"""The image side of the roadmap behaviours: features, matching and planar homing against a target.

Roadmap paper (docs/design.md, method 2): SIFT with a fixed (upright) orientation, the ratio test
at 0.65, and the planar essential matrix between the current image and a target image. Pure
functions over :mod:`perception`; the behaviours call them on frames they took.

Choices where the paper is vague:

- **A match** needs ``min_inliers`` correspondences consistent with one planar motion
  (:func:`perception.planar.estimate_planar_motion`, threshold 2 px), not a count of descriptor
  matches: textures repeat, geometry does not. 25 by default: on the simulator's 640 x 480
  front camera a true match of a view 1-2 m away has 100-200 inliers, a wrong one rarely 10.
- **Normalised coordinates** come from each image's own camera model (a target image file has
  none: it was taken with the camera that homes to it, so the live frame's model is used).
- **Camera pose**: the homing camera sits at ``offset`` (x, y; m) of the robot centre when the
  pan-tilt head is level and at pan 0; homing geometry is done for the camera, then moved to the
  robot centre, because turning the robot on the spot moves the camera.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from perception.features import Features, detect
from perception.frame import Frame
from perception.geometry import Pose2D, wrap_angle
from perception.matching import match_features
from perception.planar import PlanarResult, PlanarStatus, estimate_planar_motion

RATIO = 0.65  # the roadmap paper's ratio test for SIFT
FEATURES = 1000  # SIFT features per 640 x 480 image
MIN_INLIERS = 25
SEED = 0  # RANSAC sampling seed: the same images give the same estimate


def grey(image: np.ndarray) -> np.ndarray:
    """A grey uint8 image (BGR images are converted)."""
    if image.ndim == 3:
        return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    return image


def describe(image: np.ndarray, n_features: int = FEATURES) -> Features:
    """Upright SIFT features of an image (roadmap paper: SIFT with a fixed orientation)."""
    return detect(grey(image), "sift", n_features=n_features, upright=True)


def pinhole_of(camera: Any) -> Any:
    """The pinhole model homing uses: a stereo rig's left camera, or the model itself."""
    return getattr(camera, "left", camera)


@dataclass(frozen=True, slots=True)
class Comparison:
    """An image compared with a target image: descriptor matches, and the planar motion from the
    image to the target (``planar.theta``: turn to face as the target does; ``planar.bearing``:
    where to drive, robot frame)."""

    matches: int
    planar: PlanarResult

    @property
    def inliers(self) -> int:
        return int(self.planar.inliers.sum())

    def matched(self, min_inliers: int = MIN_INLIERS) -> bool:
        """Enough correspondences agree on a planar motion (at least its turn is known)."""
        return self.planar.theta_ok and self.inliers >= min_inliers

    @property
    def at_target(self) -> bool:
        """No parallax left after the turn: the camera is where the target image was taken."""
        return self.planar.status is PlanarStatus.NO_TRANSLATION


def compare(features: Features, camera: Any, target_features: Features, target_camera: Any = None, *,
            ratio: float = RATIO, min_inliers: int = 8) -> Comparison:
    """Match an image's features with a target's (ratio test, mutual) and estimate the planar
    motion from the image (``ref``) to the target (``cur``), as :mod:`perception.planar` homes."""
    found = match_features(features, target_features, ratio=ratio)
    here = pinhole_of(camera)
    there = pinhole_of(target_camera) if target_camera is not None else here
    ref = here.normalised(features.keypoints_uv[found.query])
    cur = there.normalised(target_features.keypoints_uv[found.train])
    planar = estimate_planar_motion(ref, cur, focal=(here.fx, here.fy), min_inliers=min_inliers, rng=SEED)
    return Comparison(len(found), planar)


def compare_frame(frame: Frame, target_features: Features, target_camera: Any = None, *, ratio: float = RATIO,
                  n_features: int = FEATURES) -> Comparison:
    """:func:`compare` for a frame just taken."""
    return compare(describe(frame.image, n_features), frame.camera, target_features, target_camera, ratio=ratio)


def camera_pose(robot: Pose2D, offset: tuple[float, float]) -> Pose2D:
    """The homing camera's planar pose for a robot pose (level head at pan 0)."""
    return robot.compose(Pose2D(offset[0], offset[1], 0.0))


def robot_pose(camera: Pose2D, offset: tuple[float, float]) -> Pose2D:
    """Inverse of :func:`camera_pose`."""
    return camera.compose(Pose2D(-offset[0], -offset[1], 0.0))


def optical_step(first: Pose2D, second: Pose2D) -> tuple[np.ndarray, float]:
    """The second camera pose in the first camera's optical frame: ``(x right, z forward)`` and the
    counter-clockwise turn, as :func:`perception.planar.distance_from_third_image` takes them."""
    rel = second.relative_to(first)
    return np.array([-rel.y, rel.x]), rel.theta


def mean_angle(a: float, b: float) -> float:
    """The circular mean of two angles (rad)."""
    return wrap_angle(a + wrap_angle(b - a) / 2.0)

