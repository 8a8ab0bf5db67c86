"""Synthetic scenes with known motion, for the perception tests and ``bearings bench perception``.

- :func:`make_scene`: landmark bearings (far and near, all around) seen from a reference pose and
  from a moved and turned pose, with noise and outliers: input for Z-infinity.
- :func:`make_planar_scene`: normalised pinhole coordinates of points seen from two floor poses:
  input for planar homing.
- :func:`textured_panorama`: a seamless grey panorama full of corners.
Pure numpy / OpenCV drawing; no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.spatial.transform import Rotation


def unit(v: np.ndarray) -> np.ndarray:
    """Rows scaled to unit length."""
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@dataclass(frozen=True)
class Scene:
    """Bearings of landmarks from a reference pose (origin) and a current pose.

    ``rotation`` maps ref-frame vectors into the current frame; ``position`` is the current
    camera centre in the reference frame; ``outlier`` marks correspondences replaced by junk.
    """

    ref: np.ndarray
    cur: np.ndarray
    rotation: np.ndarray
    position: np.ndarray
    far: np.ndarray
    outlier: np.ndarray


def make_scene(
    seed: int = 0,
    *,
    n_far: int = 150,
    n_near: int = 150,
    yaw_deg: float = 20.0,
    tilt_deg: float = 0.0,
    position: tuple[float, float, float] = (0.5, 0.2, 0.0),
    near_range: tuple[float, float] = (1.0, 4.0),
    azimuth_range_deg: tuple[float, float] = (-180.0, 180.0),
    noise_deg: float = 0.0,
    outlier_fraction: float = 0.0,
) -> Scene:
    """Bearings of ``n_far`` landmarks at 10 km and ``n_near`` at ``near_range`` metres.

    The camera turns by ``yaw_deg`` (counter-clockwise) and tilts by ``tilt_deg``, and moves to
    ``position`` (reference frame). ``noise_deg`` is the std of the bearing noise per axis;
    ``outlier_fraction`` of the current bearings are replaced by random directions.
    """
    rng = np.random.default_rng(seed)
    n = n_far + n_near
    az = np.radians(rng.uniform(*azimuth_range_deg, size=n))
    el = np.radians(rng.uniform(-30.0, 30.0, size=n))
    dirs = np.column_stack((np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)))
    dist = np.concatenate((np.full(n_far, 1e4), rng.uniform(*near_range, size=n_near)))
    points = dirs * dist[:, None]
    R = Rotation.from_euler("zyx", [-yaw_deg, tilt_deg, -tilt_deg / 2], degrees=True).as_matrix()
    c = np.asarray(position, dtype=float)
    ref = unit(points)
    cur = unit((points - c) @ R.T)
    if noise_deg > 0:
        sigma = np.radians(noise_deg)
        ref = unit(ref + rng.normal(0, sigma, ref.shape))
        cur = unit(cur + rng.normal(0, sigma, cur.shape))
    outlier = np.zeros(n, dtype=bool)
    outlier[rng.choice(n, int(round(outlier_fraction * n)), replace=False)] = True
    junk = unit(rng.normal(size=(int(outlier.sum()), 3)))
    cur[outlier] = junk
    far = np.zeros(n, dtype=bool)
    far[:n_far] = True
    return Scene(ref=ref, cur=cur, rotation=R, position=c, far=far & ~outlier, outlier=outlier)


def rotation_error_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle (deg) of the rotation between two rotation matrices."""
    return float(np.degrees(Rotation.from_matrix(a.T @ b).magnitude()))


def angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle (deg) between two vectors."""
    return float(np.degrees(np.arccos(np.clip(np.dot(unit(a), unit(b)), -1.0, 1.0))))


@dataclass(frozen=True)
class PlanarScene:
    """Normalised pinhole coordinates (OpenCV optical frame) of points seen from two floor poses.

    ``theta`` is the CCW turn from ref to cur, ``displacement`` the camera displacement (x, z) in
    the ref optical frame.
    """

    ref: np.ndarray
    cur: np.ndarray
    theta: float
    displacement: np.ndarray
    outlier: np.ndarray


def make_planar_scene(
    seed: int = 0,
    *,
    n: int = 200,
    theta_deg: float = 10.0,
    displacement: tuple[float, float] = (0.3, 1.0),
    depth_range: tuple[float, float] = (3.0, 8.0),
    noise: float = 0.0,
    outlier_fraction: float = 0.0,
    half_extent: tuple[float, float] = (1.0, 0.75),
) -> PlanarScene:
    """``n`` points 3-8 m ahead, seen before and after a turn ``theta_deg`` and a displacement.

    ``noise`` is the std of the normalised-coordinate noise (about pixels / focal length).
    ``half_extent`` bounds the normalised image, ``|x| < hx`` and ``|y| < hy`` in both views: the
    default is a 90 x 74 degree field of view; ``(320 / 525, 240 / 525)`` is the simulator's
    640 x 480 ``front`` camera. Outliers are drawn uniformly inside the same bounds.
    """
    rng = np.random.default_rng(seed)
    theta = np.radians(theta_deg)
    c = np.array([displacement[0], 0.0, displacement[1]])
    R = np.array([[np.cos(theta), 0, np.sin(theta)], [0, 1, 0], [-np.sin(theta), 0, np.cos(theta)]])
    hx, hy = half_extent
    points: list[np.ndarray] = []
    while len(points) < n:  # points visible in both views (inside the field of view)
        z = rng.uniform(*depth_range)
        p = np.array([rng.uniform(-hx, hx) * z, rng.uniform(-0.4, 0.4) * z, z])
        q = R @ (p - c)
        if q[2] > 0.5 and abs(q[0] / q[2]) < hx and abs(q[1] / q[2]) < hy:
            points.append(p)
    P = np.array(points)
    Q = (P - c) @ R.T
    ref = P[:, :2] / P[:, 2:]
    cur = Q[:, :2] / Q[:, 2:]
    if noise > 0:
        ref = ref + rng.normal(0, noise, ref.shape)
        cur = cur + rng.normal(0, noise, cur.shape)
    outlier = np.zeros(n, dtype=bool)
    outlier[rng.choice(n, int(round(outlier_fraction * n)), replace=False)] = True
    cur[outlier] = rng.uniform(-1, 1, (int(outlier.sum()), 2)) * [hx, hy]
    d = np.array(displacement, dtype=float)
    norm = np.linalg.norm(d)
    return PlanarScene(ref, cur, theta, d / norm if norm > 0 else d, outlier)


def textured_panorama(seed: int = 0, width: int = 720, height: int = 172, shapes: int = 400) -> np.ndarray:
    """A seamless (wrap-around) grey panorama full of corners: random rectangles and discs."""
    rng = np.random.default_rng(seed)
    canvas = np.full((height, 3 * width), 90, dtype=np.uint8)
    for _ in range(shapes):
        x, y = int(rng.integers(0, width)), int(rng.integers(0, height))
        w, h = int(rng.integers(4, 40)), int(rng.integers(4, 30))
        shade = int(rng.integers(0, 256))
        disc = rng.random() < 0.3
        for k in range(3):  # the same shape in every copy so that the middle copy wraps seamlessly
            if disc:
                cv2.circle(canvas, (x + k * width, y), w // 2, shade, -1)
            else:
                cv2.rectangle(canvas, (x + k * width, y), (x + k * width + w, y + h), shade, -1)
    canvas = cv2.GaussianBlur(canvas, (3, 3), 0)
    return np.ascontiguousarray(canvas[:, width : 2 * width])
