"""Driving planned paths in the room estimate: the part of travel every roadmap routine shares.

Paths come from :func:`maps.planning.plan_path` (OMPL, a disc robot that turns in place, in the
room's free grid, reference frame); the robot drives them waypoint by waypoint with ``DriveTo``
on odometry, each waypoint converted through the room's reference pose.

Choices where the paper is vague:

- **Start or goal where the grid says the robot cannot stand** (after homing to a target close
  to furniture; a target on the edge of the free polygon; the map's anchor off by some drift):
  the nearest standable point is planned from or to instead, and the robot drives straight
  between it and the real point. A goal farther than ``SNAP`` (0.6 m) from standable floor has no
  path (the routine fails with the reason); the start has no such limit (the robot stands on
  free floor, whatever the map says).
- **A robot cut off from the goal in the map** (its nearest standable floor lies in another free
  region than the goal's): planned from the nearest standable floor of the goal's region, driven
  to straight. The robot got where it stands (homing to a target drives by the images, not on
  the map), and the map's cut may be a person the stereo pairs saw who has moved on; the
  collision monitor judges the straight drive. Without this, in `annex` a robot homed to a
  target beyond a pacing person's mark failed every return and every one of the 40 search rounds
  in 2 s ("start and goal lie in separate free regions").
- The room's reference pose moves in the odometry frame when the robot homes to the reference
  image again (:func:`reanchored`): the map and its free grid stay as they are.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from behaviours.ports import InputPort, OutputPort, Port
from behaviours.roadmap.routine import Failed, RoutineBehaviour, Step, robot_disc
from maps.planning import PlanResult, plan_path
from maps.room import FreeGrid, RoomEstimate
from perception.geometry import Pose2D

SNAP = 0.6  # m: farthest a start or goal is moved to reach standable floor
PLAN_TIME = 0.5  # s: default time limit of a path search

PLAN_TIME_IN = InputPort("plan_time", float, PLAN_TIME, unit="s", minimum=0.01, maximum=10.0, literal_only=True,
                         doc="time limit of one path search (wall clock, inside one tick)")
PLAN_OUT = OutputPort("plan", PlanResult, "/map/plan", doc="the last planned path (reference frame)")
PLAN_PORTS: tuple[Port, ...] = (PLAN_TIME_IN, PLAN_OUT)
"""The ports of a node that plans; a routine without them plans within ``PLAN_TIME`` and writes no plan."""


def nearest_standable(free: FreeGrid, x: float, y: float, radius: float, snap: float = SNAP,
                      region: int | None = None) -> tuple[float, float] | None:
    """(x, y) itself when the robot may stand there, else the nearest standable cell centre within
    ``snap``; None when there is none. With ``region`` (a label of :meth:`FreeGrid.regions`), only
    floor of that region will do."""
    if region is None:
        if free.can_stand(np.array([[x, y]]), radius)[0]:
            return x, y
        standable = free.standable(radius)
    else:
        if free.region_at(np.array([[x, y]]), radius)[0] == region:
            return x, y
        standable = free.regions(radius) == region
    if not standable.any():
        return None
    centres = free.centres()[standable]
    distances = np.hypot(centres[:, 0] - x, centres[:, 1] - y)
    best = int(np.argmin(distances))
    return (float(centres[best, 0]), float(centres[best, 1])) if distances[best] <= snap else None


def reanchored(room: RoomEstimate, reference_pose: Pose2D) -> RoomEstimate:
    """The room with its reference pose moved in the odometry frame (same map, same free grid)."""
    moved = dataclasses.replace(room, reference_pose=reference_pose)
    moved.__dict__["free"] = room.free  # the cached free grid is in the reference frame: unchanged
    return moved


def plan(host: RoutineBehaviour, room: RoomEstimate, goal: Pose2D) -> Step[PlanResult]:
    """A path from the robot to ``goal`` (reference frame), start and goal snapped to standable floor.

    Written to the host's ``plan`` output when it has one; :class:`Failed` when there is none.
    """
    radius = robot_disc(host)
    here = room.to_reference((yield from host.pose()))
    start = nearest_standable(room.free, here.x, here.y, radius, snap=math.inf)  # the robot is on free floor
    end = nearest_standable(room.free, goal.x, goal.y, radius)
    if start is None or end is None:
        what = "robot" if start is None else "goal"
        raise Failed(f"no path: the {what} is more than {SNAP} m from floor where the robot may stand")
    start_region, goal_region = (int(r) for r in room.free.region_at(np.array([start, end]), radius))
    if start_region != goal_region:  # the robot stands cut off from the goal
        start = nearest_standable(room.free, here.x, here.y, radius, snap=math.inf, region=goal_region)
        assert start is not None  # the goal's own cell is in its region
    limit = host.get_input(PLAN_TIME_IN) if PLAN_TIME_IN.name in host.inputs else PLAN_TIME
    result = plan_path(room.free, Pose2D(start[0], start[1], here.theta), Pose2D(end[0], end[1], goal.theta),
                       robot_radius=radius, time_limit=limit)
    if PLAN_OUT.name in host.outputs:
        host.set_output(PLAN_OUT, result)
    if not result.ok:
        raise Failed(result.reason)
    return result


def travel(host: RoutineBehaviour, room: RoomEstimate, goal: Pose2D, *, turn: bool) -> Step[PlanResult]:
    """Plan to ``goal`` (reference frame) and drive the path (module docstring); then turn to the
    goal's heading when ``turn``."""
    path = yield from plan(host, room, goal)
    points = [*path.waypoints, goal]  # the goal itself last: it differs from the path's end when snapped
    for index, waypoint in enumerate(points):
        target = room.to_odometry(waypoint)
        yield from host.drive_to(target.x, target.y, f"to waypoint {index + 1} of {len(points)}",
                                 tolerance=0.05 if index < len(points) - 1 else 0.02)
    if turn:
        yield from host.turn_to(room.to_odometry(goal).theta, "turning to the goal heading")
    return path
