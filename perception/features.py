"""Keypoints and descriptors: ORB (default), upright SIFT, BRISK when OpenCV has it.

"Upright" means a fixed orientation: keypoint angles are set to 0 before the descriptors are
computed, as in the roadmap paper (SIFT with fixed orientation). A robot on a floor does not roll,
so rotation invariance only costs distinctiveness; upright is the default for SIFT and for
panoramas. On a full 360 degree panorama the image wraps around: detection runs on the image
padded with a strip from the other side (``cv2.BORDER_WRAP``), and only keypoints of the central
copy are kept, so a corner on the seam is found once, with its whole neighbourhood.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import cv2
import numpy as np

from perception.camera import PanoramaCamera

BINARY_KINDS = frozenset({"orb", "brisk"})
UPRIGHT_ORB_EDGE = 19  # ORB border (px at each pyramid level) for upright keypoints
SEAM_PAD = 40  # columns copied from the other side of a panorama: ORB's border at levels 0-3


def available_kinds() -> tuple[str, ...]:
    """Detector kinds usable with the installed OpenCV (BRISK is gone from OpenCV 5)."""
    kinds = ["orb", "sift"]
    if hasattr(cv2, "BRISK_create"):
        kinds.append("brisk")
    return tuple(kinds)


@dataclass(frozen=True, slots=True)
class Features:
    """Keypoints (N x 2 pixel positions, OpenCV pixel-centre convention) and their descriptors.

    ``descriptors`` is N x 32 uint8 for ORB, N x 64 uint8 for BRISK, N x 128 float32 for SIFT.
    """

    keypoints_uv: np.ndarray
    descriptors: np.ndarray
    kind: str

    def __len__(self) -> int:
        return len(self.keypoints_uv)

    @property
    def binary(self) -> bool:
        """Descriptors compared by Hamming distance."""
        return self.kind in BINARY_KINDS

    def subset(self, index: np.ndarray) -> Features:
        """The features selected by an index array or boolean mask."""
        return Features(self.keypoints_uv[index], self.descriptors[index], self.kind)


def empty_features(kind: str) -> Features:
    """No features, with the descriptor width and type of ``kind``."""
    width, dtype = {"orb": (32, np.uint8), "brisk": (64, np.uint8), "sift": (128, np.float32)}[kind]
    return Features(np.zeros((0, 2)), np.zeros((0, width), dtype=dtype), kind)


@lru_cache(maxsize=16)
def _detector(kind: str, n_features: int, levels: int | None = None, upright: bool = False) -> Any:
    if kind == "orb":
        # an upright 31-pixel patch only needs a 16-pixel margin, not the 31 a rotated one needs:
        # more of a 172-row panorama is usable and a narrower seam strip suffices
        edge = UPRIGHT_ORB_EDGE if upright else 31
        return cv2.ORB.create(n_features, nlevels=8 if levels is None else levels, edgeThreshold=edge)
    if kind == "sift":
        return cv2.SIFT.create(nfeatures=n_features)
    if kind == "brisk":
        if not hasattr(cv2, "BRISK_create"):
            raise ValueError("BRISK is not in this OpenCV build (removed in OpenCV 5); use orb or sift")
        return cv2.BRISK_create()
    raise ValueError(f"unknown feature kind {kind!r} (available: {', '.join(available_kinds())})")


def _gray(image: np.ndarray) -> np.ndarray:
    if image.ndim == 3:
        return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    if image.dtype != np.uint8:
        return cv2.convertScaleAbs(image)
    return image


def detect(
    image: np.ndarray,
    kind: str = "orb",
    *,
    n_features: int = 500,
    camera: Any = None,
    upright: bool | None = None,
    wrap: bool | None = None,
    mask: np.ndarray | None = None,
    levels: int | None = None,
) -> Features:
    """Detect keypoints and compute descriptors on a grey (or BGR) image.

    ``upright`` defaults to True for SIFT and for panoramas. ``wrap`` defaults to True when
    ``camera`` is a :class:`PanoramaCamera` covering 360 degrees. ``mask`` (uint8, image-sized)
    limits detection to its non-zero pixels (e.g. the ring of a catadioptric image). ``levels``
    sets ORB's pyramid depth (OpenCV's default 8 when None; 1 for same-scale views such as a
    rectified stereo pair, where it keeps keypoint positions at full resolution).
    """
    gray = _gray(image)
    is_panorama = isinstance(camera, PanoramaCamera)
    if upright is None:
        upright = kind == "sift" or is_panorama
    if wrap is None:
        wrap = is_panorama and camera.wraps
    width = gray.shape[1]
    pad = min(SEAM_PAD, width // 2) if wrap else 0
    # ORB: keep the budget for the original width despite the pads' duplicates
    budget = int(round(n_features * (width + 2 * pad) / width)) if kind == "orb" and pad else n_features
    detector = _detector(kind, budget, levels, upright)
    if not (pad or upright):  # plain case: one pass of OpenCV
        keypoints, descriptors = detector.detectAndCompute(gray, mask)
        if descriptors is None or not keypoints:
            return empty_features(kind)
        return Features(np.asarray(cv2.KeyPoint.convert(keypoints), dtype=np.float64), descriptors, kind)
    if pad:
        gray = cv2.copyMakeBorder(gray, 0, 0, pad, pad, cv2.BORDER_WRAP)
        mask = None if mask is None else cv2.copyMakeBorder(mask, 0, 0, pad, pad, cv2.BORDER_WRAP)
    keypoints = _central(detector.detect(gray, mask), pad, width)
    if upright:
        keypoints = _upright(keypoints, dedupe=kind != "orb")
    return _describe(detector, gray, keypoints, kind, pad, n_features)


def _central(keypoints: Sequence[cv2.KeyPoint], pad: int, width: int) -> list[cv2.KeyPoint]:
    """Fold a wrap-padded detection back: keep the central copy, whose neighbourhood is complete."""
    if not pad:
        return list(keypoints)
    u = np.asarray(cv2.KeyPoint.convert(keypoints))[:, 0] if keypoints else np.zeros(0)
    central = np.flatnonzero((u >= pad - 0.5) & (u < pad + width - 0.5))
    return [keypoints[int(i)] for i in central]


def _describe(
    detector: Any, gray: np.ndarray, keypoints: list[cv2.KeyPoint], kind: str, pad: int, n_features: int
) -> Features:
    """Descriptors of chosen keypoints, positions shifted back by ``pad``; ORB on a padded
    panorama keeps the strongest ``n_features`` (the budget of the original width)."""
    if not keypoints:
        return empty_features(kind)
    keypoints, descriptors = detector.compute(gray, keypoints)
    if descriptors is None or not keypoints:
        return empty_features(kind)
    uv = np.asarray(cv2.KeyPoint.convert(keypoints), dtype=np.float64)
    uv[:, 0] -= pad
    if kind == "orb" and pad and len(uv) > n_features:
        responses = np.array([k.response for k in keypoints])
        order = np.argsort(-responses, kind="stable")[:n_features]
        uv, descriptors = uv[order], descriptors[order]
    return Features(uv, descriptors, kind)


def _upright(keypoints: list[cv2.KeyPoint], *, dedupe: bool) -> list[cv2.KeyPoint]:
    """The keypoints with angle 0 (in place). With ``dedupe``, SIFT's copies of one point at
    several orientations (same position and size) become one."""
    if dedupe:
        seen: set[tuple[float, float, float]] = set()
        unique = []
        for k in keypoints:
            key = (round(k.pt[0], 2), round(k.pt[1], 2), round(k.size, 2))
            if key not in seen:
                seen.add(key)
                unique.append(k)
        keypoints = unique
    for k in keypoints:
        k.angle = 0.0
    return keypoints
