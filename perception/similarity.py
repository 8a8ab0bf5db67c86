"""The ``delta_t`` dissimilarity of tracked landmarks (LT-map paper, eq. 1, as written).

``delta_t`` says how far the current view has drifted from a viewframe: the mean robust cost of
how far each tracked landmark's current, rotation-compensated bearing ``l'`` has turned from its
bearing ``l`` in the viewframe. A new viewframe is made when ``delta_t`` exceeds a threshold;
during route following the robot switches to the next viewframe when it falls below it.

**Eq. 1** applies the Pseudo-Huber cost to the cosine distance ``x = 1 - l^T l'``:
``2 b^2 (sqrt(1 + (x / b)^2) - 1)``. For a bearing change ``theta``, ``x = 1 - cos(theta) =
2 sin^2(theta / 2)`` (computed as ``|l - l'|^2 / 2``, exact near 0), so the cost grows like
``theta^4 / 4`` while ``x << b`` (bearing noise weighs almost nothing) and like ``b theta^2``
beyond (quadratic in the angle, as least squares); it never exceeds about ``4 b`` (``x <= 2``).
How it is read here:

- **b.** The paper gives no value: :data:`DEFAULT_SCALE` is the cosine distance of 2 degrees
  (6.09e-4), where the cost turns from quartic to quadratic in the angle. A larger ``b`` keeps
  the quartic part longer and lets the few landmarks that moved most dominate the mean even
  more (a 20 deg change costs 67 thresholds of 3 deg with this ``b``, 1300 with ``b`` = 0.035);
  no ``b`` makes eq. 1 cheaper than quadratic in the angle, since ``x`` itself is.
- **Threshold.** The default (:func:`default_threshold`) is the cost of a 3 deg bearing change
  (:data:`THRESHOLD_ANGLE`, 1.085e-6), the change the earlier angle form's 1e-3 rad^2 stood for.
  Thresholds and fractions of them are best thought of as bearing changes:
  :func:`cost_of_angle`, :func:`angle_of_cost` and :func:`scaled` translate.
- **Normalisation.** The paper does not fix it; the mean (not the sum) is used so that the
  threshold does not depend on how many landmarks are tracked.

The form used before (the Pseudo-Huber cost of the angle itself, delta 2 deg: quadratic near 0,
linear beyond) grows like ``theta^2 / 2`` near 0, about 900 times eq. 1 at 3 degrees; its
thresholds are converted by :func:`angle_form_threshold_angle` (map files written with it).
"""

from __future__ import annotations

import math

import numpy as np

DEFAULT_SCALE = 1.0 - math.cos(math.radians(2.0))  # eq. 1's b: the cosine distance of 2 deg (6.09e-4)
THRESHOLD_ANGLE = math.radians(3.0)  # the default threshold: the cost of a 3 deg bearing change
ANGLE_FORM_DELTA = math.radians(2.0)  # the earlier form's Pseudo-Huber delta (rad), for old thresholds


def _pseudo_huber(scale: float, r: np.ndarray) -> np.ndarray:
    """``scale^2 (sqrt(1 + (r / scale)^2) - 1)``, written ``r^2 / (sqrt(1 + (r / scale)^2) + 1)``
    so that it stays exact for tiny ``r`` (no cancellation)."""
    r = np.asarray(r, dtype=np.float64)
    return r * r / (np.sqrt(1.0 + (r / scale) ** 2) + 1.0)


def _units(vectors: np.ndarray) -> np.ndarray:
    v = np.asarray(vectors, dtype=np.float64).reshape(-1, 3)
    return v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-300)


def bearing_angles(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angles (rad) between corresponding unit bearings (N x 3 each), accurate near 0 and pi."""
    a = np.asarray(a, dtype=np.float64).reshape(-1, 3)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 3)
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))


def cosine_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``1 - a^T b`` of corresponding bearings (normalised first), as ``|a - b|^2 / 2``: exact near 0."""
    return 0.5 * np.sum((_units(a) - _units(b)) ** 2, axis=1)


def eq1_costs(x: np.ndarray, scale: float = DEFAULT_SCALE) -> np.ndarray:
    """Eq. 1's summand for cosine distances ``x = 1 - l^T l'``: ``2 b^2 (sqrt(1 + (x / b)^2) - 1)``."""
    return 2.0 * _pseudo_huber(scale, x)  # eq. 1


def cost_of_angle(angle: float, scale: float = DEFAULT_SCALE) -> float:
    """Eq. 1's cost of a bearing change of ``angle`` rad."""
    return float(eq1_costs(np.array(2.0 * math.sin(angle / 2.0) ** 2), scale))


def angle_of_cost(cost: float, scale: float = DEFAULT_SCALE) -> float:
    """The bearing change (rad) whose eq. 1 cost is ``cost`` (pi when none costs that much)."""
    x = scale * math.sqrt((1.0 + cost / (2.0 * scale * scale)) ** 2 - 1.0)
    return 2.0 * math.asin(math.sqrt(x / 2.0)) if x < 2.0 else math.pi


def scaled(threshold: float, factor: float, scale: float = DEFAULT_SCALE) -> float:
    """The cost of ``factor`` times the bearing change whose cost is ``threshold``: a fraction of
    a threshold taken of the change it stands for (eq. 1 is quartic near 0: a quarter of the cost
    is 0.7 of the change)."""
    return cost_of_angle(factor * angle_of_cost(threshold, scale), scale)


def default_threshold(scale: float = DEFAULT_SCALE) -> float:
    """The eq. 1 threshold viewframes are made at by default: the cost of :data:`THRESHOLD_ANGLE`."""
    return cost_of_angle(THRESHOLD_ANGLE, scale)


def angle_form_threshold_angle(threshold: float) -> float:
    """The bearing change (rad) a threshold of the earlier form stood for (the Pseudo-Huber cost
    of the angle, delta 2 deg; 1e-3 rad^2 is 3.04 deg)."""
    d = ANGLE_FORM_DELTA
    return min(math.pi, d * math.sqrt((1.0 + threshold / (d * d)) ** 2 - 1.0))


def delta_t(
    ref: np.ndarray,
    cur: np.ndarray,
    *,
    rotation: np.ndarray | None = None,
    scale: float = DEFAULT_SCALE,
    weights: np.ndarray | None = None,
) -> float:
    """Eq. 1: the mean cost of the bearing changes of the tracked landmarks.

    ``ref`` are the viewframe bearings, ``cur`` the current ones (N x 3); ``rotation`` (3 x 3,
    ref -> current, e.g. from Z-infinity) is removed from ``cur`` first, so turning on the spot
    leaves ``delta_t`` at 0. Returns ``inf`` when no landmark is tracked (nothing is similar).
    """
    cur = np.asarray(cur, dtype=np.float64).reshape(-1, 3)
    if rotation is not None:
        cur = cur @ np.asarray(rotation)  # row form of R^T l'
    if len(cur) == 0:
        return float("inf")
    return float(np.average(eq1_costs(cosine_distances(ref, cur), scale), weights=weights))  # eq. 1
