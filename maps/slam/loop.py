"""Recognising an old place: a keyframe's features against an older keyframe's, checked geometrically.

Descriptors are matched twice. Without any pose prediction (ratio test and mutual check over all
features, :func:`perception.matching.match_descriptors`): after a long detour the pose may be off
by more than any gate. And guided by the motion the pose graph predicts between the two keyframes,
within that prediction's uncertainty (:func:`guided_matches`: each new point's candidates are the
old points inside the gate of (L2), the nearest descriptor among them wins if clearly better than
the second): the ratio test over all features throws away every corner that has a look-alike
anywhere in the other view (a floor's or a wall's repeated texture), and two views of one place
from a few decimetres and a few tens of degrees apart share few corners to begin with. In a
``rooms`` run the robot came back, 3.3 degrees and 0.26 m off, to a place it had mapped: the
unguided matches gave 18-24 verified inliers per old keyframe (a loop needs 25) and no loop
closed; the guided ones gave 31-40, all agreeing on the same 3.4-degree correction. The two sets
are pooled (a new point matched both ways keeps its guided match). The matches are then verified
in 3-D: both keyframes hold their points in their own base frame, on the same floor, so the same
points must be related by one planar motion ``T = (x, y, theta)`` (the new keyframe's pose in the
old one's frame):

    b_k = Rz(theta) a_k + (x, y, 0)                                                        (L1)

(``a`` the new keyframe's points, ``b`` the old one's). With the predicted motion ``T0`` and its
covariance ``Sigma`` (the two keyframes' poses' uncertainties added), a new point ``a_k`` may be
old point ``b_j`` when

    (b_j - T0 a_k)^T (C_b + R C_a R^T + J Sigma J^T)^-1 (b_j - T0 a_k) <= chi2_3(99 %)        (L2)

(``J`` the Jacobian of ``T a`` in ``T``). RANSAC on pairs of matches (two points fix a planar
motion, :func:`align_planar`: the weighted 2-D Procrustes solution) finds the largest set agreeing
within the points' covariances (the gate of :mod:`maps.slam.association`: chi-square, 3 degrees of
freedom, 99 %, on ``b - T a`` with covariance ``C_b + R C_a R^T``; the height must agree too);
Gauss-Newton on those inliers refines T and gives its covariance. A loop is accepted with at least
``min_inliers`` inliers: far more than chance gives (random matches agree with a motion
fitted to two of them in a handful of cases).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from maps.slam.association import CHI2_3DOF_99
from maps.slam.keyframes import Keyframe
from maps.slam.landmarks import descriptor_distance
from perception.geometry import rot_z
from perception.matching import match_descriptors


@dataclass(frozen=True, slots=True)
class PlanarMatch:
    """A verified motion: ``motion`` (x, y, theta) of (L1), its ``covariance`` (3, 3), the inlier
    match indices into ``a`` and ``b``."""

    motion: np.ndarray
    covariance: np.ndarray
    a: np.ndarray
    b: np.ndarray

    @property
    def inliers(self) -> int:
        return len(self.a)


@dataclass(frozen=True, slots=True)
class LoopClosure:
    """Keyframe ``new`` seen again in keyframe ``old``: the match (``motion``: new in old's frame)."""

    old: int
    new: int
    match: PlanarMatch


def align_planar(a: np.ndarray, b: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """The planar motion (x, y, theta) that best maps points ``a`` onto ``b`` (N, 2 or 3; x, y used)
    in the weighted least-squares sense (L1): the angle from the centred points' cross and dot
    products, then the translation of the centroids."""
    w = np.ones(len(a)) if weights is None else np.asarray(weights, dtype=np.float64)
    ca = (w[:, None] * a[:, :2]).sum(axis=0) / w.sum()
    cb = (w[:, None] * b[:, :2]).sum(axis=0) / w.sum()
    pa, pb = a[:, :2] - ca, b[:, :2] - cb
    theta = math.atan2(float((w * (pa[:, 0] * pb[:, 1] - pa[:, 1] * pb[:, 0])).sum()),
                       float((w * (pa[:, 0] * pb[:, 0] + pa[:, 1] * pb[:, 1])).sum()))
    c, s = math.cos(theta), math.sin(theta)
    t = cb - np.array([c * ca[0] - s * ca[1], s * ca[0] + c * ca[1]])
    return np.array([t[0], t[1], theta])


def _gate(motion: np.ndarray, a: np.ndarray, b: np.ndarray, cov_a: np.ndarray, cov_b: np.ndarray) -> np.ndarray:
    """Squared Mahalanobis distances of ``b - T a`` (the residuals of (L1))."""
    rotation = rot_z(float(motion[2]))
    residual = b - a @ rotation.T - (motion[0], motion[1], 0.0)
    covariance = cov_b + rotation @ cov_a @ rotation.T
    return np.einsum("ni,ni->n", residual, np.linalg.solve(covariance, residual[:, :, None])[:, :, 0])


def _refine(motion: np.ndarray, a: np.ndarray, b: np.ndarray, cov_a: np.ndarray,
            cov_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Newton on (L1) weighted by the points' covariances: the motion and its covariance."""
    info = np.eye(3)
    for _ in range(5):
        rotation = rot_z(float(motion[2]))
        turned = a @ rotation.T
        residual = b - turned - (motion[0], motion[1], 0.0)
        weight = np.linalg.inv(cov_b + rotation @ cov_a @ rotation.T)
        jac = np.zeros((len(a), 3, 3))  # d(T a) / d(x, y, theta)
        jac[:, 0, 0] = jac[:, 1, 1] = 1.0
        jac[:, 0, 2], jac[:, 1, 2] = -turned[:, 1], turned[:, 0]
        jt_w = np.swapaxes(jac, 1, 2) @ weight
        info = np.einsum("nij,njk->ik", jt_w, jac)
        step = np.linalg.solve(info, np.einsum("nij,nj->i", jt_w, residual))
        motion = motion + step
        if np.abs(step).max() < 1e-7:
            break
    covariance = np.linalg.inv(info)
    return motion, (covariance + covariance.T) / 2.0


def ransac_planar(a: np.ndarray, b: np.ndarray, cov_a: np.ndarray, cov_b: np.ndarray, *,
                  rng: np.random.Generator, iterations: int = 200, min_inliers: int = 20,
                  min_spread: float = 0.3) -> PlanarMatch | None:
    """The planar motion of (L1) that most matched points (``a[k]`` <-> ``b[k]``) agree with, refined;
    None with fewer than ``min_inliers``. Sample pairs closer than ``min_spread`` (m) are skipped
    (their angle is ill-defined)."""
    n = len(a)
    if n < max(min_inliers, 2):
        return None
    best: np.ndarray | None = None
    for _ in range(iterations):
        i, j = rng.choice(n, size=2, replace=False)
        if np.hypot(*(a[i, :2] - a[j, :2])) < min_spread:
            continue
        motion = align_planar(a[[i, j]], b[[i, j]])
        inliers = _gate(motion, a, b, cov_a, cov_b) <= CHI2_3DOF_99
        if best is None or inliers.sum() > best.sum():
            best = inliers
    if best is None or best.sum() < min_inliers:
        return None
    for _ in range(2):  # refine on the inliers, then take the inliers of the refined motion
        motion = align_planar(a[best], b[best])
        motion, covariance = _refine(motion, a[best], b[best], cov_a[best], cov_b[best])
        best = _gate(motion, a, b, cov_a, cov_b) <= CHI2_3DOF_99
        if best.sum() < min_inliers:
            return None
    index = np.flatnonzero(best)
    return PlanarMatch(motion, covariance, index, index.copy())


def guided_matches(current: Keyframe, old: Keyframe, motion: np.ndarray, covariance: np.ndarray, *,
                   max_distance: float = 64.0, ratio: float = 0.9) -> tuple[np.ndarray, np.ndarray]:
    """Matches (indices into ``current``'s and ``old``'s points) guided by a predicted ``motion``
    (``current`` in ``old``'s frame, (L1)) with ``covariance`` (3, 3): each current point's
    candidates are the old points inside the gate (L2); the nearest descriptor among them, within
    ``max_distance`` and below ``ratio`` times the second nearest, is its match; an old point
    claimed twice goes to the closer descriptor."""
    none = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))
    if len(current) == 0 or len(old) == 0:
        return none
    rotation = rot_z(float(motion[2]))
    turned = current.points @ rotation.T
    predicted = turned + (motion[0], motion[1], 0.0)
    jac = np.zeros((len(current), 3, 3))  # d(T a) / d(x, y, theta)
    jac[:, 0, 0] = jac[:, 1, 1] = 1.0
    jac[:, 0, 2], jac[:, 1, 2] = -turned[:, 1], turned[:, 0]
    spread = rotation @ current.covariances @ rotation.T + jac @ covariance @ np.swapaxes(jac, 1, 2)
    # the search radius: the gate's long axis with a typical old point's spread (the 90th percentile:
    # the few far, imprecise points would widen every search); the gate itself is exact
    widest = (np.linalg.eigvalsh(spread[:, :2, :2])[:, -1]
              + float(np.percentile(np.linalg.eigvalsh(old.covariances[:, :2, :2])[:, -1], 90)))
    lists = cKDTree(old.points[:, :2]).query_ball_point(predicted[:, :2], np.sqrt(CHI2_3DOF_99 * widest))
    counts = np.array([len(c) for c in lists])
    if counts.sum() == 0:
        return none
    a = np.repeat(np.arange(len(current)), counts)
    b = np.concatenate([np.asarray(c, dtype=np.int64) for c in lists if c])
    residual = old.points[b] - predicted[a]
    gate = spread[a] + old.covariances[b]
    inside = np.einsum("ni,ni->n", residual, np.linalg.solve(gate, residual[:, :, None])[:, :, 0]) <= CHI2_3DOF_99
    a, b = a[inside], b[inside]  # (L2)
    if len(a) == 0:
        return none
    dist = descriptor_distance(current.descriptors[a], old.descriptors[b]).astype(np.float64)
    order = np.lexsort((dist, a))  # by current point, then by descriptor distance
    a, b, dist = a[order], b[order], dist[order]
    first = np.flatnonzero(np.r_[True, a[1:] != a[:-1]])
    has_second = np.r_[first[1:], len(a)] - first > 1
    second = np.where(has_second, dist[np.minimum(first + 1, len(a) - 1)], np.inf)
    best = first[(dist[first] <= max_distance) & (dist[first] < ratio * second)]
    a, b, dist = a[best], b[best], dist[best]
    order = np.lexsort((dist, b))  # an old point claimed twice goes to the closer descriptor
    a, b = a[order], b[order]
    unique = np.r_[True, b[1:] != b[:-1]] if len(b) else np.zeros(0, dtype=bool)
    return a[unique], b[unique]


def _pooled(current: Keyframe, old: Keyframe, kind: str, ratio: float,
            predicted: tuple[np.ndarray, np.ndarray] | None) -> tuple[np.ndarray, np.ndarray]:
    """The unguided matches and, with a prediction, the guided ones; a point matched both ways (in
    either keyframe) keeps its guided match."""
    found = match_descriptors(current.descriptors, old.descriptors, kind, ratio=ratio)
    if predicted is None:
        return found.query, found.train
    a, b = guided_matches(current, old, predicted[0], predicted[1])
    extra = ~np.isin(found.query, a) & ~np.isin(found.train, b)
    return np.concatenate((a, found.query[extra])), np.concatenate((b, found.train[extra]))


def find_loop(current: Keyframe, candidates: list[Keyframe], kind: str, *, rng: np.random.Generator,
              min_matches: int = 30, min_inliers: int = 25, ratio: float = 0.8,
              predicted: list[tuple[np.ndarray, np.ndarray]] | None = None) -> LoopClosure | None:
    """The candidate keyframe that the current one sees again with the most verified inliers (the
    module docstring), or None. ``predicted``: per candidate, the motion the pose graph predicts
    (the current keyframe in the candidate's frame) and its covariance, to guide the matching."""
    best: LoopClosure | None = None
    for k, old in enumerate(candidates):
        query, train = _pooled(current, old, kind, ratio, predicted[k] if predicted is not None else None)
        if len(query) < min_matches:
            continue
        match = ransac_planar(current.points[query], old.points[train],
                              current.covariances[query], old.covariances[train],
                              rng=rng, min_inliers=min_inliers)
        if match is not None and (best is None or match.inliers > best.match.inliers):
            match = PlanarMatch(match.motion, match.covariance, query[match.a], train[match.b])
            best = LoopClosure(old.index, current.index, match)
    return best
