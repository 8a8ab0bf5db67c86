"""Interest edges (algorithm 3, eq. 2): which depth jumps between image neighbours are worth watching.

``r = p_c / p_f`` with ``p_c``, ``p_f`` the 3-D distances from the camera to the edge's closer and
farther point, and ``phi`` the angle between the robot's heading (its direction of travel) and the
direction, in plan, from the camera to the closer point. An edge ahead (phi <= pi/6) with a large
depth jump (r <= 0.5) is watched now: driving past it opens the view behind its closer point, and
the gaze control follows it from there up to 90 degrees (eq. 3, :mod:`maps.exploration.gaze`).
``r >= 0.95`` (no depth jump left to look behind) makes an edge never interesting again, for good;
everything else is watch later. The paper names no state for a large depth jump off to the side
(r <= 0.5, phi > pi/6): it is *watch later*, since turning towards it makes it *watch now*. Edges
are re-evaluated from the current pose (:func:`reevaluate_interest`) only within ``max_range``: r
tends to 1 with distance, and an edge should not be retired just because the robot went elsewhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from scipy.spatial import cKDTree

from maps.exploration.grid import ExplorationMap
from perception.geometry import wrap_angles


class Interest(IntEnum):
    """The interest state of an edge between two image neighbours (eq. 2)."""

    WATCH_NOW = 1
    WATCH_LATER = 2
    NEVER = 3  # never interesting again: sticky


@dataclass(frozen=True, slots=True)
class InterestParams:
    """Thresholds of eq. 2 (the paper's values)."""

    r_now: float = 0.5
    r_never: float = 0.95
    phi_now: float = math.pi / 6.0


def edge_geometry(
    a: np.ndarray, b: np.ndarray, eye: np.ndarray, heading: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``r``, ``phi`` of eq. 2 for edges a-b seen from ``eye``, and whether ``a`` is the closer point."""
    da = np.linalg.norm(np.asarray(a, dtype=np.float64).reshape(-1, 3) - eye, axis=1)
    db = np.linalg.norm(np.asarray(b, dtype=np.float64).reshape(-1, 3) - eye, axis=1)
    a_closer = da <= db
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.where(a_closer, da, db) / np.maximum(np.where(a_closer, db, da), 1e-12)  # eq. 2: r = p_c / p_f
    closer = np.where(a_closer[:, None], np.reshape(a, (-1, 3)), np.reshape(b, (-1, 3)))
    phi = np.abs(wrap_angles(np.arctan2(closer[:, 1] - eye[1], closer[:, 0] - eye[0]) - heading))  # eq. 2: phi
    return r, phi, a_closer


def classify_interest(r: np.ndarray, phi: np.ndarray, params: InterestParams = InterestParams()) -> np.ndarray:
    """Interest state from r and phi (eq. 2): r <= 0.5 and phi <= pi/6 now, r >= 0.95 never, else later."""
    r, phi = np.asarray(r, dtype=np.float64), np.asarray(phi, dtype=np.float64)
    state = np.full(r.shape, Interest.WATCH_LATER, dtype=np.uint8)
    state[(r <= params.r_now) & (phi <= params.phi_now)] = Interest.WATCH_NOW
    state[r >= params.r_never] = Interest.NEVER
    return state


def reevaluate_interest(
    m: ExplorationMap,
    eye: np.ndarray,
    heading: float,
    params: InterestParams = InterestParams(),
    max_range: float = 8.0,
) -> ExplorationMap:
    """The map with every edge within ``max_range`` of ``eye`` re-classified from there (NEVER stays)."""
    if len(m.edges) == 0:
        return m
    a, b = m.points[m.edges[:, 0]], m.points[m.edges[:, 1]]
    near = np.minimum(np.linalg.norm(a - eye, axis=1), np.linalg.norm(b - eye, axis=1)) <= max_range
    live = near & (m.interest != Interest.NEVER)
    if not live.any():
        return m
    r, phi, _ = edge_geometry(a[live], b[live], eye, heading)
    interest = m.interest.copy()
    interest[live] = classify_interest(r, phi, params)
    return m.replaced(interest=interest)


def closer_points(m: ExplorationMap, eye: np.ndarray, edges: np.ndarray | None = None) -> np.ndarray:
    """The closer endpoint (K x 3) of each edge seen from ``eye``: the point to watch. ``edges``:
    indices of the edges to look at (default: all of them, in order)."""
    pairs = m.edges if edges is None else m.edges[edges]
    a, b = m.points[pairs[:, 0]], m.points[pairs[:, 1]]
    a_closer = np.einsum("ij,ij->i", a - eye, a - eye) <= np.einsum("ij,ij->i", b - eye, b - eye)
    return np.where(a_closer[:, None], a, b)


def image_edges(uv: np.ndarray, max_px: float) -> np.ndarray:
    """Pairs (K x 2, smaller index first, sorted) of image neighbours: pixels at most ``max_px`` apart."""
    pts = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    if len(pts) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    pairs = cKDTree(pts).query_pairs(max_px, output_type="ndarray").astype(np.int64)
    return pairs_of_keys(np.unique(pair_keys(np.sort(pairs, axis=1))))


def pair_keys(pairs: np.ndarray) -> np.ndarray:
    """One int64 key per index pair (indices below 2^31), for sets of edges."""
    return (pairs[:, 0].astype(np.int64) << 32) | pairs[:, 1].astype(np.int64)


def pairs_of_keys(keys: np.ndarray) -> np.ndarray:
    """The index pairs (K x 2) of :func:`pair_keys`."""
    return np.column_stack((keys >> 32, keys & 0xFFFFFFFF)).astype(np.int64).reshape(-1, 2)

