"""Images in a recording: JPEG-encoded, at a rate a person can watch (``bearings run --image-rate``).

A raw 720 x 172 colour panorama is 370 kB per frame; logged raw, every camera on every tenth
tick, the roadmap's ``learn_targets`` recorded 265 MB. Two choices keep recordings small:

- every image goes into the recording as a JPEG (rerun's ``EncodedImage``; quality
  :data:`JPEG_QUALITY`), about a tenth of the raw bytes for camera images;
- each camera's frames are logged at most :data:`DEFAULT_RATE_HZ` times per second of the run's
  own clock (simulated or wall time), and only frames the camera delivered anew (a frame is never
  logged twice); ``--image-rate 0`` logs every frame grabbed.

The frames are those the data-gathering branch grabbed (``/perception/frames``): what the mission
saw, on a robot as in the simulator, and logging never makes a camera grab or render.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np

DEFAULT_RATE_HZ = 2.0
"""Images per second and camera in a recording, unless ``--image-rate`` says otherwise."""

JPEG_QUALITY = 85
"""JPEG quality (0-100) of recorded images: edges and features stay readable to the eye."""


def jpeg(image: np.ndarray, quality: int = JPEG_QUALITY) -> bytes:
    """``image`` (H x W grey, or H x W x 3/4 RGB(A), uint8) as JPEG bytes (alpha dropped)."""
    pixels = np.asarray(image)
    if pixels.dtype != np.uint8:
        pixels = np.clip(pixels, 0, 255).astype(np.uint8)
    if pixels.ndim == 3 and pixels.shape[2] == 4:
        pixels = pixels[:, :, :3]
    if pixels.ndim == 3 and pixels.shape[2] == 3:
        pixels = cv2.cvtColor(np.ascontiguousarray(pixels), cv2.COLOR_RGB2BGR)  # OpenCV writes BGR
    ok, encoded = cv2.imencode(".jpg", np.ascontiguousarray(pixels), [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise ValueError(f"cannot encode an image of shape {pixels.shape} as JPEG")
    return encoded.tobytes()


@dataclass
class ImageRate:
    """Which camera frames to log: new ones, at most ``rate_hz`` per camera (None or 0: all new ones)."""

    rate_hz: float | None = DEFAULT_RATE_HZ
    _logged_at: dict[str, float] = field(default_factory=dict)
    _stamps: dict[str, float] = field(default_factory=dict)

    def due(self, frames: Mapping[str, Any], now: float) -> Iterator[tuple[str, Any]]:
        """(camera name, frame) for the image frames to log at time ``now`` (and remember them)."""
        period = 1.0 / self.rate_hz if self.rate_hz else 0.0
        for name, frame in frames.items():
            if not isinstance(getattr(frame, "image", None), np.ndarray):
                continue  # an ideal bearings sensor: nothing to show
            if self._stamps.get(name) == frame.stamp:
                continue
            last = self._logged_at.get(name)
            if last is not None and now - last < period - 1e-9:
                continue
            self._logged_at[name], self._stamps[name] = now, frame.stamp
            yield name, frame
