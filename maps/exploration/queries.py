"""What the exploration map says about the robot's way: the cells of a disc round points, the
obstacle cells across a path, whether they were free floor on an earlier map (something moved
there: a person), and how far an arc is free.

Map queries, shared by the path follower (:mod:`behaviours.exploration.follow_path`) and the goal
selection (:mod:`behaviours.exploration.select_goal`); they read an
:class:`~maps.exploration.grid.ExplorationMap` and change nothing.
"""

from __future__ import annotations

import math

import numpy as np

from maps.exploration.grid import Cell, ExplorationMap
from perception.geometry import Pose2D


def _disc_offsets(m: ExplorationMap, radius: float) -> np.ndarray:
    """(row, column) offsets (K x 2) of the cells of a disc of ``radius`` around a cell."""
    f = m.frame
    k = int(math.ceil(radius / f.resolution))
    offsets = np.mgrid[-k : k + 1, -k : k + 1].reshape(2, -1).T
    return offsets[np.hypot(*(offsets * f.resolution).T) <= radius + f.resolution * 0.5]


def cells_around(
    m: ExplorationMap, centres: np.ndarray, radius: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The cells around each of ``centres`` (N x 2) out to a superset of the disc of ``radius``, centre
    after centre: their centres (K x 2), their offsets from their disc's centre (K x 2), the length
    of those (K,), and their states (uint8 Cell, UNKNOWN outside the grid). The disc itself is
    ``distance <= radius``."""
    f = m.frame
    points = np.asarray(centres, dtype=np.float64).reshape(-1, 2)
    offsets = _disc_offsets(m, radius + f.resolution)  # a superset: a disc around a point, not a cell centre
    rows, cols = f.cell_of(points)
    r = (rows[:, None] + offsets[None, :, 0]).ravel()
    c = (cols[:, None] + offsets[None, :, 1]).ravel()
    xy = f.centre_of(r, c)
    rel = xy - np.repeat(points, len(offsets), axis=0)
    inside = f.inside(r, c)
    states = np.full(len(r), Cell.UNKNOWN, dtype=np.uint8)
    states[inside] = m.cells[r[inside], c[inside]]
    return xy, rel, np.hypot(*rel.T), states


def disc_cells(m: ExplorationMap, centres: np.ndarray, radius: float) -> np.ndarray:
    """The states (uint8 Cell) of the cells whose centres lie within ``radius`` of any of ``centres``
    (exactly: a travel-cost path, whose cells have more clearance than the radius, is never found
    blocked by this)."""
    _, _, distance, states = cells_around(m, centres, radius)
    return states[distance <= radius]


def blocking_cells(m: ExplorationMap, path: np.ndarray, radius: float, *, trail: bool = False) -> np.ndarray:
    """The centres (K x 2) of the obstacle cells of ``m`` within ``radius`` of a point of ``path``.

    With ``trail``, a point of the path on the robot's trail (``visited``) is blocked only by obstacle
    cells on the trail themselves (something stands where the robot drove): it fitted there, so an
    obstacle cell beside its trail is a squeeze narrowed by stereo noise, or something the range
    sensors judge as it drives (the travel cost's own rule, :func:`maps.exploration.travel.traversable`).
    Without it, a robot in a place its map has since narrowed finds every way out blocked."""
    if len(path) == 0:
        return np.zeros((0, 2))
    points = np.asarray(path, dtype=np.float64).reshape(-1, 2)
    centres, _, distance, states = cells_around(m, points, radius)
    hit = (distance <= radius) & (states == Cell.OBSTACLE)
    if trail:
        on_trail = np.repeat(_visited(m, points), len(states) // len(points))
        hit &= ~on_trail | _visited(m, centres)
    return centres[hit]


def _visited(m: ExplorationMap, xy: np.ndarray) -> np.ndarray:
    """Whether each (x, y) lies on a cell of the robot's trail (False outside the grid)."""
    assert m.visited is not None  # always set once the map is built (None only as a constructor argument)
    return m.frame.sample(m.visited, xy, False)


def moved_onto(before: ExplorationMap, blocking: np.ndarray) -> bool:
    """Were the cells ``blocking`` a path (:func:`blocking_cells`), some at least, all free floor in
    ``before`` (something moved there since: a person), none unknown or an obstacle then?"""
    return len(blocking) > 0 and bool(np.all(before.cell_state(blocking) == Cell.FREE))


def free_travel(m: ExplorationMap, pose: Pose2D, curvature: float, room: float, reach: float) -> float:
    """How far (m, at most ``reach``) the robot can go along the arc of ``curvature`` (1/m, left
    positive) from ``pose`` before an obstacle cell comes within ``room`` of its centre, nearer than
    now by a quarter cell (a robot already closer to something may still move along or away from it)."""
    f = m.frame
    k = int(math.ceil((reach + room) / f.resolution)) + 1
    rows, cols = f.cell_of(np.array([[pose.x, pose.y]]))
    r0, c0 = int(rows[0]), int(cols[0])
    window = (slice(max(r0 - k, 0), max(r0 + k + 1, 0)), slice(max(c0 - k, 0), max(c0 + k + 1, 0)))
    wr, wc = np.nonzero(m.cells[window] == Cell.OBSTACLE)
    if len(wr) == 0:
        return reach
    obstacles = f.centre_of(wr + window[0].start, wc + window[1].start)
    s = np.arange(0.0, reach + f.resolution / 2, f.resolution / 2)
    if abs(curvature) < 1e-6:
        dx, dy = s, np.zeros_like(s)
    else:
        dx, dy = np.sin(curvature * s) / curvature, (1.0 - np.cos(curvature * s)) / curvature
    c, sn = math.cos(pose.theta), math.sin(pose.theta)
    centres = np.column_stack((pose.x + c * dx - sn * dy, pose.y + sn * dx + c * dy))
    nearest = np.min(np.hypot(centres[:, None, 0] - obstacles[None, :, 0], centres[:, None, 1] - obstacles[None, :, 1]),
                     axis=1)
    closing = (nearest < room) & (nearest < nearest[0] - f.resolution / 4.0)  # grazing along a wall is not closing
    hit = np.flatnonzero(closing)
    return float(s[hit[0]]) if len(hit) else reach
