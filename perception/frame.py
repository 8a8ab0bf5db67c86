"""What a camera delivers: an image with its model, or (ideal sensors) identified bearings."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True, slots=True)
class Frame:
    """An image grabbed from a named camera at ``stamp`` (clock seconds).

    ``camera`` is a model from :mod:`perception.camera` (pinhole, panorama, catadioptric); for a
    stereo pair, ``image`` is the left image and ``right`` the right one, both rectified.
    """

    image: np.ndarray
    camera: Any
    stamp: float
    camera_name: str = "camera"
    right: np.ndarray | None = None


@dataclass(frozen=True, slots=True)
class LandmarkBearings:
    """What a ``bearings`` sensor reports at ``stamp``: ``ids`` (N,) int64 and unit ``bearings``
    (N, 3) float64 in the body frame of camera ``camera_name``, sorted by id."""

    ids: np.ndarray
    bearings: np.ndarray
    stamp: float
    camera_name: str = "bearings"

    def __len__(self) -> int:
        return len(self.ids)

    @property
    def count(self) -> int:
        """How many landmarks are seen (the same name as :class:`perception.observation.Observation`)."""
        return len(self.ids)

    def bearing_of(self, landmark_id: int) -> np.ndarray | None:
        """The bearing of one landmark, or None when it is not seen."""
        hit = np.flatnonzero(self.ids == landmark_id)
        return self.bearings[hit[0]] if hit.size else None
