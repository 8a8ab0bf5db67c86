"""What one frame tells about landmarks: their unit bearing vectors, with descriptors or ids.

Two sources give the same value: a camera image (features detected, descriptors to match by)
and an ideal ``bearings`` sensor of the simulator (landmark ids, so matching is exact). Code
downstream needs only ``bearings`` plus a way to associate: ``features`` or ``ids``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from perception.features import Features, detect
from perception.frame import Frame, LandmarkBearings


@dataclass(frozen=True, slots=True)
class Observation:
    """Landmarks seen at ``stamp``: bearings (N x 3, camera body frame) and either the features
    they were detected as (``features``) or their known identities (``ids``)."""

    bearings: np.ndarray
    stamp: float
    camera_name: str
    features: Features | None = None
    ids: np.ndarray | None = None

    @property
    def count(self) -> int:
        """How many landmarks were observed (usable in missions: ``/perception/observation.count``)."""
        return len(self.bearings)


def observe(frame: Frame, *, kind: str = "orb", n_features: int = 500) -> Observation:
    """Detect features on the frame and turn their pixels into bearings with the frame's camera."""
    features = detect(frame.image, kind, n_features=n_features, camera=frame.camera)
    bearings = frame.camera.pixel_to_bearing(features.keypoints_uv) if len(features) else np.zeros((0, 3))
    return Observation(bearings, frame.stamp, frame.camera_name, features=features)


def from_landmark_bearings(sensed: LandmarkBearings) -> Observation:
    """The observation of an ideal bearings sensor: identities instead of descriptors."""
    return Observation(sensed.bearings, sensed.stamp, sensed.camera_name, ids=sensed.ids)
