"""The pose graph over keyframes: relative-pose constraints solved by scipy's least squares.

Unknowns: the keyframes' base poses ``X_k = (x, y, theta)`` in the odometry frame; the first stays
where it is (it fixes the frame). Each edge says that keyframe ``b`` was seen at ``z`` (x, y, theta)
in the frame of keyframe ``a``, with information ``W``; its residual is

    e = (X_a^-1 X_b) - z   (angle wrapped),   whitened by L with L^T L = W                  (G1)

Edges: between consecutive keyframes (the tracked motion between them, with a covariance that
grows with the distance and the turn: the tracker's drift), between keyframes that observed the
same landmarks (the motion their estimates agree on, stiff: they were tracked against the same
points), and loop closures (:mod:`maps.slam.loop`: the verified motion and its covariance). A few
hundred keyframes solve in tens of milliseconds (a sparse Jacobian: each edge touches six
unknowns), and the solver runs only when a loop closes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix

from perception.geometry import wrap_angles


@dataclass(frozen=True, slots=True)
class Edge:
    """Keyframe ``b`` at ``measured`` (x, y, theta) in the frame of keyframe ``a``; ``whitener`` L
    (3, 3) with ``L^T L`` the information of the measurement."""

    a: int
    b: int
    measured: np.ndarray
    whitener: np.ndarray


def whitener(covariance: np.ndarray) -> np.ndarray:
    """L with ``L^T L = covariance^-1`` (upper Cholesky factor of the information)."""
    return np.linalg.cholesky(np.linalg.inv(covariance + np.eye(3) * 1e-12)).T


def relative(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Poses ``b`` (N, 3) in the frames of poses ``a`` (N, 3): ``a^-1 b``, angle wrapped."""
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    c, s = np.cos(a[:, 2]), np.sin(a[:, 2])
    dx, dy = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
    return np.column_stack((c * dx + s * dy, -s * dx + c * dy, wrap_angles(b[:, 2] - a[:, 2])))


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pose ``b`` (3,) given in the frame of pose ``a`` (3,), in the world: ``a b``."""
    c, s = math.cos(float(a[2])), math.sin(float(a[2]))
    return np.array([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1],
                     math.remainder(float(a[2] + b[2]), 2.0 * math.pi)])


def optimise(poses: np.ndarray, edges: list[Edge], *, fixed: int = 0) -> np.ndarray:
    """The poses (K, 3) that best satisfy the edges (G1), pose ``fixed`` held where it is."""
    k = len(poses)
    free = np.array([i for i in range(k) if i != fixed], dtype=np.int64)
    if len(free) == 0 or not edges:
        return poses.copy()
    column = np.full(k, -1, dtype=np.int64)
    column[free] = np.arange(len(free))
    a = np.array([e.a for e in edges])
    b = np.array([e.b for e in edges])
    measured = np.array([e.measured for e in edges])
    whiteners = np.array([e.whitener for e in edges])

    def unpack(values: np.ndarray) -> np.ndarray:
        out = poses.copy()
        out[free] = values.reshape(-1, 3)
        return out

    def residuals(values: np.ndarray) -> np.ndarray:
        current = unpack(values)
        error = relative(current[a], current[b]) - measured
        error[:, 2] = wrap_angles(error[:, 2])
        return np.einsum("nij,nj->ni", whiteners, error).ravel()  # (G1)

    sparsity = lil_matrix((3 * len(edges), 3 * len(free)), dtype=np.int8)
    for row, (first, second) in enumerate(zip(a, b, strict=True)):
        for node in (first, second):
            if column[node] >= 0:
                sparsity[3 * row : 3 * row + 3, 3 * column[node] : 3 * column[node] + 3] = 1
    start = poses[free].ravel()
    solution = least_squares(residuals, start, jac_sparsity=sparsity, method="trf", x_scale=1.0, max_nfev=50)
    result = unpack(solution.x)
    result[:, 2] = wrap_angles(result[:, 2])
    return result
