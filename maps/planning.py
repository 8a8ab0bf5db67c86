"""Motion planning between poses in the free space, with OMPL (docs/design.md, method 2).

Used to reach coverage positions and to return to the reference pose. All poses are in the
room estimate's reference frame; the free space is a :class:`maps.room.FreeGrid`.

Model and choices:

- **Robot**: a disc of radius ``robot_radius`` that turns in place (differential drive). Turning
  sweeps nothing, so a path is a polyline: at each waypoint the robot turns to face the next
  and drives straight; at the goal it turns to the goal heading (:attr:`PlanResult.legs`).
- **State space**: OMPL's ``SE2StateSpace`` bounded by the grid. A disc's heading never
  changes what it collides with, so the validity checker looks at x, y only and the headings of
  OMPL's intermediate states are replaced by the direction of travel.
- **Validity**: :meth:`maps.room.FreeGrid.standable` (distance transform of the free cells with
  a conservative margin, see :mod:`maps.room`). OMPL checks straight motions every quarter cell
  (its longest valid segment; SE2 distances are never shorter than the x-y distance), and the
  margin's extra eighth of a cell covers the points between two checks, so every point of an
  accepted path keeps ``robot_radius`` from anything not free.
- **No path, at once**: a start or goal where the robot cannot stand, or a start and goal in
  different 8-connected groups of standable cells (:meth:`FreeGrid.regions`), is answered
  without running OMPL: consecutive checked states of any accepted path are at most a quarter
  cell apart, so their cells touch by a side or a corner.
- **Straight first**: when the straight segment from start to goal passes the same checks, it
  is the path (no search, two waypoints).
- **Planner**: ``RRTConnect`` (it stops at the first solution), then
  ``PathSimplifier.simplifyMax`` (shortcuts until no more help; no clock involved). OMPL's
  random generator is seeded before any planner object exists, so the same inputs and seed give
  the same path. The search is bounded by ``time_limit`` seconds; running out is reported.
- OMPL objects are built inside :func:`plan_path` (module-level ones make nanobind report leaks
  at exit) and its console is kept at warnings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maps.room import FreeGrid
from perception.geometry import Pose2D, wrap_angle

CHECK_FRACTION_OF_CELL = 0.25  # OMPL's longest valid segment, in cells (see the module docstring)


@dataclass(frozen=True, slots=True)
class Leg:
    """Turn in place by ``turn`` (rad, counter-clockwise), then drive ``distance`` (m) straight."""

    turn: float
    distance: float


@dataclass(frozen=True, slots=True)
class PlanResult:
    """A planned path, or why there is none.

    ``waypoints``: start, intermediate points, goal (reference frame); an intermediate
    waypoint's heading is the direction of the segment leaving it. ``legs`` then ``final_turn``
    drive the robot from start to goal. ``reason`` is empty when ``ok``.
    """

    ok: bool
    reason: str = ""
    waypoints: tuple[Pose2D, ...] = ()
    legs: tuple[Leg, ...] = ()
    final_turn: float = 0.0
    length: float = 0.0


def segment_is_free(free: FreeGrid, a: np.ndarray, b: np.ndarray, robot_radius: float) -> bool:
    """Whether the robot may stand at every point checked along a -> b (every quarter cell)."""
    steps = max(1, math.ceil(float(np.hypot(*(b - a))) / (CHECK_FRACTION_OF_CELL * free.cell)))
    t = np.linspace(0.0, 1.0, steps + 1)[:, None]
    return bool(free.can_stand(a + t * (b - a), robot_radius).all())


def legs_through(points: np.ndarray, start_theta: float, goal_theta: float) -> tuple[tuple[Leg, ...], float]:
    """Turn-and-drive legs along a polyline (N x 2) from a start heading, and the final turn."""
    legs = []
    heading = start_theta
    for a, b in zip(points[:-1], points[1:], strict=True):
        dx, dy = b - a
        distance = math.hypot(dx, dy)
        if distance < 1e-9:
            continue
        direction = math.atan2(dy, dx)
        legs.append(Leg(wrap_angle(direction - heading), distance))
        heading = direction
    return tuple(legs), wrap_angle(goal_theta - heading)


def plan_path(free: FreeGrid, start: Pose2D, goal: Pose2D, *, robot_radius: float, time_limit: float = 1.0,
              seed: int = 1) -> PlanResult:
    """A collision-free turn-and-drive path from start to goal (module docstring), or why not."""
    ends = np.array([[start.x, start.y], [goal.x, goal.y]])
    can = free.can_stand(ends, robot_radius)
    for ok, what, pose in ((can[0], "start", start), (can[1], "goal", goal)):
        if not ok:
            return PlanResult(False, f"the robot (radius {robot_radius:.2f} m) cannot stand at the {what} "
                                     f"({pose.x:.2f}, {pose.y:.2f}): too close to an obstacle or outside the "
                                     "free space")
    regions = free.region_at(ends, robot_radius)
    if regions[0] != regions[1]:
        return PlanResult(False, f"no path: start and goal lie in separate free regions for a robot of radius "
                                 f"{robot_radius:.2f} m")
    if segment_is_free(free, ends[0], ends[1], robot_radius):
        return _result(ends, start, goal)
    points = _ompl_polyline(free, start, goal, robot_radius, time_limit, seed)
    if points is None:
        return PlanResult(False, f"no path found within {time_limit:g} s")
    return _result(points, start, goal)


def _result(points: np.ndarray, start: Pose2D, goal: Pose2D) -> PlanResult:
    legs, final_turn = legs_through(points, start.theta, goal.theta)
    headings = [math.atan2(*(b - a)[::-1]) for a, b in zip(points[:-1], points[1:], strict=True)]
    waypoints = [Pose2D(start.x, start.y, start.theta)]
    waypoints += [Pose2D(float(p[0]), float(p[1]), h) for p, h in zip(points[1:-1], headings[1:], strict=True)]
    waypoints.append(Pose2D(goal.x, goal.y, goal.theta))
    return PlanResult(True, "", tuple(waypoints), legs, final_turn, float(sum(leg.distance for leg in legs)))


def _ompl_polyline(free: FreeGrid, start: Pose2D, goal: Pose2D, robot_radius: float, time_limit: float,
                   seed: int) -> np.ndarray | None:
    """OMPL RRTConnect + simplification in SE2; the path's x-y points, or None when none was found."""
    import ompl.util as ou
    from ompl import base as ob
    from ompl import geometric as og

    _seed_ompl(ou, seed)
    space = ob.SE2StateSpace()
    x0, y0, x1, y1 = free.bounds
    bounds = ob.RealVectorBounds(2)
    bounds.setLow(0, x0)
    bounds.setLow(1, y0)
    bounds.setHigh(0, x1)
    bounds.setHigh(1, y1)
    space.setBounds(bounds)
    standable = free.standable(robot_radius)
    ox, oy, cell = free.origin[0], free.origin[1], free.cell
    nx, ny = standable.shape

    def is_valid(state) -> bool:  # noqa: ANN001 (an OMPL state)
        ix = math.floor((state.getX() - ox) / cell + 0.5)
        iy = math.floor((state.getY() - oy) / cell + 0.5)
        return 0 <= ix < nx and 0 <= iy < ny and bool(standable[ix, iy])

    setup = og.SimpleSetup(space)
    setup.setStateValidityChecker(is_valid)
    info = setup.getSpaceInformation()
    info.setStateValidityCheckingResolution(CHECK_FRACTION_OF_CELL * cell / space.getMaximumExtent())
    setup.setPlanner(og.RRTConnect(info))
    setup.setStartAndGoalStates(_state(space, start), _state(space, goal))
    setup.solve(float(time_limit))
    if not setup.haveExactSolutionPath():
        return None
    path = setup.getSolutionPath()
    og.PathSimplifier(info).simplifyMax(path)
    if not path.check():
        return None
    return np.array([[s.getX(), s.getY()] for s in path.getStates()])


def _state(space, pose: Pose2D):  # noqa: ANN001, ANN202 (OMPL types)
    state = space.allocState()
    state.setX(pose.x)
    state.setY(pose.y)
    state.setYaw(wrap_angle(pose.theta))
    return state


def _seed_ompl(ou, seed: int) -> None:  # noqa: ANN001 (the ompl.util module)
    """Seed OMPL's generator quietly (it logs an error when reseeded, yet honours the seed) and
    keep its console at warnings."""
    ou.setLogLevel(ou.LOG_NONE)
    ou.RNG.setSeed(int(seed))
    ou.setLogLevel(ou.LOG_WARN)
