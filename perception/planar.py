"""Homing by the planar essential matrix (Shimshoni & Rivlin; DESIGN.md, algorithm 2).

Inputs are N x 2 NORMALISED image coordinates of a pinhole camera (OpenCV optical convention:
x right, y down, z forward; undistort with ``PinholeCamera.normalised``) of the same points in a
``ref`` and a ``cur`` image. The camera moves on the floor plane and turns about its vertical
(optical y) axis, so with ``X_cur = R(theta) (X_ref - c)``, ``R(theta)`` a rotation about y and
``c = (c_x, 0, c_z)`` the displacement, the essential matrix ``E = [t]_x R`` with ``t = -R c`` is

    E = [[0, -t_z, 0], [t_z cos + t_x sin, 0, t_z sin - t_x cos], [0, t_x, 0]]

and ``x_cur^T E x_ref = 0`` is LINEAR in ``e = (-t_z, t_z cos + t_x sin, t_z sin - t_x cos, t_x)``:
``[x2 y1, y2 x1, y2, y1] . e = 0``. Three points give ``e`` up to scale (3 unknowns: theta and the
direction of ``(t_x, t_z)``); RANSAC picks the inliers, ``scipy.optimize.least_squares`` refines
(theta, direction) on the Sampson distance, and the sign of the translation (which ``E`` cannot
see) comes from a majority vote: after de-rotation, points move away from the direction of travel.

Points on the horizon (y = 0 in both images) lie in every epipolar plane of a planar motion and
carry no information; the scene must have points above or below the camera height.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

SeedLike = int | np.random.Generator | None


@dataclass(frozen=True, slots=True)
class PlanarResult:
    """Planar motion from the ``ref`` view to the ``cur`` view.

    ``theta``: the turn (rad, counter-clockwise seen from above, i.e. robot yaw) from ref to cur.
    ``direction``: unit ``(x, z)`` displacement of the camera from ref to cur in the REF optical
    frame (x right, z forward), sign resolved by the majority vote. To home, pass the current
    image as ``ref`` and the target image as ``cur``: drive along ``direction``, then turn by
    ``theta``. ``votes`` is the fraction of inliers that agreed with the chosen sign. ``moved``
    is False (and ``direction`` zero) when the points show no parallax after de-rotation: a pure
    turn, where every direction fits and none is reported.
    """

    theta: float
    direction: np.ndarray
    inliers: np.ndarray
    ok: bool
    votes: float = 0.0
    rms_sampson: float = float("nan")
    moved: bool = True

    @property
    def bearing(self) -> float:
        """Azimuth of ``direction`` in the robot body frame (rad, left-positive, 0 = ahead)."""
        return float(np.arctan2(-self.direction[0], self.direction[1]))

    @property
    def t(self) -> np.ndarray:
        """OpenCV-convention translation ``t = -R c`` (unit 3-vector) of ``X_cur = R X_ref + t``."""
        c = np.array([self.direction[0], 0.0, self.direction[1]])
        return -(rotation_y(self.theta) @ c)


def rotation_y(theta: float) -> np.ndarray:
    """Rotation about the optical y axis that maps ref-frame vectors into the current frame."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def planar_essential(theta: float, direction: np.ndarray) -> np.ndarray:
    """``E = [t]_x R`` for a turn ``theta`` and camera displacement ``direction = (c_x, c_z)``."""
    R = rotation_y(theta)
    t = -(R @ np.array([direction[0], 0.0, direction[1]]))
    tx = np.array([[0.0, -t[2], t[1]], [t[2], 0.0, -t[0]], [-t[1], t[0], 0.0]])
    return tx @ R


def _design(ref: np.ndarray, cur: np.ndarray) -> np.ndarray:
    """Rows ``[x2 y1, y2 x1, y2, y1]`` of the linear planar epipolar constraint (N x 4)."""
    x1, y1 = ref[:, 0], ref[:, 1]
    x2, y2 = cur[:, 0], cur[:, 1]
    return np.column_stack((x2 * y1, y2 * x1, y2, y1))


def _params_from_e(e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(theta, c) per row of e (K x 4), c = camera displacement (c_x, c_z) up to sign, unit."""
    t_x, t_z = e[:, 3], -e[:, 0]
    # (e2, e3) = [[t_z, t_x], [-t_x, t_z]] (cos, sin): invert the scaled rotation
    cos = t_z * e[:, 1] - t_x * e[:, 2]
    sin = t_x * e[:, 1] + t_z * e[:, 2]
    theta = np.arctan2(sin, cos)
    # t = -R c  =>  c = -R^T t, in the (x, z) plane
    c, s = np.cos(theta), np.sin(theta)
    c_x = -(c * t_x - s * t_z)
    c_z = -(s * t_x + c * t_z)
    d = np.column_stack((c_x, c_z))
    return theta, d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-15)


def _sampson(E: np.ndarray, ref_h: np.ndarray, cur_h: np.ndarray) -> np.ndarray:
    """Signed Sampson distances of homogeneous correspondences for one or K stacked E (K x N)."""
    Ex1 = np.einsum("...ij,nj->...ni", E, ref_h)
    Etx2 = np.einsum("...ji,nj->...ni", E, cur_h)
    num = np.einsum("ni,...ni->...n", cur_h, Ex1)
    den = np.sqrt(Ex1[..., 0] ** 2 + Ex1[..., 1] ** 2 + Etx2[..., 0] ** 2 + Etx2[..., 1] ** 2)
    return num / np.maximum(den, 1e-15)


def _essentials(theta: np.ndarray, d: np.ndarray) -> np.ndarray:
    """K stacked planar essential matrices (vectorised :func:`planar_essential`)."""
    c, s = np.cos(theta), np.sin(theta)
    t_x = -(c * d[:, 0] + s * d[:, 1])  # t = -R c
    t_z = -(-s * d[:, 0] + c * d[:, 1])
    E = np.zeros((len(theta), 3, 3))
    E[:, 0, 1] = -t_z
    E[:, 1, 0] = t_z * c + t_x * s
    E[:, 1, 2] = t_z * s - t_x * c
    E[:, 2, 1] = t_x
    return E


def _vote(ref_h: np.ndarray, cur_h: np.ndarray, theta: float, d: np.ndarray) -> float:
    """Signed majority vote for moving along +d: each point's shift after de-rotation."""
    c = np.array([d[0], 0.0, d[1]])
    derotated = cur_h @ rotation_y(theta)  # row form of R^T x_cur
    r1 = ref_h / np.linalg.norm(ref_h, axis=1, keepdims=True)
    r2 = derotated / np.linalg.norm(derotated, axis=1, keepdims=True)
    # moving along c, every point's ray turns away from c: (r1 - r2) . c > 0
    return float(np.mean(np.sign((r1 - r2) @ c)))


def _median_parallax(ref_h: np.ndarray, cur_h: np.ndarray, theta: float) -> float:
    """Median angle (rad) between each ref ray and its de-rotated current ray."""
    r1 = ref_h / np.linalg.norm(ref_h, axis=1, keepdims=True)
    derotated = cur_h @ rotation_y(theta)
    r2 = derotated / np.linalg.norm(derotated, axis=1, keepdims=True)
    return float(np.median(np.linalg.norm(np.cross(r1, r2), axis=1)))


def estimate_planar_motion(
    ref: np.ndarray,
    cur: np.ndarray,
    *,
    threshold: float = 2e-3,
    iterations: int = 200,
    min_inliers: int = 8,
    rng: SeedLike = 0,
    refine: bool = True,
) -> PlanarResult:
    """Planar homing between two views from normalised coordinates (see the module docstring).

    ``threshold`` is the Sampson distance (normalised units, ~pixels / focal length) under which
    a correspondence is an inlier. ``ok`` is False, with ``theta`` 0 and ``direction`` zero, when
    fewer than ``min_inliers`` points away from the horizon (``|y| > 10 threshold`` in either
    view) agree on a motion, or no sign wins the vote.
    """
    ref = np.asarray(ref, dtype=np.float64).reshape(-1, 2)
    cur = np.asarray(cur, dtype=np.float64).reshape(-1, 2)
    if ref.shape != cur.shape:
        raise ValueError(f"ref and cur must have the same shape, got {ref.shape} and {cur.shape}")
    n = len(ref)
    failed = PlanarResult(0.0, np.zeros(2), np.zeros(n, dtype=bool), False)
    if n < max(3, min_inliers):
        return failed
    generator = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    ref_h = np.column_stack((ref, np.ones(n)))
    cur_h = np.column_stack((cur, np.ones(n)))
    # points at camera height satisfy every planar epipolar constraint: they cannot vouch for one
    informative = np.abs(ref[:, 1]) + np.abs(cur[:, 1]) > 10.0 * threshold
    A = _design(ref, cur)
    samples = np.argpartition(generator.random((iterations, n)), 3, axis=1)[:, :3]  # 3 distinct points
    _, _, vt = np.linalg.svd(A[samples])  # batched 3 x 4 systems: the null vector is the last row
    theta, d = _params_from_e(vt[:, -1, :])
    errors = np.abs(_sampson(_essentials(theta, d), ref_h, cur_h))
    inlier_sets = errors < threshold
    best = int(np.argmax(inlier_sets.sum(axis=1)))
    mask = inlier_sets[best]
    if (mask & informative).sum() < min_inliers:
        return failed
    th, direction = float(theta[best]), d[best]
    # linear least squares on all inliers (>= 3 points), then the Sampson refinement
    _, _, vt_all = np.linalg.svd(A[mask])
    th_all, d_all = _params_from_e(vt_all[-1:, :])
    if (np.abs(_sampson(planar_essential(th_all[0], d_all[0]), ref_h, cur_h)) < threshold).sum() >= mask.sum():
        th, direction = float(th_all[0]), d_all[0]
    if refine:
        phi0 = np.arctan2(direction[0], direction[1])

        def residuals(p: np.ndarray) -> np.ndarray:
            dd = np.array([np.sin(p[1]), np.cos(p[1])])
            return _sampson(planar_essential(p[0], dd), ref_h[mask], cur_h[mask])

        fit = least_squares(residuals, x0=[th, phi0], loss="soft_l1", f_scale=threshold)
        th, phi = float(fit.x[0]), float(fit.x[1])
        direction = np.array([np.sin(phi), np.cos(phi)])
        mask = np.abs(_sampson(planar_essential(th, direction), ref_h, cur_h)) < threshold
        if (mask & informative).sum() < min_inliers:
            return failed
    th = float(np.arctan2(np.sin(th), np.cos(th)))
    if _median_parallax(ref_h[mask], cur_h[mask], th) < 2.0 * threshold:
        # pure rotation: every direction fits E = 0, so report the turn and no translation
        return PlanarResult(th, np.zeros(2), mask, True, moved=False)
    vote = _vote(ref_h[mask], cur_h[mask], th, direction)  # forward/backward by majority
    if vote == 0.0:
        return failed
    if vote < 0.0:
        direction = -direction
    rms = float(np.sqrt(np.mean(_sampson(planar_essential(th, direction), ref_h[mask], cur_h[mask]) ** 2)))
    return PlanarResult(th, direction, mask, True, votes=abs(vote) * 0.5 + 0.5, rms_sampson=rms)


@dataclass(frozen=True, slots=True)
class ThirdImageDistance:
    """Distances (m) from the first and second camera positions to the target's position."""

    from_first: float
    from_second: float
    target_xz: np.ndarray  # target position in the first camera's (x, z) frame
    parallax: float  # angle (rad) between the two rays at the target
    ok: bool


def distance_from_third_image(
    first: PlanarResult,
    second: PlanarResult,
    step: np.ndarray,
    turn: float = 0.0,
    *,
    min_parallax: float = np.radians(2.0),
) -> ThirdImageDistance:
    """Distance to a target after a step of known length, by triangulating two homing directions.

    ``first`` is the homing estimate from the first image (ref) to the target image (cur),
    ``second`` the one from the third image, taken after the robot moved by ``step`` (metres,
    ``(x, z)`` in the first camera's optical frame) and turned by ``turn`` (rad, CCW). The three
    camera centres form a triangle with one known side (the step) and all three directions known,
    so both unknown sides follow (two baselines: first -> target and second -> target meeting at
    the target). A step along the direction to the target gives no parallax: ``ok`` is False
    whenever the rays meet at less than ``min_parallax``, behind a camera, or either estimate
    failed.
    """
    nan = float("nan")
    failed = ThirdImageDistance(nan, nan, np.full(2, nan), 0.0, False)
    if not (first.ok and second.ok and first.moved and second.moved):
        return failed
    d0 = np.asarray(first.direction, dtype=float)
    c, s = np.cos(turn), np.sin(turn)
    x1, z1 = second.direction
    d1 = np.array([c * x1 - s * z1, s * x1 + c * z1])  # second frame -> first frame: R_y(turn)^T
    parallax = float(np.arccos(np.clip(abs(np.dot(d0, d1)), -1.0, 1.0)))
    if parallax < min_parallax:
        return ThirdImageDistance(nan, nan, np.full(2, nan), parallax, False)
    # target = lam0 d0 = step + lam1 d1
    (lam0, lam1), *_ = np.linalg.lstsq(np.column_stack((d0, -d1)), np.asarray(step, dtype=float), rcond=None)
    ok = bool(lam0 > 0 and lam1 > 0)
    return ThirdImageDistance(float(lam0), float(lam1), lam0 * d0, parallax, ok)
