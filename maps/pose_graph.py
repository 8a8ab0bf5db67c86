"""Target poses from every measurement of them: a small pose graph (roadmap paper, "Graph").

Each target's pose relative to the reference is measured once when it is found (the trip from
the homed target back to the homed reference); each edge measures one target relative to another
(two trips, fused by covariance in :mod:`maps.roadmap`). Both are odometry between homed poses,
so they err by the odometry of their trips. The targets' poses that best agree with all of them
(weighted least squares, :func:`scipy.optimize.least_squares`) are more accurate than any one
trip: a target 6 m from the reference, joined by edges to one 3 m away, is placed by both paths.

Model: unknowns are the (x, y, theta) of the targets that have a measurement from the reference
(``priors``); the reference is the origin. Residuals are the differences between predicted and
measured relative poses (heading wrapped), whitened by the measurement's (x, y, theta)
covariance (:meth:`maps.roadmap.EdgeMotion.pose_covariance`: first-order propagation of the
rotate-drive-rotate covariance). Targets without a prior keep their pose and anchor the edges
that reach them.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from scipy.optimize import least_squares

from maps.roadmap import EdgeMotion, Roadmap
from perception.geometry import Pose2D, wrap_angle


def _whitener(motion: EdgeMotion) -> np.ndarray:
    """``W`` with ``W^T W`` the inverse of the motion's (x, y, theta) covariance."""
    covariance = motion.pose_covariance() + np.eye(3) * 1e-12  # a straight drive has rank-2 (x, y)
    return np.linalg.cholesky(np.linalg.inv(covariance)).T


def _difference(predicted: Pose2D, measured: Pose2D) -> np.ndarray:
    return np.array([predicted.x - measured.x, predicted.y - measured.y, wrap_angle(predicted.theta - measured.theta)])


def refine_targets(roadmap: Roadmap, priors: Mapping[str, EdgeMotion]) -> Roadmap:
    """The roadmap with its targets' poses fitted to ``priors`` (reference -> target) and its edges.

    Returns the roadmap unchanged when no target has a prior; images and edges are kept.
    """
    free = [t.name for t in roadmap.targets if t.name in priors]
    if not free:
        return roadmap
    index = {name: k for k, name in enumerate(free)}
    fixed = {t.name: t.pose for t in roadmap.targets if t.name not in index}
    terms: list[tuple[str | None, str, Pose2D, np.ndarray]] = [
        (None, name, priors[name].relative_pose(), _whitener(priors[name])) for name in free]
    terms += [(e.source, e.target, e.motion.relative_pose(), _whitener(e.motion)) for e in roadmap.edges]

    def pose(values: np.ndarray, name: str | None) -> Pose2D:
        if name is None:
            return Pose2D()
        if name in index:
            x, y, theta = values[3 * index[name]: 3 * index[name] + 3]
            return Pose2D(float(x), float(y), float(theta))
        return fixed[name]

    def residuals(values: np.ndarray) -> np.ndarray:
        out = [w @ _difference(pose(values, b).relative_to(pose(values, a)), z) for a, b, z, w in terms]
        return np.concatenate(out)

    start = np.concatenate([roadmap.target(name).pose.as_array() for name in free])
    fitted = least_squares(residuals, start).x
    refined = roadmap
    for name in free:
        refined = refined.with_target(name, pose(fitted, name), roadmap.target(name).image)
    return refined
