"""Depth from a rectified parallel stereo pair with a known baseline (room estimation, the exploration map).

Roadmap paper: at each corner of a dodecagon the robot takes a stereo pair of parallel images;
matches along horizontal epipolar lines give depth ``Z = f * B / d``, hence the free floor space
and the distance to the scene in every direction. Two ways are offered:

- :func:`sparse_stereo`: features of the left image matched to features of the right image on
  the same row (``|dv| <= max_dy``) with a positive disparity up to ``max_disparity``. The ratio
  test is applied among the candidates ALLOWED by that constraint, so repeated texture (several
  look-alikes on the same epipolar line) is rejected as ambiguous instead of giving wrong depth;
  the mutual check removes many-to-one matches.
- :func:`dense_depth`: OpenCV's semi-global matcher (``cv2.StereoSGBM``) with a uniqueness
  margin (the same idea for every pixel) and left-right consistency; :func:`pyramid_points` runs
  it on halved images and drops the smear beside depth jumps (exploration's map, every frame).

Both return depths along the optical axis and 3-D points in the rig's body frame (the LEFT
camera's: x forward, y left, z up).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from perception.camera import PinholeCamera, StereoRig
from perception.features import detect
from perception.matching import DEFAULT_RATIO


@dataclass(frozen=True, slots=True)
class StereoPoints:
    """Matched points of a stereo pair: left pixels, disparities (px), depths (m), body points, and
    (from :func:`sparse_stereo`) the left features' descriptors of ``kind``, so the points can be
    recognised again (visual localisation)."""

    uv_left: np.ndarray
    disparity: np.ndarray
    depth: np.ndarray
    points: np.ndarray
    descriptors: np.ndarray | None = None
    kind: str = ""

    def __len__(self) -> int:
        return len(self.depth)


def points_from_disparity(rig: StereoRig, uv_left: np.ndarray, disparity: np.ndarray,
                          descriptors: np.ndarray | None = None, kind: str = "") -> StereoPoints:
    """Triangulate left pixels with their disparities (``Z = fx * B / d``) into body-frame points."""
    uv = np.asarray(uv_left, dtype=np.float64).reshape(-1, 2)
    d = np.asarray(disparity, dtype=np.float64).ravel()
    depth = rig.depth_from_disparity(d)
    bearings = rig.left.pixel_to_bearing(uv)
    points = bearings * (depth / bearings[:, 0])[:, None]  # body x is the optical axis: x = Z
    return StereoPoints(uv, d, depth, points, descriptors, kind)


def sparse_stereo(
    left: np.ndarray,
    right: np.ndarray,
    rig: StereoRig,
    *,
    kind: str = "orb",
    n_features: int = 1000,
    max_dy: float = 1.5,
    min_disparity: float = 0.5,
    max_disparity: float | None = None,
    ratio: float | None = None,
    levels: int | None = None,
) -> StereoPoints:
    """Feature matches along horizontal epipolar lines (see the module docstring). ``levels``: ORB's
    pyramid (default 1: the same scale in both views, full-resolution positions; more levels give
    descriptors that recognise the point again from nearer or farther)."""
    max_disparity = rig.width / 2 if max_disparity is None else max_disparity
    if kind == "orb" and levels is None:
        levels = 1
    fl = detect(left, kind, n_features=n_features, upright=True, levels=levels)
    fr = detect(right, kind, n_features=n_features, upright=True, levels=levels)
    empty = points_from_disparity(rig, np.zeros((0, 2)), np.zeros(0), fl.descriptors[:0], kind)
    if len(fl) == 0 or len(fr) == 0:
        return empty
    disparity = fl.keypoints_uv[:, None, 0] - fr.keypoints_uv[None, :, 0]
    dy = np.abs(fl.keypoints_uv[:, None, 1] - fr.keypoints_uv[None, :, 1])
    allowed = ((dy <= max_dy) & (disparity >= min_disparity) & (disparity <= max_disparity)).astype(np.uint8)
    norm = cv2.NORM_HAMMING if fl.binary else cv2.NORM_L2
    matcher = cv2.BFMatcher(norm)
    ratio = DEFAULT_RATIO.get(kind, 0.75) if ratio is None else ratio
    left_idx, right_idx = [], []
    for candidates in matcher.knnMatch(fl.descriptors, fr.descriptors, k=2, mask=allowed):
        if not candidates:
            continue
        if len(candidates) == 2 and not candidates[0].distance < ratio * candidates[1].distance:
            continue  # two look-alikes on the same epipolar line: repeated texture, ambiguous
        left_idx.append(candidates[0].queryIdx)
        right_idx.append(candidates[0].trainIdx)
    if not left_idx:
        return empty
    li, ri = np.array(left_idx), np.array(right_idx)
    back = matcher.knnMatch(fr.descriptors, fl.descriptors, k=1, mask=np.ascontiguousarray(allowed.T))
    nearest_left = np.full(len(fr), -1)
    for candidates in back:
        if candidates:
            nearest_left[candidates[0].queryIdx] = candidates[0].trainIdx
    keep = nearest_left[ri] == li  # mutual check
    li, ri = li[keep], ri[keep]
    if len(li) == 0:
        return empty
    uv_left = _subpixel(left, fl.keypoints_uv[li])
    uv_right = _subpixel(right, fr.keypoints_uv[ri])
    d = uv_left[:, 0] - uv_right[:, 0]
    ok = (d >= min_disparity) & (np.abs(uv_left[:, 1] - uv_right[:, 1]) <= max_dy)
    return points_from_disparity(rig, uv_left[ok], d[ok], fl.descriptors[li][ok], kind)


def _subpixel(image: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Corner positions refined to sub-pixel accuracy (``cv2.cornerSubPix``) for finer disparities."""
    gray = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    corners = uv.astype(np.float32).reshape(-1, 1, 2).copy()
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 20, 0.01)
    refined = cv2.cornerSubPix(gray, corners, (3, 3), (-1, -1), criteria).reshape(-1, 2).astype(np.float64)
    moved = np.linalg.norm(refined - uv, axis=1) > 1.5  # a refinement that wandered off: keep the detection
    refined[moved] = uv[moved]
    return refined


def dense_depth(
    left: np.ndarray,
    right: np.ndarray,
    rig: StereoRig,
    *,
    num_disparities: int = 64,
    block_size: int = 5,
    uniqueness: int = 15,
) -> np.ndarray:
    """Depth map (m, float32, left-image sized; NaN where no reliable disparity) by StereoSGBM.

    ``uniqueness`` is OpenCV's ``uniquenessRatio`` (percent by which the best cost must beat the
    second best): the guard against repeated texture. ``num_disparities`` is rounded up to 16.
    """
    num = int(np.ceil(num_disparities / 16.0) * 16)
    gray = [cv2.cvtColor(im, cv2.COLOR_BGR2GRAY) if im.ndim == 3 else im for im in (left, right)]
    matcher = cv2.StereoSGBM.create(
        minDisparity=0,
        numDisparities=num,
        blockSize=block_size,
        P1=8 * block_size**2,
        P2=32 * block_size**2,
        disp12MaxDiff=1,
        uniquenessRatio=uniqueness,
        speckleWindowSize=50,
        speckleRange=2,
    )
    disparity = matcher.compute(gray[0], gray[1]).astype(np.float32) / 16.0  # fixed point, 4 bits
    depth = np.full(disparity.shape, np.nan, dtype=np.float32)
    valid = disparity > 0
    depth[valid] = rig.left.fx * rig.baseline / disparity[valid]
    return depth


def dense_samples(depth: np.ndarray, rig: StereoRig, *, step: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Body-frame points (M x 3) of a depth map sampled every ``step`` pixels, NaNs dropped, and their
    left pixels (M x 2: u, v), for those who need to know which points were image neighbours."""
    vs, us = np.mgrid[0 : depth.shape[0] : step, 0 : depth.shape[1] : step]
    z = depth[vs, us].ravel()
    ok = np.isfinite(z)
    uv = np.column_stack((us.ravel()[ok], vs.ravel()[ok])).astype(np.float64)
    bearings = rig.left.pixel_to_bearing(uv)
    return bearings * (z[ok] / bearings[:, 0])[:, None], uv


def dense_points(depth: np.ndarray, rig: StereoRig, *, step: int = 4) -> np.ndarray:
    """Body-frame points (M x 3) of a depth map, sampled every ``step`` pixels, NaNs dropped."""
    return dense_samples(depth, rig, step=step)[0]


BELOW_FLOOR = 0.2  # m: stereo points this far below a flat floor are wrong matches, to be dropped


def drop_jumps(depth: np.ndarray, max_jump: float, radius: int = 3) -> np.ndarray:
    """The depth map without the pixels within ``radius`` of a depth jump larger than ``max_jump``
    (relative): a semi-global matcher smears depth across occluding edges (a door jamb in front of
    the room behind), streaks that would otherwise become obstacles on the floor between the two."""
    if max_jump <= 0.0:
        return depth
    kernel = np.ones((2 * radius + 1, 2 * radius + 1), np.uint8)
    ok = np.isfinite(depth)
    high = cv2.dilate(np.where(ok, depth, 0.0).astype(np.float32), kernel)
    low = cv2.erode(np.where(ok, depth, np.finfo(np.float32).max).astype(np.float32), kernel)
    keep = ok & (high - low <= max_jump * low)
    return np.where(keep, depth, np.nan).astype(np.float32)


def halved(rig: StereoRig) -> StereoRig:
    """The rig of images halved by ``cv2.pyrDown`` (pixel centres: ``(u + 0.5) / 2 - 0.5``)."""
    def half(c: PinholeCamera) -> PinholeCamera:
        return PinholeCamera((c.width + 1) // 2, (c.height + 1) // 2, c.fx / 2.0, c.fy / 2.0,
                             (c.cx + 0.5) / 2.0 - 0.5, (c.cy + 0.5) / 2.0 - 0.5, c.dist)

    return StereoRig(half(rig.left), half(rig.right), rig.baseline)


def pyramid_points(
    left: np.ndarray,
    right: np.ndarray,
    rig: StereoRig,
    *,
    levels: int,
    num_disparities: int,
    max_jump: float,
    step: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Dense stereo of a pair matched on images halved ``levels`` times (each level: 4x fewer pixels
    to match, depth within a few cm at 3 m for one): body-frame points (M x 3) and their pixels in
    the full left image (M x 2), sampled every ``step`` full-image pixels.

    ``num_disparities`` is the search range of the full images (scaled down with them);
    ``max_jump`` drops the pixels beside depth jumps (:func:`drop_jumps`, 0: keep all)."""
    small = rig
    for _ in range(levels):
        left, right, small = cv2.pyrDown(left), cv2.pyrDown(right), halved(small)
    scale = 2**levels
    depth = dense_depth(left, right, small, num_disparities=-(-num_disparities // scale))
    depth = drop_jumps(depth, max_jump)
    points, uv = dense_samples(depth, small, step=max(1, step // scale))
    return points, (uv + 0.5) * scale - 0.5  # full-image pixels: image neighbours as in the full image
