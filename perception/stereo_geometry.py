"""A point seen by a rectified stereo pair: triangulation with its uncertainty, and projection back.

A stereo observation of a point is ``(u, v, u_r)``: its pixel in the left image and its column in
the right one (same row in a rectified pair). With the left camera's ``fx, fy, cx, cy``, the right
one's ``cx_r`` and the baseline ``B`` (the right camera at body ``(0, -B, 0)``), a point ``p`` of
the rig's body frame (the left camera's, REP-103: x along the optical axis, y left, z up) is seen at

    u = cx - fx p_y / p_x,   v = cy - fy p_z / p_x,   u_r = cx_r - fx (p_y + B) / p_x      (S1)

and back, with the disparity ``d = u - u_r - (cx - cx_r)``,

    p_x = fx B / d,   p_y = -(u - cx) p_x / fx,   p_z = -(v - cy) p_x / fy                (S2)

The covariance of a triangulated point is the pixel noise propagated through (S2) to first order
(``J diag(s_u^2, s_v^2, s_u^2) J^T``): along the ray it grows with the square of the depth
(``s_Z = Z^2 s_d / (fx B)``), across it linearly. Why pixels and not metres for the residuals of
a localisation: the pixel noise is the same for a point at 1 m and at 6 m, so far points (which
fix the heading well) and near ones (which fix the position) are each weighted as they deserve.
"""

from __future__ import annotations

import numpy as np

from perception.camera import StereoRig


def triangulate(rig: StereoRig, observed: np.ndarray, sigma_px: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Body-frame points (N, 3) of stereo observations ``(u, v, u_r)`` (N, 3), by (S2), and their
    covariances (N, 3, 3) for pixel noise ``sigma_px`` on each coordinate. Disparities must be > 0."""
    obs = np.asarray(observed, dtype=np.float64).reshape(-1, 3)
    left, right = rig.left, rig.right
    fb = left.fx * rig.baseline
    d = obs[:, 0] - obs[:, 2] - (left.cx - right.cx)
    if np.any(d <= 0):
        raise ValueError("stereo observations need a positive disparity")
    x = fb / d  # (S2)
    du, dv = obs[:, 0] - left.cx, obs[:, 1] - left.cy
    points = np.column_stack((x, -du * x / left.fx, -dv * x / left.fy))
    # d(p)/d(u, v, u_r): x depends on u and u_r through d; y and z through x and their own pixel
    dx_dd = -x / d
    jac = np.zeros((len(obs), 3, 3))
    jac[:, 0, 0], jac[:, 0, 2] = dx_dd, -dx_dd
    jac[:, 1, 0] = -x / left.fx - du / left.fx * dx_dd
    jac[:, 1, 2] = du / left.fx * dx_dd
    jac[:, 2, 0] = -dv / left.fy * dx_dd
    jac[:, 2, 1] = -x / left.fy
    jac[:, 2, 2] = dv / left.fy * dx_dd
    covariance = sigma_px**2 * jac @ np.swapaxes(jac, 1, 2)
    return points, covariance


def project(rig: StereoRig, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stereo observations ``(u, v, u_r)`` (N, 3) of body-frame points (N, 3) by (S1), and the
    Jacobians (N, 3, 3) of the observation with respect to the point. Points must lie in front
    (``p_x > 0``)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    left, right, b = rig.left, rig.right, rig.baseline
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    inv = 1.0 / x
    observed = np.column_stack((left.cx - left.fx * y * inv, left.cy - left.fy * z * inv,
                                right.cx - right.fx * (y + b) * inv))  # (S1)
    jac = np.zeros((len(p), 3, 3))
    jac[:, 0, 0], jac[:, 0, 1] = left.fx * y * inv**2, -left.fx * inv
    jac[:, 1, 0], jac[:, 1, 2] = left.fy * z * inv**2, -left.fy * inv
    jac[:, 2, 0], jac[:, 2, 1] = right.fx * (y + b) * inv**2, -right.fx * inv
    return observed, jac
