"""Drive a polyline of waypoints on odometry: the teach mission's operator in the simulator.

A route to teach is a list of points in the odometry frame (the start pose is the origin), given
flat as a mission input (``route: [x0, y0, x1, y1, ...]``, so ``--set route=[...]`` can change
it). Each waypoint is reached as ``DriveTo`` reaches its goal: turn towards it when it is more
than 30 degrees off, then drive while steering, slowing down near it.
"""

from __future__ import annotations

import math
from typing import Any

from py_trees.common import Status

from behaviours.motion import ANGULAR_DECEL, LINEAR_DECEL, MIN_SPEED, MOTION_PORTS, DriveTo, OdometryMotion, ramp
from behaviours.ports import InputPort
from behaviours.registry import register
from perception.geometry import Pose2D, wrap_angle


def waypoint_pairs(flat: list[float]) -> list[tuple[float, float]]:
    """``[x0, y0, x1, y1, ...]`` as points; ValueError for an odd count."""
    if len(flat) % 2:
        raise ValueError(f"waypoints come as x, y pairs: got {len(flat)} numbers")
    return [(flat[i], flat[i + 1]) for i in range(0, len(flat), 2)]


@register
class DriveWaypoints(OdometryMotion):
    """Drive through the waypoints in order (odometry frame); SUCCESS at the last one.

    The intermediate waypoints are passed within ``tolerance`` without stopping when the next
    leg goes on straight; the robot stops and turns where the route bends by more than 30 deg.
    Each command says how far the robot goes before it stops (``reach``: to the next bend or the
    end), so an avoidance judges the way no farther than that.
    """

    WAYPOINTS = InputPort("waypoints", list[float], unit="m", doc="x0, y0, x1, y1, ... in the odometry frame")
    SPEED = InputPort("speed", float, 0.3, unit="m/s", minimum=0.01, maximum=1.2, doc="top speed")
    TOLERANCE = InputPort("tolerance", float, 0.05, unit="m", minimum=0.005, doc="how close a waypoint is reached")
    PORTS = (WAYPOINTS, SPEED, TOLERANCE, *MOTION_PORTS)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.points = waypoint_pairs(self.get_input(self.WAYPOINTS))
        if not self.points:
            raise ValueError(f"{self.name}: no waypoints")
        self.index = 0

    def initialise(self) -> None:
        self.index = 0

    def step(self, pose: Pose2D) -> Status:
        tolerance = self.get_input(self.TOLERANCE)
        while self.index < len(self.points) and math.dist((pose.x, pose.y), self.points[self.index]) <= tolerance:
            self.index += 1
        if self.index >= len(self.points):
            self.command(0.0, 0.0)
            return Status.SUCCESS
        x, y = self.points[self.index]
        distance = math.hypot(x - pose.x, y - pose.y)
        error = wrap_angle(math.atan2(y - pose.y, x - pose.x) - pose.theta)
        w = ramp(error, math.radians(60.0), ANGULAR_DECEL, 0.0) if error else 0.0
        remaining = distance + self._straight_on(self.index)
        v = 0.0 if abs(error) > DriveTo.TURN_IN_PLACE else ramp(remaining, self.get_input(self.SPEED),
                                                                 LINEAR_DECEL, MIN_SPEED) * math.cos(error)
        self.command(v, w, remaining)  # where it stops next (a bend or the end): the goal of this command
        self.feedback_message = f"waypoint {self.index + 1} of {len(self.points)}: {distance:.2f} m to go"
        return Status.RUNNING

    def _straight_on(self, index: int) -> float:
        """How far the route goes on past waypoint ``index`` before it bends by more than 30 deg."""
        total = 0.0
        for k in range(index, len(self.points) - 1):
            a, b = self.points[k], self.points[k + 1]
            before = self.points[k - 1] if k > 0 else None
            if before is not None:
                turn = wrap_angle(math.atan2(b[1] - a[1], b[0] - a[0]) - math.atan2(a[1] - before[1], a[0] - before[0]))
                if abs(turn) > DriveTo.TURN_IN_PLACE:
                    break
            total += math.dist(a, b)
        return total
