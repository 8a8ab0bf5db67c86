"""The ``delta_t`` dissimilarity of tracked landmarks (LT-map paper, eq. 1).

``delta_t`` says how far the current view has drifted from a viewframe: the mean Pseudo-Huber
cost of the angles between each tracked landmark's bearing in the viewframe and its current,
rotation-compensated bearing. Pseudo-Huber is quadratic for small angles (noise) and linear
for large ones, so a few badly tracked landmarks cannot dominate. A new viewframe is made when
``delta_t`` exceeds a threshold; during route following the robot switches to the next viewframe
when it falls below it. The paper does not fix the normalisation; the mean (not the sum) is used
here so that the threshold does not depend on how many landmarks are tracked.
"""

from __future__ import annotations

import numpy as np
from scipy.special import pseudo_huber

DEFAULT_SCALE = np.radians(2.0)  # Pseudo-Huber delta: angles above ~2 deg count linearly


def bearing_angles(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angles (rad) between corresponding unit bearings (N x 3 each), accurate near 0 and pi."""
    a = np.asarray(a, dtype=np.float64).reshape(-1, 3)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 3)
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))


def delta_t(
    ref: np.ndarray,
    cur: np.ndarray,
    *,
    rotation: np.ndarray | None = None,
    scale: float = DEFAULT_SCALE,
    weights: np.ndarray | None = None,
) -> float:
    """Eq. 1: mean Pseudo-Huber cost of the bearing changes of the tracked landmarks (rad^2).

    ``ref`` are the viewframe bearings, ``cur`` the current ones (N x 3); ``rotation`` (3 x 3,
    ref -> current, e.g. from Z-infinity) is removed from ``cur`` first, so turning on the spot
    leaves ``delta_t`` at 0. Returns ``inf`` when no landmark is tracked (nothing is similar).
    """
    cur = np.asarray(cur, dtype=np.float64).reshape(-1, 3)
    if rotation is not None:
        cur = cur @ np.asarray(rotation)  # row form of R^T l'
    if len(cur) == 0:
        return float("inf")
    costs = pseudo_huber(scale, bearing_angles(ref, cur))  # eq. 1
    return float(np.average(costs, weights=weights))
