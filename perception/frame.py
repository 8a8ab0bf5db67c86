"""One camera image with the model that turns its pixels into bearings."""

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
