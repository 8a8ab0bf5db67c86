"""Which feature of a frame is which landmark: the gate on the predicted observation, then the descriptor.

Every landmark in front of the camera is projected at the predicted pose (:mod:`maps.slam.viewpoint`,
then (S1) of :mod:`perception.stereo_geometry`) to a predicted stereo observation ``h = (u, v, u_r)``
with the innovation covariance

    S = H_X P H_X^T + H_L C H_L^T + s^2 I                                                   (A1)

(``P`` the pose covariance, ``C`` the landmark's, ``H_X`` and ``H_L`` the Jacobians of ``h`` with
respect to the pose and to the landmark, ``s`` the pixel noise). A feature observed at ``z`` is a
candidate for the landmark when it passes the gate

    (z - h)^T S^-1 (z - h) <= g                                                             (A2)

(``g`` = 11.34 by default: chi-square with 3 degrees of freedom at 99 %). Comparing ``u_r`` too
checks the depth: a corner of the wall behind a table edge is not the table's. Among a landmark's
candidates, the closest descriptor is taken when it is within ``max_distance`` and clearly
better than the second (``ratio``, among the gated candidates only: two look-alikes far apart in
the image are no ambiguity here); a feature claimed by several landmarks goes to the closest
descriptor. The pixel search uses a k-d tree of the features (radius from the largest axis of S),
so the cost grows with the number of candidates, not with landmarks times features.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from maps.slam.landmarks import LandmarkMap, descriptor_distance
from maps.slam.viewpoint import Viewpoint
from perception.camera import StereoRig
from perception.stereo_geometry import project

CHI2_3DOF_99 = 11.34  # the gate (A2): chi-square, 3 degrees of freedom, 99 %


@dataclass(frozen=True, slots=True)
class Prediction:
    """The landmarks predicted in view: their ``rows`` in the map, predicted observations ``observed``
    (M, 3), the Jacobians of the observation (M, 3, 3) with respect to the pose and to the landmark,
    and the innovation covariances ``covariance`` (M, 3, 3) of (A1)."""

    rows: np.ndarray
    observed: np.ndarray
    jac_pose: np.ndarray
    jac_point: np.ndarray
    covariance: np.ndarray

    def __len__(self) -> int:
        return len(self.rows)


@dataclass(frozen=True, slots=True)
class Association:
    """Pairs: ``landmark[k]`` (an index into the :class:`Prediction`) is feature ``feature[k]``."""

    landmark: np.ndarray
    feature: np.ndarray

    def __len__(self) -> int:
        return len(self.landmark)


def predict(landmarks: LandmarkMap, pose: np.ndarray, pose_covariance: np.ndarray, viewpoint: Viewpoint,
            rig: StereoRig, *, sigma_px: float, depth: tuple[float, float], margin: float = 8.0) -> Prediction:
    """The landmarks of the map whose depth lies in ``depth`` (min, max, m) and whose predicted pixel
    is inside the image by ``margin`` px, with their predicted observations and (A1)."""
    empty = np.zeros((0, 3, 3))
    if len(landmarks) == 0:
        return Prediction(np.zeros(0, dtype=np.int64), np.zeros((0, 3)), empty, empty, empty)
    p, d_pose, d_point = viewpoint.to_camera(pose, landmarks.positions)
    ahead = np.flatnonzero((p[:, 0] > depth[0]) & (p[:, 0] < depth[1]))
    observed, d_proj = project(rig, p[ahead])
    inside = ((observed[:, 0] >= margin) & (observed[:, 0] <= rig.width - 1 - margin)
              & (observed[:, 1] >= margin) & (observed[:, 1] <= rig.height - 1 - margin))
    rows, observed, d_proj = ahead[inside], observed[inside], d_proj[inside]
    jac_pose = d_proj @ d_pose[rows]
    jac_point = d_proj @ d_point[rows]
    covariance = (jac_pose @ pose_covariance @ np.swapaxes(jac_pose, 1, 2)
                  + jac_point @ landmarks.covariances[rows] @ np.swapaxes(jac_point, 1, 2)
                  + np.eye(3) * sigma_px**2)  # (A1)
    return Prediction(rows, observed, jac_pose, jac_point, covariance)


def gate_distance(innovation: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """Squared Mahalanobis distances ``nu^T S^-1 nu`` of innovations (K, 3) with covariances (K, 3, 3): (A2)."""
    nu = np.asarray(innovation, dtype=np.float64).reshape(-1, 3)
    return np.einsum("ni,ni->n", nu, np.linalg.solve(covariance, nu[:, :, None])[:, :, 0])


def associate(prediction: Prediction, landmark_descriptors: np.ndarray, observed: np.ndarray,
              descriptors: np.ndarray, *, gate: float = CHI2_3DOF_99, max_distance: float = 64.0,
              ratio: float = 0.9) -> Association:
    """Features (``observed`` (N, 3) stereo observations, ``descriptors`` (N, D)) paired with the
    predicted landmarks (``landmark_descriptors`` (M, D), in the prediction's order), as the module
    docstring says."""
    none = Association(np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))
    if len(prediction) == 0 or len(observed) == 0:
        return none
    reach = np.sqrt(gate * np.linalg.eigvalsh(prediction.covariance[:, :2, :2])[:, -1])  # px: the ellipse's long axis
    lists = cKDTree(observed[:, :2]).query_ball_point(prediction.observed[:, :2], reach)
    counts = np.array([len(c) for c in lists])
    if counts.sum() == 0:
        return none
    lm = np.repeat(np.arange(len(prediction)), counts)
    ft = np.concatenate([np.asarray(c, dtype=np.int64) for c in lists if c])
    inside = gate_distance(observed[ft] - prediction.observed[lm], prediction.covariance[lm]) <= gate  # (A2)
    lm, ft = lm[inside], ft[inside]
    if len(lm) == 0:
        return none
    dist = descriptor_distance(landmark_descriptors[lm], descriptors[ft]).astype(np.float64)
    order = np.lexsort((dist, lm))  # by landmark, then by descriptor distance
    lm, ft, dist = lm[order], ft[order], dist[order]
    first = np.flatnonzero(np.r_[True, lm[1:] != lm[:-1]])  # each landmark's best candidate
    has_second = np.r_[first[1:], len(lm)] - first > 1
    second = np.where(has_second, dist[np.minimum(first + 1, len(lm) - 1)], np.inf)
    good = (dist[first] <= max_distance) & (dist[first] < ratio * second)
    best = first[good]
    if len(best) == 0:
        return none
    lm, ft, dist = lm[best], ft[best], dist[best]
    order = np.lexsort((dist, ft))  # a feature claimed twice goes to the closer descriptor
    lm, ft = lm[order], ft[order]
    unique = np.r_[True, ft[1:] != ft[:-1]]
    return Association(lm[unique], ft[unique])
