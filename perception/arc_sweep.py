"""When does a footprint following a velocity command's arc first touch each of some points?

A differential-drive base commanded ``(v, w)`` follows a circle of radius ``v / w`` about its
instantaneous centre of rotation (ICR) at ``(0, v / w)`` in the base frame (a straight line when
``w = 0``). Seen from the base, a still point then moves the other way: along a straight line
``p - (v t, 0)`` (eq. 1) or around the ICR by ``-w t`` (eq. 2,
``p(t) = c + R(-w t) (p - c)``). The first contact of the footprint with the point is the first
time that path crosses one of the footprint's edges; this module solves it in closed form for
every (point, edge) pair at once, so the answer is exact (no time stepping, unlike Nav2's
``simulation_time_step``) and costs one small array operation per tick.

Points already inside the footprint (a sensor's artefact, or a contact) cannot be reached along
a path; they are taken as touching now when the command moves the base towards their side
(forward for a point ahead of the base's centre, backward for one behind) and never otherwise.
"""

from __future__ import annotations

import math

import numpy as np

from perception.polygons import contains, following

EPS = 1e-9
TWO_PI = 2.0 * math.pi


def contact_times(footprint: np.ndarray, points: np.ndarray, v: float, w: float) -> np.ndarray:
    """Seconds until the footprint, moving at ``(v, w)``, first touches each point (``inf``: never,
    within one turn of the arc for ``w != 0``). ``footprint`` counter-clockwise, base frame."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    times = np.full(len(pts), np.inf)
    if len(pts) == 0 or (v == 0.0 and abs(w) < EPS):  # no motion (a turn too slow to sweep: the straight case)
        return times
    inside = contains(footprint, pts)
    towards = np.sign(pts[:, 0]) == np.sign(v) if v != 0.0 else np.zeros(len(pts), dtype=bool)
    times[inside & towards] = 0.0
    outside = ~inside
    if outside.any():
        sweep = _straight_times if abs(w) < EPS else _arc_times
        times[outside] = sweep(footprint, pts[outside], v, w)
    return times


def _straight_times(footprint: np.ndarray, pts: np.ndarray, v: float, _w: float) -> np.ndarray:
    """Eq. 1: the point moves along ``-sign(v) x`` at ``|v|``; first edge it meets."""
    a = footprint[None, :, :]
    e = (following(footprint) - footprint)[None, :, :]
    direction = -math.copysign(1.0, v)  # the point's motion along x, seen from the base
    # p + s (direction, 0) = a + u e  ->  solve for s >= 0 and 0 <= u <= 1
    dy = a[..., 1] - pts[:, None, 1]
    dx = a[..., 0] - pts[:, None, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = -dy / e[..., 1]
        s = (dx + u * e[..., 0]) / direction
    hit = (np.abs(e[..., 1]) > EPS) & (u >= -EPS) & (u <= 1.0 + EPS) & (s >= -EPS)
    distance = np.where(hit, np.maximum(s, 0.0), np.inf).min(axis=1)
    return np.asarray(distance / abs(v))


def _arc_times(footprint: np.ndarray, pts: np.ndarray, v: float, w: float) -> np.ndarray:
    """Eq. 2: the point turns about the ICR ``c`` by ``-w t``; first edge its circle meets, as the
    angle turned from the point to the crossing in the direction of motion, over ``|w|``."""
    centre = np.array([0.0, v / w])
    rel = pts - centre
    radius = np.hypot(rel[:, 0], rel[:, 1])
    start = np.arctan2(rel[:, 1], rel[:, 0])
    a = footprint - centre
    e = following(footprint) - footprint
    # |a + u e|^2 = r^2: (e.e) u^2 + 2 (a.e) u + a.a - r^2 = 0, for every (point, edge)
    ee = np.sum(e * e, axis=1)[None, :]
    ae = np.sum(a * e, axis=1)[None, :]
    aa = np.sum(a * a, axis=1)[None, :]
    disc = ae * ae - ee * (aa - radius[:, None] ** 2)
    best = np.full(len(pts), np.inf)
    root = np.sqrt(np.maximum(disc, 0.0))
    for sign in (-1.0, 1.0):
        u = (-ae + sign * root) / ee
        valid = (disc >= 0.0) & (u >= -EPS) & (u <= 1.0 + EPS)
        cross = a[None, :, :] + u[..., None] * e[None, :, :]
        angle = np.arctan2(cross[..., 1], cross[..., 0])
        turned = (start[:, None] - angle) if w > 0 else (angle - start[:, None])  # the point turns by -w t
        turned = np.mod(turned, TWO_PI)
        turned = np.where(turned > TWO_PI - 1e-9, 0.0, turned)
        best = np.minimum(best, np.where(valid, turned, np.inf).min(axis=1))
    return best / abs(w)
