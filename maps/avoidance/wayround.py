"""A way round what holds the robot: a path planned on the echoes of the last tens of seconds.

The detour (:mod:`maps.avoidance.detour`) is reactive: of the directions free now, the one
closest to the wish, none more than a right angle from it. That passes a person or a desk, but
not a pocket: in the lab, two people standing on the route beside a desk leave a way home that
starts 120 degrees from the wish (back round the first person, then on north of both), and the
robot stood in the pocket until the time limit (docs/obstacles-measured.md, "Fresh seeds and
the desk pocket"). Nav2 splits this into a planner on a local costmap and a controller; here the
planner is asked only when the reactive choice has none to give:

- the **grid**: 5 cm cells, :data:`HALF` metres each way round the robot (base frame), a cell
  occupied where an echo of :class:`perception.echo_map.EchoMap` lies (the desk the robot faced
  ten seconds ago is still there; a person who walked away was seen through);
- the **room** of a cell: its distance to the nearest occupied cell (a distance transform, less
  half a cell's diagonal), and a cell can be stood on where that exceeds the footprint's
  enclosing radius plus the clearance (the robot may turn anywhere on the way); the cells within
  :data:`NEAR` of the robot need only the enclosing radius, or the room the robot has where it
  stands if that is less, so that a robot already near something can leave it;
- cells farther than :data:`STRAY` times ``max_stray`` from the detour's line are out (eq. 3, as
  for the directions, but farther: in the lab's pocket the way home passes two people standing
  on the route, 1.5 m from where the robot was held, when the route's detours keep within 1 m);
- the **way**: Dijkstra over the 8-connected cells (``scipy.sparse.csgraph``), a step costing up
  to three times its length within :data:`KEEP_OFF` of the least room (a costmap's inflation: the
  way keeps off things where there is space), to the cheapest cell at least ``ahead`` metres
  along the wish's heading from where the robot was held: past what holds it, not merely out of
  the corner. No such cell: no way (the robot is held as before and backs away).

The way is driven (:func:`along`) by the same directions as a detour: each tick the free direction
nearest its point :data:`LOOKAHEAD` on, within :data:`WAY_FACING` of it, or a turn on the spot
towards that point when it lies behind, beyond the fan's reach; within :data:`WAY_DONE` of its end
it is driven.

Pure: the points and poses are passed in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import distance_transform_edt
from scipy.sparse.csgraph import dijkstra

from maps.avoidance.directions import Choice, choose, steer
from maps.avoidance.sweep import AvoidSettings, DetourLine, Surroundings
from maps.exploration.grid import GridFrame
from maps.exploration.travel import chain_to, grid_graph
from perception.geometry import Pose2D, frame_to_parent, wrap_angle
from perception.polygons import enclosing_radius

RESOLUTION = 0.05  # m: the grid's cells
HALF = 3.0  # m: the grid reaches this far from the robot each way
AHEAD = 1.0  # m: a way ends at least this far along the wish's heading from where the robot was held
NEAR = 0.25  # m: cells this near the robot need only the enclosing radius (it may leave what it is near)
KEEP_OFF = 0.2  # m: within this of the least room a step costs more (up to PENALTY + 1 times its length)
PENALTY = 2.0
LOOKAHEAD = 0.5  # m: a way is steered along towards its point this far on
WAY_FACING = math.pi / 4.0  # rad: no direction farther than this from that point is taken
WAY_DONE = 0.25  # m: a way this near its end is driven
STRAY = 2.0  # a way may stray this many times a detour's max_stray from its line: it goes round a cluster


@dataclass(frozen=True, slots=True)
class WayRound:
    """A way planned: cell centres from the robot to its end (odometry frame, K x 2) and its length (m)."""

    path: np.ndarray
    length: float

    @property
    def end(self) -> np.ndarray:
        return self.path[-1]

    def driven(self, pose: Pose2D) -> bool:
        """Is the robot at ``pose`` within :data:`WAY_DONE` of the end?"""
        return float(np.hypot(*(self.end - (pose.x, pose.y)))) <= WAY_DONE


def plan(points: np.ndarray, pose: Pose2D, heading: float, settings: AvoidSettings, *,
         origin: tuple[float, float], line: DetourLine | None = None, ahead: float = AHEAD, stray: float = STRAY
         ) -> WayRound | None:
    """The way (module docstring) from the robot at odometry ``pose``, among the echoes ``points``
    (base frame), to a cell at least ``ahead`` metres along ``heading`` (rad, odometry) from
    ``origin`` (odometry: where the robot was held), within ``stray`` times ``max_stray`` of the
    ``line``; None when there is none."""
    cells = int(round(2.0 * HALF / RESOLUTION))
    frame = GridFrame(-HALF, -HALF, RESOLUTION, cells, cells)
    occupied = np.zeros(frame.shape, dtype=bool)
    rows, cols = frame.cell_of(points)
    inside = frame.inside(rows, cols)
    occupied[rows[inside], cols[inside]] = True
    room = distance_transform_edt(~occupied) * RESOLUTION - RESOLUTION * math.sqrt(0.5) if occupied.any() \
        else np.full(frame.shape, np.inf)
    every = np.indices(frame.shape).reshape(2, -1)
    base = frame.centre_of(every[0], every[1])
    odometry = frame_to_parent(pose, base)
    radius = enclosing_radius(settings.footprint)
    need = radius + settings.clearance
    near = (np.hypot(base[:, 0], base[:, 1]) <= NEAR).reshape(frame.shape)
    start_r, start_c = (int(v[0]) for v in frame.cell_of(np.zeros((1, 2))))
    ok = (room > need) | (near & (room >= min(radius, room[start_r, start_c])))
    if line is not None:
        here = abs(line.offset(pose.x, pose.y))
        offsets = np.abs(line.offset(odometry[:, 0], odometry[:, 1])).reshape(frame.shape)
        ok &= (offsets <= max(stray * settings.max_stray, here)) | near
    ok[start_r, start_c] = True
    progress = ((odometry[:, 0] - origin[0]) * math.cos(heading)
                + (odometry[:, 1] - origin[1]) * math.sin(heading)).reshape(frame.shape)
    if not (ok & (progress >= ahead)).any():
        return None
    weight = 1.0 + PENALTY * np.clip((need + KEEP_OFF - room) / KEEP_OFF, 0.0, 1.0)
    node = np.full(frame.shape, -1, dtype=np.int64)
    node[ok] = np.arange(np.count_nonzero(ok))
    cost, previous = dijkstra(grid_graph(ok, node, weight, RESOLUTION), directed=False,
                              indices=int(node[start_r, start_c]), return_predecessors=True)
    ok_rows, ok_cols = np.nonzero(ok)
    goal = np.where(progress[ok_rows, ok_cols] >= ahead, cost, np.inf)
    best = int(np.argmin(goal))
    if not math.isfinite(goal[best]):
        return None
    index = chain_to(previous, best)
    path = frame_to_parent(pose, frame.centre_of(ok_rows[index], ok_cols[index]))
    path[0] = (pose.x, pose.y)
    return WayRound(path, float(np.sum(np.hypot(*np.diff(path, axis=0).T))))


def along(way: WayRound, around: Surroundings, pose: Pose2D, settings: AvoidSettings
          ) -> tuple[tuple[float, float], Choice | None]:
    """The command that drives along ``way`` (and the fan judged, if it was): the free direction
    nearest its point :data:`LOOKAHEAD` on, within :data:`WAY_FACING` of it
    (:func:`maps.avoidance.directions.choose`, ``steer``), or a turn on the spot towards that point
    when it lies behind, beyond the fan; (0, 0) when neither will do."""
    point, _ = carrot(way, pose, LOOKAHEAD)
    psi = wrap_angle(math.atan2(point[1] - pose.y, point[0] - pose.x) - pose.theta)
    if abs(psi) > settings.spread:
        return ((0.0, math.copysign(settings.turn_rate, psi)) if around.turns(psi) else (0.0, 0.0)), None
    choice = choose(around, psi, settings, within=WAY_FACING)
    return steer(choice, around, settings), choice


def carrot(way: WayRound, pose: Pose2D, lookahead: float) -> tuple[np.ndarray, float]:
    """The point of the way ``lookahead`` metres on from the robot's nearest point on it (its end when
    nearer), and how far the robot is from that end (m)."""
    here = np.array([pose.x, pose.y])
    nearest = int(np.argmin(np.hypot(*(way.path - here).T)))
    ahead = way.path[nearest:]
    far = np.nonzero(np.hypot(*(ahead - here).T) >= lookahead)[0]
    point = ahead[far[0]] if len(far) else way.end
    return point, float(np.hypot(*(way.end - here)))
