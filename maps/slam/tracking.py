"""The pose update: an iterated, robust EKF step on the stereo observations of known landmarks.

The prior is the odometry prediction ``N(mu, P)`` of the base pose ``X = (x, y, theta)``; each
associated landmark ``L_j`` (position and covariance ``C_j``) observed at ``z_j = (u, v, u_r)``
adds the residual ``r_j = z_j - h_j(X)`` with covariance ``R_j = s^2 I + H_L C_j H_L^T``. The
update minimises

    (X - mu)^T P^-1 (X - mu) + sum_j w_j r_j^T R_j^-1 r_j                                  (T1)

by Gauss-Newton (the iterated EKF: the observation model is linearised again at each iterate),

    (P^-1 + sum_j w_j H_j^T R_j^-1 H_j) dX = -P^-1 (X - mu) + sum_j w_j H_j^T R_j^-1 r_j     (T2)

with Huber weights ``w_j = min(1, k / chi_j)``, ``chi_j^2 = r_j^T R_j^-1 r_j`` (a wrong association
that passed the gate pulls linearly, not quadratically). The posterior covariance is the inverse of
the left-hand matrix of (T2) at the end. The landmarks are taken as known, their uncertainty folded
into ``R_j``: the pose is not estimated jointly with thousands of points (a full EKF-SLAM's cost
grows with their square), and what that leaves out (the landmarks were placed from earlier poses)
is what keyframes and the pose graph of :mod:`maps.slam.graph` handle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from maps.slam.viewpoint import Viewpoint
from perception.camera import StereoRig
from perception.geometry import wrap_angle
from perception.stereo_geometry import project


@dataclass(frozen=True, slots=True)
class PoseUpdate:
    """The updated pose ``mean`` (3,) and ``covariance`` (3, 3), and each observation's final
    ``chi2`` (``r^T R^-1 r``; inf for a landmark that fell behind the camera)."""

    mean: np.ndarray
    covariance: np.ndarray
    chi2: np.ndarray


def _linearise(x: np.ndarray, positions: np.ndarray, position_covariances: np.ndarray, observed: np.ndarray,
               viewpoint: Viewpoint, rig: StereoRig, sigma_px: float) -> tuple[np.ndarray, ...]:
    """Residuals, H_X, R^-1 and chi^2 at pose ``x`` (landmarks behind the camera: chi^2 inf)."""
    p, d_pose, d_point = viewpoint.to_camera(x, positions)
    front = p[:, 0] > 0.05
    h, d_proj = project(rig, np.where(front[:, None], p, 1.0))
    residual = observed - h
    jac_l = d_proj @ d_point  # H_L
    noise = np.eye(3) * sigma_px**2 + jac_l @ position_covariances @ np.swapaxes(jac_l, 1, 2)
    weight_matrix = np.linalg.inv(noise)
    chi2 = np.where(front, np.einsum("ni,nij,nj->n", residual, weight_matrix, residual), np.inf)
    return residual, d_proj @ d_pose, weight_matrix, chi2


def refine_pose(mean: np.ndarray, covariance: np.ndarray, positions: np.ndarray, position_covariances: np.ndarray,
                observed: np.ndarray, viewpoint: Viewpoint, rig: StereoRig, *, sigma_px: float, huber: float = 2.0,
                iterations: int = 6) -> PoseUpdate:
    """Minimise (T1) from the prior ``mean``, ``covariance`` (see the module docstring); landmarks at
    ``positions`` (K, 3) with ``position_covariances`` (K, 3, 3) observed at ``observed`` (K, 3)."""
    prior = np.asarray(mean, dtype=np.float64)
    prior_info = np.linalg.inv(covariance + np.eye(3) * 1e-12)  # a pose known exactly stays put
    x, info = prior.copy(), prior_info
    args = (positions, position_covariances, observed, viewpoint, rig, sigma_px)
    for _ in range(iterations):
        residual, jac, weight_matrix, chi2 = _linearise(x, *args)
        w = np.where(np.isfinite(chi2), np.minimum(1.0, huber / np.sqrt(np.maximum(chi2, 1e-12))), 0.0)  # Huber
        ht_w = np.swapaxes(jac, 1, 2) @ (w[:, None, None] * weight_matrix)  # w H^T R^-1
        info = prior_info + np.einsum("nij,njk->ik", ht_w, jac)
        diff = x - prior
        diff[2] = wrap_angle(float(diff[2]))
        step = np.linalg.solve(info, -prior_info @ diff + np.einsum("nij,nj->i", ht_w, residual))  # (T2)
        x = x + step
        x[2] = wrap_angle(float(x[2]))
        if np.abs(step[:2]).max() < 1e-5 and abs(step[2]) < 1e-6:
            break
    chi2 = _linearise(x, *args)[3]
    cov = np.linalg.inv(info)
    return PoseUpdate(x, (cov + cov.T) / 2.0, chi2)
