"""Plane polygons in the base frame: the robot's footprint and the collision monitor's zones.

A polygon is an (N x 2) array of vertices in order (metres, REP-103 base frame: x forward, y
left); :func:`as_polygon` checks one and turns it counter-clockwise. Everything here is pure
geometry on small arrays (a footprint has 4 to 32 vertices, a sonar scan a few dozen points).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

EPS = 1e-12


def as_polygon(vertices: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
    """The vertices as a counter-clockwise (N x 2) float array; ValueError when it is not a simple
    polygon of at least 3 finite vertices with an area."""
    poly = np.asarray(vertices, dtype=float)
    if poly.ndim != 2 or poly.shape[1] != 2 or len(poly) < 3:
        raise ValueError("a polygon needs at least 3 vertices [x, y]")
    if not np.isfinite(poly).all():
        raise ValueError("a polygon's vertices must be finite")
    if not is_simple(poly):
        raise ValueError("the polygon's edges cross each other")
    area = signed_area(poly)
    if abs(area) < 1e-9:
        raise ValueError("the polygon has no area (its vertices are on one line)")
    return poly if area > 0 else poly[::-1].copy()


def following(poly: np.ndarray) -> np.ndarray:
    """Each vertex's successor along the outline (the last one's is the first): edge i goes from
    ``poly[i]`` to ``following(poly)[i]`` (a roll by one, at a tenth of numpy's general roll's cost)."""
    return np.concatenate((poly[1:], poly[:1]))


def signed_area(poly: np.ndarray) -> float:
    """Shoelace area: positive when the vertices go counter-clockwise."""
    x, y = poly[:, 0], poly[:, 1]
    nxt = following(poly)
    return 0.5 * float(np.dot(x, nxt[:, 1]) - np.dot(nxt[:, 0], y))


def is_convex(poly: np.ndarray) -> bool:
    """Every turn along the (counter-clockwise) outline is to the left (collinear vertices allowed)."""
    edges = following(poly) - poly
    after = following(edges)
    turns = edges[:, 0] * after[:, 1] - edges[:, 1] * after[:, 0]
    return bool(np.all(turns >= -1e-12) or np.all(turns <= 1e-12))


def is_simple(poly: np.ndarray) -> bool:
    """No two edges that are not neighbours touch or cross."""
    n = len(poly)
    a, b = poly, following(poly)
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue  # neighbours through the closing edge
            if _segments_touch(a[i], b[i], a[j], b[j]):
                return False
    return True


def _segments_touch(p1: np.ndarray, p2: np.ndarray, q1: np.ndarray, q2: np.ndarray) -> bool:
    def cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
        return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))

    d1, d2, d3, d4 = cross(q1, q2, p1), cross(q1, q2, p2), cross(p1, p2, q1), cross(p1, p2, q2)
    if ((d1 > 0) != (d2 > 0)) and ((d3 > 0) != (d4 > 0)) and 0 not in (d1, d2, d3, d4):
        return True
    return any(abs(d) < EPS and _on_segment(s1, s2, p) for d, s1, s2, p in
               ((d1, q1, q2, p1), (d2, q1, q2, p2), (d3, p1, p2, q1), (d4, p1, p2, q2)))


def _on_segment(a: np.ndarray, b: np.ndarray, p: np.ndarray) -> bool:
    return bool(min(a[0], b[0]) - EPS <= p[0] <= max(a[0], b[0]) + EPS
                and min(a[1], b[1]) - EPS <= p[1] <= max(a[1], b[1]) + EPS)


def contains(poly: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Which points (N x 2) lie inside the polygon (even-odd rule; a point on an edge may go either way)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    x, y = pts[:, 0:1], pts[:, 1:2]
    ax, ay = poly[:, 0], poly[:, 1]
    nxt = following(poly)
    bx, by = nxt[:, 0], nxt[:, 1]
    straddles = (ay > y) != (by > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        crossing_x = ax + (y - ay) * (bx - ax) / (by - ay)
    crossings = straddles & (x < crossing_x)
    return np.asarray(np.count_nonzero(crossings, axis=1) % 2 == 1)


def distance(poly: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Distance (m) of each point to the polygon: 0 inside, else to its nearest edge."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(pts) == 0:
        return np.zeros(0)
    a = poly[None, :, :]
    e = (following(poly) - poly)[None, :, :]
    ap = pts[:, None, :] - a
    t = np.clip(np.sum(ap * e, axis=2) / np.maximum(np.sum(e * e, axis=2), EPS), 0.0, 1.0)
    nearest = np.linalg.norm(ap - t[..., None] * e, axis=2).min(axis=1)
    return np.where(contains(poly, pts), 0.0, nearest)


def rectangle(front: float, rear: float, half_width: float) -> np.ndarray:
    """The box from ``-rear`` to ``front`` along x and ``+-half_width`` along y, counter-clockwise."""
    return np.array([[front, -half_width], [front, half_width], [-rear, half_width], [-rear, -half_width]])


def enclosing_radius(poly: np.ndarray) -> float:
    """The radius of the disc about the origin that holds ``poly`` (for a footprint in the base
    frame: what turning on the spot sweeps)."""
    return float(np.max(np.hypot(poly[:, 0], poly[:, 1])))


def disc(radius: float, sides: int = 32) -> np.ndarray:
    """A regular polygon that contains the disc of ``radius`` (its edges touch the circle)."""
    outer = radius / math.cos(math.pi / sides)
    angles = (np.arange(sides) + 0.5) * (2.0 * math.pi / sides)
    return np.column_stack((outer * np.cos(angles), outer * np.sin(angles)))


def grow(poly: np.ndarray, margin: float) -> np.ndarray:
    """A convex, counter-clockwise polygon with every edge moved ``margin`` metres outwards (corners
    mitred: the result contains every point within ``margin`` of the polygon)."""
    if margin == 0:
        return poly.copy()
    edges = following(poly) - poly
    normals = np.column_stack((edges[:, 1], -edges[:, 0])) / np.linalg.norm(edges, axis=1)[:, None]
    out = []
    for i in range(len(poly)):  # vertex i joins edge i-1 and edge i
        n0, n1 = normals[i - 1], normals[i]
        bisector = n0 + n1
        cos_half = float(np.dot(bisector / np.linalg.norm(bisector), n1))
        out.append(poly[i] + bisector / np.linalg.norm(bisector) * (margin / max(cos_half, 1e-6)))
    return np.array(out)
