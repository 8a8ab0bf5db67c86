"""Basic motion on odometry: drive a distance, rotate by an angle, drive to a point, stop.

Each behaviour writes a :class:`~drivers.interfaces.VelocityCommand` to its ``command`` output
(``/robot/command`` unless remapped) every tick it runs; the runner clears the command before
each tick, so a finished or halted behaviour leaves the robot commanded to rest. Speeds ramp
down as ``sqrt(2 a d)`` near the end so the base stops on target within its deceleration limit
instead of overshooting.

A motion the collision monitor keeps stopping (a person standing in the way, a wall short of the
goal) fails after ``held_timeout`` seconds with the monitor's reason, as Nav2's ``DriveOnHeading``
fails past its ``time_allowance``: otherwise a ``Drive`` at someone who stays would hold the
mission until its time limit, and no recovery could take over. Wrap it in ``AvoidObstacles`` to
wait for them and drive round.
"""

from __future__ import annotations

import math
from typing import ClassVar

from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.keys import SAFETY_KEY
from behaviours.ports import InputPort, OutputPort, Port, Ref
from behaviours.registry import register
from drivers.interfaces import STOP, VelocityCommand
from perception.collision_monitor import SafetyState
from perception.geometry import Pose2D, wrap_angle

LINEAR_DECEL = 0.25  # m/s^2, below the Pioneer's 0.3 so the ramp is always achievable
ANGULAR_DECEL = math.radians(80.0)  # rad/s^2, below the Pioneer's 100 deg/s^2
MIN_SPEED = 0.02  # m/s, so the last millimetres do not take forever
MIN_TURN = math.radians(2.0)  # rad/s
HEADING_GAIN = 1.5  # 1/s, holds the heading while driving straight


def ramp(remaining: float, top: float, decel: float, floor: float) -> float:
    """Speed for ``remaining`` distance (signed): capped at ``top``, able to stop in time."""
    speed = min(top, math.sqrt(2.0 * decel * abs(remaining)))
    return math.copysign(max(speed, floor), remaining)


ODOMETRY = InputPort("odometry", Pose2D, Ref("/robot/odometry"), doc="the base's pose in the odometry frame")
STALLED = InputPort("stalled", bool, Ref("/robot/stalled"), doc="a wheel is stalled: stop and fail")
COMMAND = OutputPort("command", VelocityCommand, "/robot/command", unit="m/s, rad/s",
                     doc="the velocity for this tick (the runner sends it to the base)")
SAFETY = InputPort("safety", SafetyState, Ref(SAFETY_KEY.path), doc=SAFETY_KEY.doc)
HELD_TIMEOUT = InputPort("held_timeout", float, 20.0, unit="s", minimum=0.0, maximum=3600.0, literal_only=True,
                         doc="fail when the collision monitor has stopped the motion this long (0: never)")
MOTION_PORTS: tuple[Port, ...] = (ODOMETRY, STALLED, COMMAND, SAFETY, HELD_TIMEOUT)


class OdometryMotion(BearingsBehaviour):
    """The base of motion on odometry: waits for odometry, fails (stopped) when stalled, stops when
    it ends or is halted; subclasses implement :meth:`step` (plugins may subclass it too)."""

    PORTS: ClassVar[tuple[Port, ...]] = MOTION_PORTS
    _held_since: float | None = None  # the collision monitor has stopped every command since

    def odometry(self) -> Pose2D | None:
        return self.get_input(ODOMETRY, None)

    @property
    def held_since(self) -> float | None:
        """Since when the collision monitor has stopped every command of this motion (None: it has not)."""
        return self._held_since

    def command(self, v: float, w: float, reach: float = math.inf) -> None:
        """Write the command; ``reach``: how far the node means to go on it before its goal (m)."""
        self.set_output(COMMAND, VelocityCommand(v, w, reach))

    def blocked(self) -> bool:
        if self.get_input(STALLED, False):
            self.command(0.0, 0.0)
            self.feedback_message = "stalled"
            return True
        return False

    def held(self) -> bool:
        """Has the collision monitor stopped this motion's commands for ``held_timeout`` seconds? Then
        it is stopped, with the monitor's reason."""
        safety, limit = self.get_input(SAFETY, None), self.get_input(HELD_TIMEOUT)
        if not isinstance(safety, SafetyState) or safety.state != "stopped" or limit <= 0.0:
            self._held_since = None
            return False
        now = self.now()
        self._held_since = now if self._held_since is None else self._held_since
        if now - self._held_since < limit:
            return False
        self.command(0.0, 0.0)
        self.feedback_message = f"held by the collision monitor for {now - self._held_since:.0f} s: {safety.reason}"
        return True

    def update(self) -> Status:
        pose = self.odometry()
        if pose is None:
            self.feedback_message = "waiting for odometry"
            return Status.RUNNING
        if self.blocked() or self.held():
            return Status.FAILURE
        return self.step(pose)

    def step(self, pose: Pose2D) -> Status:
        """One control step from the current odometry (the base is known not to be stalled)."""
        raise NotImplementedError

    def terminate(self, new_status: Status) -> None:
        if new_status != Status.RUNNING:
            self.set_output(COMMAND, STOP)
            self._held_since = None


@register
class Drive(OdometryMotion):
    """Drive straight ``distance`` metres (negative: backwards), holding the starting heading."""

    DISTANCE = InputPort("distance", float, unit="m", doc="signed distance along the starting heading")
    SPEED = InputPort("speed", float, 0.3, unit="m/s", doc="top speed", minimum=0.01, maximum=1.2)
    TOLERANCE = InputPort("tolerance", float, 0.01, unit="m", doc="close enough", minimum=0.001)
    PORTS = (DISTANCE, SPEED, TOLERANCE, *MOTION_PORTS)

    def initialise(self) -> None:
        self._start: Pose2D | None = self.odometry()

    def step(self, pose: Pose2D) -> Status:
        if self._start is None:
            self._start = pose
        start = self._start
        travelled = (pose.x - start.x) * math.cos(start.theta) + (pose.y - start.y) * math.sin(start.theta)
        remaining = self.get_input(self.DISTANCE) - travelled
        if abs(remaining) <= self.get_input(self.TOLERANCE):
            self.command(0.0, 0.0)
            return Status.SUCCESS
        v = ramp(remaining, self.get_input(self.SPEED), LINEAR_DECEL, MIN_SPEED)
        w = -HEADING_GAIN * wrap_angle(pose.theta - start.theta)
        self.command(v, w, abs(remaining))
        self.feedback_message = f"{remaining:+.2f} m to go"
        return Status.RUNNING


@register
class Rotate(OdometryMotion):
    """Turn on the spot by ``angle`` degrees (positive: counter-clockwise)."""

    ANGLE = InputPort("angle", float, unit="deg", doc="signed angle to turn")
    SPEED = InputPort("speed", float, 45.0, unit="deg/s", doc="top turn rate", minimum=1.0, maximum=300.0)
    TOLERANCE = InputPort("tolerance", float, 1.0, unit="deg", doc="close enough", minimum=0.05)
    PORTS = (ANGLE, SPEED, TOLERANCE, *MOTION_PORTS)

    def initialise(self) -> None:
        self._last: float | None = None
        self._turned = 0.0

    def step(self, pose: Pose2D) -> Status:
        if self._last is not None:
            self._turned += wrap_angle(pose.theta - self._last)  # unwrapped: angles beyond 180 deg work
        self._last = pose.theta
        remaining = math.radians(self.get_input(self.ANGLE)) - self._turned
        if abs(remaining) <= math.radians(self.get_input(self.TOLERANCE)):
            self.command(0.0, 0.0)
            return Status.SUCCESS
        w = ramp(remaining, math.radians(self.get_input(self.SPEED)), ANGULAR_DECEL, MIN_TURN)
        self.command(0.0, w)
        self.feedback_message = f"{math.degrees(remaining):+.1f} deg to go"
        return Status.RUNNING


@register
class DriveTo(OdometryMotion):
    """Drive to the point (x, y) of the odometry frame: turn towards it, then drive while steering."""

    X = InputPort("x", float, unit="m", doc="goal x in the odometry frame")
    Y = InputPort("y", float, unit="m", doc="goal y in the odometry frame")
    SPEED = InputPort("speed", float, 0.3, unit="m/s", doc="top speed", minimum=0.01, maximum=1.2)
    TOLERANCE = InputPort("tolerance", float, 0.05, unit="m", doc="goal radius", minimum=0.005)
    PORTS = (X, Y, SPEED, TOLERANCE, *MOTION_PORTS)
    TURN_IN_PLACE = math.radians(30.0)  # heading error above which the robot turns before driving

    def step(self, pose: Pose2D) -> Status:
        dx, dy = self.get_input(self.X) - pose.x, self.get_input(self.Y) - pose.y
        distance = math.hypot(dx, dy)
        if distance <= self.get_input(self.TOLERANCE):
            self.command(0.0, 0.0)
            return Status.SUCCESS
        error = wrap_angle(math.atan2(dy, dx) - pose.theta)
        w = ramp(error, math.radians(60.0), ANGULAR_DECEL, 0.0) if error else 0.0
        v = 0.0 if abs(error) > self.TURN_IN_PLACE else ramp(distance, self.get_input(self.SPEED),
                                                              LINEAR_DECEL, MIN_SPEED) * math.cos(error)
        self.command(v, w, distance)
        self.feedback_message = f"{distance:.2f} m to go"
        return Status.RUNNING


@register
class Stop(OdometryMotion):
    """Command the base to rest; SUCCESS at once (with or without odometry, stalled or not)."""

    PORTS = (COMMAND,)

    def update(self) -> Status:
        self.command(0.0, 0.0)
        return Status.SUCCESS
