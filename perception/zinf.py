"""Z-infinity: rotation and direction of translation between two sets of landmark bearings.

Jäger, Mair et al., IROS 2013 (docs/design.md, method 1). ``ref`` and ``cur`` are N x 3 unit
bearings of the same landmarks seen from a reference place (a viewframe) and from the current
place, in the camera body frame (x forward, y left, z up).

1. Far landmarks are translation-invariant: ``l'_i = R l_i``. RANSAC on 2-point minimal sets
   (SVD / Kabsch) separates them from near landmarks and mismatches; a hypothesis whose inlier
   set leaves an angular gap (in azimuth) larger than 180 degrees is rejected, because far
   landmarks on one side only cannot tell a rotation from a translation.
2. The near landmarks are de-rotated (``l''_i = R^T l'_i``); each gives ``m_i = l''_i x l_i``,
   normal to the epipolar plane that contains the translation, so the translation is the
   eigenvector of the smallest eigenvalue of ``M = sum w_i m_i m_i^T`` (eqs. 2-5), made robust
   here with a 2-point RANSAC (``t = m_a x m_b``) before the eigen-decomposition.
3. The sign comes from eq. 6: moving along ``t``, landmarks move away from ``t``.

Conventions of the result: ``rotation`` maps ref-frame bearings into the current frame;
``translation`` is the unit direction of the displacement from the reference place to the
current place, expressed in the REFERENCE frame; :attr:`ZinfResult.home_direction` is the
direction back to the reference place in the CURRENT frame (what homing steers along).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum

import numpy as np
from scipy.spatial.transform import Rotation

SeedLike = int | np.random.Generator | None


class ZinfStatus(StrEnum):
    """Outcome of :func:`estimate_motion`; only ``OK`` carries a translation."""

    OK = "ok"
    NOT_ENOUGH_LANDMARKS = "not_enough_landmarks"  # fewer correspondences than min_landmarks
    NO_ROTATION = "no_rotation"  # no far set large enough with azimuth gaps <= max_gap
    NO_TRANSLATION = "no_translation"  # rotation found, too few consistent near landmarks


@dataclass(frozen=True, slots=True)
class ZinfResult:
    """Motion between a reference landmark set and the current one.

    ``far`` marks the translation-invariant inliers that gave the rotation, ``inliers`` the far
    ones plus the near landmarks consistent with the translation. ``confidence`` in [0, 1] is
    ``1 - lambda_1 / lambda_2`` of ``M`` (how sharply the smallest eigenvector is determined),
    0 unless the status is OK. ``rotation`` is the identity and ``translation`` zero when they
    could not be estimated (see ``status``), never a guess.
    """

    rotation: np.ndarray
    translation: np.ndarray
    far: np.ndarray
    inliers: np.ndarray
    confidence: float
    status: ZinfStatus

    @property
    def ok(self) -> bool:
        """Both rotation and translation were estimated."""
        return self.status is ZinfStatus.OK

    @property
    def rotation_ok(self) -> bool:
        """The rotation is valid (also when there was no measurable translation)."""
        return self.status in (ZinfStatus.OK, ZinfStatus.NO_TRANSLATION)

    @property
    def yaw(self) -> float:
        """Rotation about the body z axis (rad, counter-clockwise) from ref to current frame.

        A landmark that was straight ahead in the reference frame appears at azimuth ``yaw`` in
        the current frame, i.e. the robot turned by ``-yaw``.
        """
        return float(np.arctan2(self.rotation[1, 0], self.rotation[0, 0]))

    @property
    def home_direction(self) -> np.ndarray:
        """Unit direction from the current place back to the reference place, current frame."""
        return -(self.rotation @ self.translation)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-15)


def largest_azimuth_gap(bearings: np.ndarray) -> float:
    """Largest gap (rad) between consecutive azimuths of ``bearings`` around the z axis; 2 pi if < 2."""
    if len(bearings) < 2:
        return 2.0 * np.pi
    az = np.sort(np.arctan2(bearings[:, 1], bearings[:, 0]))
    gaps = np.diff(np.concatenate((az, az[:1] + 2.0 * np.pi)))
    return float(gaps.max())


def _kabsch_batch(ref_pairs: np.ndarray, cur_pairs: np.ndarray) -> np.ndarray:
    """Rotations R_k minimising sum |cur - R ref|^2 for K point sets (K x P x 3) by batched SVD."""
    H = np.einsum("kpi,kpj->kij", cur_pairs, ref_pairs)
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(U @ Vt))
    U[:, :, 2] *= d[:, None]
    return U @ Vt


def _samples(rng: np.random.Generator, n: int, count: int) -> np.ndarray:
    """``count`` random pairs of distinct indices in [0, n)."""
    a = rng.integers(0, n, size=count)
    b = (a + rng.integers(1, n, size=count)) % n
    return np.column_stack((a, b))


def _adaptive(
    hypotheses: Callable[[int], tuple[np.ndarray, np.ndarray]], n: int, iterations: int, *, first: int = 40
) -> tuple[np.ndarray, np.ndarray]:
    """Batched RANSAC hypotheses: a first batch, then as many more as the standard stopping rule
    ``log(1 - 0.999) / log(1 - w^2)`` asks for (w: best inlier ratio so far), ``iterations`` at most.

    ``hypotheses(count)`` returns ``(models, inlier_masks)`` for ``count`` random 2-point samples.
    """
    models, masks = hypotheses(min(first, iterations))
    best = masks.sum(axis=1).max() / n if len(masks) else 0.0
    if best >= 1.0:
        return models, masks
    needed = iterations if best <= 0.0 else int(np.ceil(np.log(1e-3) / np.log1p(-(best**2))))
    extra = min(iterations, needed) - min(first, iterations)
    if extra > 0:
        more_models, more_masks = hypotheses(extra)
        models, masks = np.concatenate((models, more_models)), np.concatenate((masks, more_masks))
    return models, masks


def estimate_rotation(
    ref: np.ndarray,
    cur: np.ndarray,
    weights: np.ndarray,
    *,
    rng: np.random.Generator,
    threshold: float,
    iterations: int,
    max_gap: float,
    min_far: int,
    max_gap_checks: int = 64,
) -> tuple[np.ndarray, np.ndarray] | None:
    """RANSAC over 2-point sets for the rotation of the far landmarks; None if no valid set.

    Returns ``(R, far_mask)``. Hypotheses are ranked by the weighted inlier score; the best one
    whose inlier set has at least ``min_far`` landmarks and no azimuth gap above ``max_gap`` (among
    the ``max_gap_checks`` best) is refined by a weighted Kabsch fit (scipy) on its inliers, twice.
    """
    n = len(ref)
    cos_thr = np.cos(threshold)
    # cos of the angle between R_k l_i and l'_i for every hypothesis k, as one (K x 9) @ (9 x N) product
    outer = (cur[:, :, None] * ref[:, None, :]).reshape(n, 9).T

    def hypotheses(count: int) -> tuple[np.ndarray, np.ndarray]:
        pairs = _samples(rng, n, count)
        ra, rb = ref[pairs[:, 0]], ref[pairs[:, 1]]
        separated = np.abs(np.einsum("ki,ki->k", ra, rb)) < np.cos(np.radians(5.0))  # skip near-collinear pairs
        Rs = _kabsch_batch(ref[pairs[separated]], cur[pairs[separated]])
        return Rs, (Rs.reshape(-1, 9) @ outer) > cos_thr

    Rs, inlier_sets = _adaptive(hypotheses, n, iterations)
    if len(Rs) == 0:
        return None
    scores = inlier_sets.astype(float) @ weights
    counts = inlier_sets.sum(axis=1)
    order = [k for k in np.argsort(-scores, kind="stable") if counts[k] >= min_far]
    for k in order[:max_gap_checks]:
        mask = inlier_sets[k]
        if largest_azimuth_gap(ref[mask]) > max_gap:
            continue  # far landmarks on one side only: rotation not separable from translation
        R = Rs[k]
        for _ in range(2):  # local optimisation on the inliers
            rot, _ = Rotation.align_vectors(cur[mask], ref[mask], weights=weights[mask])
            R = rot.as_matrix()
            new_mask = (cur * (ref @ R.T)).sum(axis=1) > cos_thr
            if new_mask.sum() < min_far or largest_azimuth_gap(ref[new_mask]) > max_gap:
                break
            mask = new_mask
        return R, mask
    return None


def estimate_translation(
    ref: np.ndarray,
    derotated: np.ndarray,
    weights: np.ndarray,
    *,
    rng: np.random.Generator,
    threshold: float,
    iterations: int,
    min_near: int,
) -> tuple[np.ndarray, np.ndarray, float] | None:
    """Direction of translation from near landmarks (already de-rotated); None if too few agree.

    Returns ``(t, inlier_mask, confidence)`` with ``t`` in the reference frame.
    """
    m = np.cross(derotated, ref)  # eq. 2: m_i = l'_i x l_i, normal of the epipolar plane
    norms = np.linalg.norm(m, axis=1)
    m_hat = m / np.maximum(norms, 1e-15)[:, None]
    n = len(ref)
    if n < max(min_near, 2):
        return None
    sin_thr = np.sin(threshold)

    def residuals(ts: np.ndarray) -> np.ndarray:
        """Angle-like distance of each landmark pair from the epipolar plane of each t (K x N).

        ``|t . m_i| / sqrt(|t x l_i|^2 + |t x l''_i|^2)``: the coplanarity error measured on the
        bearings themselves (a spherical Sampson distance), not on the ill-conditioned direction
        of a short ``m_i``.
        """
        along = (ts @ ref.T) ** 2 + (ts @ derotated.T) ** 2
        return np.abs(ts @ m.T) / np.sqrt(np.maximum(2.0 - along, 1e-12))

    # a landmark whose parallax is within twice the threshold fits almost any t: it may refine M
    # (where |m_i|^2 weighs it little) but neither proposes hypotheses nor counts towards min_near
    informative = np.flatnonzero(norms > np.sin(2.0 * threshold))
    if len(informative) < max(min_near, 2):
        return None

    def hypotheses(count: int) -> tuple[np.ndarray, np.ndarray]:
        pairs = informative[_samples(rng, len(informative), count)]
        hyps = np.cross(m_hat[pairs[:, 0]], m_hat[pairs[:, 1]])  # t is normal to both planes' normals
        hyp_norm = np.linalg.norm(hyps, axis=1)
        good = hyp_norm > 1e-6
        hyps = hyps[good] / hyp_norm[good, None]
        return hyps, residuals(hyps) < sin_thr

    hyps, inlier_sets = _adaptive(hypotheses, len(informative), iterations)
    if len(hyps) == 0:
        return None
    best = int(np.argmax(inlier_sets[:, informative].astype(float) @ weights[informative]))
    mask = inlier_sets[best]
    t = hyps[best]
    for _ in range(2):  # refine: eqs. 3-5 on the inliers, then re-select
        if mask[informative].sum() < min_near:
            return None
        w = weights[mask]
        M = (m[mask] * w[:, None]).T @ m[mask]  # eq. 3: M = sum w_i m_i m_i^T
        eigenvalues, eigenvectors = np.linalg.eigh(M)  # ascending
        t = eigenvectors[:, 0]  # eqs. 4-5: smallest eigenvalue's eigenvector
        mask = residuals(t[None, :])[0] < sin_thr
    # eq. 6: the sign makes landmarks move away from the direction of travel
    shift = (ref - derotated) @ t
    if np.sum(weights[mask] * shift[mask]) < 0.0:
        t = -t
        shift = -shift
    mask &= shift > -sin_thr  # cheirality: a landmark moving towards t is a mismatch
    if mask[informative].sum() < min_near:
        return None
    confidence = float(1.0 - eigenvalues[0] / max(eigenvalues[1], 1e-300))
    return t, mask, float(np.clip(confidence, 0.0, 1.0))


def estimate_motion(
    ref: np.ndarray,
    cur: np.ndarray,
    weights: np.ndarray | None = None,
    *,
    rng: SeedLike = 0,
    far_threshold: float = np.radians(1.0),
    near_threshold: float = np.radians(1.0),
    iterations: int = 200,
    max_gap: float = np.pi,
    min_landmarks: int = 8,
    min_far: int = 8,
    min_near: int = 5,
) -> ZinfResult:
    """Z-infinity motion estimate between corresponding landmark bearings ``ref`` -> ``cur``.

    ``weights`` (N, optional, >= 0) weigh each landmark in the RANSAC scores, the rotation fit
    and ``M`` (eq. 3). ``far_threshold`` is the angle (rad) under which a landmark counts as
    unmoved after rotation; ``near_threshold`` the angle by which a near landmark may miss its
    epipolar plane. ``max_gap`` is the largest azimuth gap allowed in the far set (180 degrees in
    the paper: a pinhole view narrower than that never gives a rotation). ``rng`` seeds the
    RANSAC sampling: the result is deterministic for a given seed.
    """
    ref = _unit(np.asarray(ref, dtype=np.float64).reshape(-1, 3))
    cur = _unit(np.asarray(cur, dtype=np.float64).reshape(-1, 3))
    if ref.shape != cur.shape:
        raise ValueError(f"ref and cur must have the same shape, got {ref.shape} and {cur.shape}")
    n = len(ref)
    w = np.ones(n) if weights is None else np.asarray(weights, dtype=np.float64).reshape(n)
    if np.any(w < 0) or not np.all(np.isfinite(w)):
        raise ValueError("weights must be finite and non-negative")
    generator = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    none = np.zeros(n, dtype=bool)

    def failed(status: ZinfStatus) -> ZinfResult:
        return ZinfResult(np.eye(3), np.zeros(3), none, none.copy(), 0.0, status)

    if n < max(min_landmarks, 2):
        return failed(ZinfStatus.NOT_ENOUGH_LANDMARKS)
    found = estimate_rotation(
        ref, cur, w, rng=generator, threshold=far_threshold, iterations=iterations, max_gap=max_gap,
        min_far=min_far,
    )
    if found is None:
        return failed(ZinfStatus.NO_ROTATION)
    R, far = found
    near_idx = np.flatnonzero(~far)
    derotated = cur[near_idx] @ R  # row form of R^T l'_i
    moved = estimate_translation(
        ref[near_idx], derotated, w[near_idx], rng=generator, threshold=near_threshold,
        iterations=iterations, min_near=min_near,
    )
    if moved is None:
        return ZinfResult(R, np.zeros(3), far, far.copy(), 0.0, ZinfStatus.NO_TRANSLATION)
    t, near_mask, confidence = moved
    inliers = far.copy()
    inliers[near_idx[near_mask]] = True
    return ZinfResult(R, t, far, inliers, confidence, ZinfStatus.OK)
