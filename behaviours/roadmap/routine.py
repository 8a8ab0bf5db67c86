"""Long-running roadmap behaviours as coroutines: one step per tick, motion through the motion nodes.

The roadmap's procedures are loops whose next motion depends on what the last image showed
(the next homing step, the next edge, the next scan heading), so a mission cannot unroll them
into ``Rotate``/``Drive`` nodes. A :class:`RoutineBehaviour` writes such a procedure as a Python
generator, :meth:`RoutineBehaviour.routine`, advanced once per tick: every ``yield`` returns
RUNNING to the tree, so nothing sleeps or blocks and time is the tree's clock. Motion is not
re-implemented: :meth:`rotate`, :meth:`drive`, :meth:`drive_to` create the standard
:mod:`behaviours.motion` nodes bound to this behaviour's own ``odometry``/``stalled``/``command``
ports and tick them until they finish. :meth:`capture` waits until the robot is at rest with its
pan-tilt head level, then returns the next image of a camera.

A routine fails by raising :class:`Failed` with a one-line reason (the behaviour's feedback
message, hence the run report's reason); halting the behaviour closes the generator, which
stops the running motion node (its ``terminate`` commands a stop).
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Generator
from typing import Any, ClassVar, TypeAlias, TypeVar

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.footprint import FOOTPRINT, robot_radius
from behaviours.keys import RANGES_KEY
from behaviours.motion import COMMAND, ODOMETRY, STALLED, Drive, DriveTo, OdometryMotion, Rotate
from behaviours.ports import InputPort, OutputPort, Port, Ref
from drivers.interfaces import STOP, PanTiltCommand, PanTiltState
from perception.frame import Frame
from perception.geometry import Pose2D, wrap_angle
from perception.obstacle_memory import ObstacleMemory
from perception.ranges import RangeScan

T = TypeVar("T")
Step: TypeAlias = Generator[None, None, T]
"""A routine or a part of one: yields once per tick, returns its result."""

CAPTURE_TIMEOUT = 10.0  # s of tree time to wait for a frame at rest before giving up
HEAD_TIMEOUT = 10.0  # s to level the pan-tilt head
HEAD_TOLERANCE = math.radians(0.5)
HEAD_SPEED = 2.0  # rad/s
MIN_TURN = math.radians(0.3)  # smaller turns are not worth a motion
MOTION_SLACK = 3.0  # a motion may take this many times its duration at top speed ...
MOTION_MARGIN = 5.0  # ... plus this (s: accelerating, ramping down) before it counts as stuck


class Failed(Exception):
    """A routine cannot go on; the behaviour fails and reports this reason."""


CAMERA = InputPort("camera", str, "front", literal_only=True, camera=True,
                   doc="camera that takes the homing and scan images (pinhole, on the level pan-tilt head at pan 0)")
CAMERA_OFFSET = InputPort("camera_offset", list[float], [0.15, 0.0], unit="m", literal_only=True,
                          doc="that camera's position on the robot (x forward, y left) at pan 0")
FRAMES = InputPort("frames", dict, Ref("/perception/frames"), doc="the latest frame of each camera, by name")
HEAD = InputPort("ptu", PanTiltState, Ref("/ptu/state"), doc="the pan-tilt head (absent: a fixed camera)")
HEAD_COMMAND = OutputPort("ptu_command", PanTiltCommand, "/ptu/command", unit="rad, rad/s",
                          doc="levels the pan-tilt head before images are taken")
SPEED = InputPort("speed", float, 0.3, unit="m/s", minimum=0.01, maximum=1.2, doc="top driving speed")
TURN_SPEED = InputPort("turn_speed", float, 45.0, unit="deg/s", minimum=1.0, maximum=300.0, doc="top turn rate")
SETTLE = InputPort("settle", float, 0.3, unit="s", minimum=0.0, maximum=5.0,
                   doc="time at rest before an image is taken")
ROBOT_RADIUS = InputPort("robot_radius", float, 0.0, unit="m", minimum=0.0, maximum=2.0, literal_only=True,
                         doc="radius of the disc the robot occupies (with a margin); 0: the disc round the robot's "
                             "own footprint ('footprint') grown by 0.02 m")
DISC_MARGIN = 0.02  # m: robot_radius 0 is the footprint's disc grown by this (a P3-DX's 0.26 m: 0.28 m)
RANGES_IN = InputPort("ranges", RangeScan, Ref(RANGES_KEY.path),
                      doc="range sensors around the base: a homing judges its sidesteps by them (absent: not judged)")
RANGES_MEMORY = 1.0  # s of echoes judged together (a sonar ring fires one transducer at a time)
ROUTINE_PORTS: tuple[Port, ...] = (CAMERA, CAMERA_OFFSET, SPEED, TURN_SPEED, SETTLE, ODOMETRY, STALLED, FRAMES, HEAD,
                                   FOOTPRINT, COMMAND, HEAD_COMMAND)
"""Ports every routine has: its camera, motion limits, the robot's state and footprint, its two commands."""


def robot_disc(host: BearingsBehaviour) -> float:
    """The radius of the disc ``host`` plans the robot as: its ``robot_radius``, or (0) the disc round
    the robot's own footprint (:mod:`behaviours.footprint`) grown by :data:`DISC_MARGIN`."""
    given = host.get_input(ROBOT_RADIUS)
    return given if given > 0.0 else robot_radius(host, 0.0) + DISC_MARGIN


class RoutineBehaviour(BearingsBehaviour):
    """A leaf whose work is :meth:`routine`, a generator advanced once per tick (module docstring)."""

    PORTS: ClassVar[tuple[Port, ...]] = ROUTINE_PORTS
    RANGES_OPTIONAL = True  # a node with RANGES_IN judges nothing without them (missions.log_check)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.camera_offset = self.pair(CAMERA_OFFSET)
        self._routine: Step[None] | None = None
        self._motion: BearingsBehaviour | None = None
        self._last_direction = 1.0  # sign of the last drive: a stall is backed away from the other way
        self._echoes = ObstacleMemory(RANGES_MEMORY)  # with RANGES_IN: the echoes of the last second, odometry frame

    def pair(self, port: InputPort[list[float]]) -> tuple[float, float]:
        """A literal ``[x, y]`` port (a position on the robot); ValueError naming the port otherwise."""
        value = self.get_input(port)
        if len(value) != 2:
            raise ValueError(f"{type(self).__name__}.{port.name} takes [x, y], got {value}")
        return value[0], value[1]

    # -- the coroutine ---------------------------------------------------------------------
    def routine(self) -> Step[None]:
        """The procedure; return for SUCCESS, raise :class:`Failed` for FAILURE."""
        raise NotImplementedError

    def initialise(self) -> None:
        self.feedback_message = ""
        self._routine = self.routine()

    def update(self) -> Status:
        self._remember_echoes()
        if self._routine is None:
            self._routine = self.routine()
        try:
            next(self._routine)
        except StopIteration:
            self._routine = None
            return Status.SUCCESS
        except Failed as exc:
            self._routine = None
            self.feedback_message = str(exc)
            return Status.FAILURE
        return Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        if self._routine is not None:  # halted while running: unwind (stops the motion node)
            self._routine.close()
            self._routine = None
        if new_status != Status.RUNNING:
            self.set_output(COMMAND, STOP)

    def written(self, port: OutputPort[T]) -> T | None:
        """What this node last wrote to an output port (None before it wrote), for reports and views."""
        try:
            return self.bb.get(self.output_key(port))
        except KeyError:
            return None

    # -- motion through the motion nodes ---------------------------------------------------------
    def run_motion(self, node: BearingsBehaviour, what: str, expected: float) -> Step[None]:
        """Tick a motion node once per tick until it finishes; its failure (a stall, held by the
        collision monitor for its ``held_timeout``) is :class:`Failed`, and so is taking more than
        ``MOTION_SLACK`` times the ``expected`` duration (s) plus ``MOTION_MARGIN`` (a robot pushing
        against something it does not feel). Time the monitor holds the motion does not count
        towards that: a person crossing the dodecagon's side gets the motion node's ``held_timeout``
        (20 s) to pass, not the 7.5 s a 0.25 m side is given (in an untuned library a walker
        crossing the hall failed the room estimation at its 11th corner)."""
        node.setup(clock=self.clock)
        self._motion = node
        last = self.now()
        deadline = last + MOTION_SLACK * expected + MOTION_MARGIN
        try:
            while True:
                node.tick_once()
                if node.status == Status.SUCCESS:
                    return
                if node.status == Status.FAILURE:
                    raise Failed(f"{what}: {node.feedback_message or 'failed'}")
                now = self.now()
                if isinstance(node, OdometryMotion) and node.held_since is not None:
                    deadline += now - last
                last = now
                if now > deadline:
                    raise Failed(f"{what}: no progress ({node.feedback_message})")
                self.feedback_message = f"{what}: {node.feedback_message}"
                yield
        finally:
            if node.status == Status.RUNNING:
                node.stop(Status.INVALID)  # its terminate commands a stop
            with contextlib.suppress(KeyError):  # the blackboard was cleared under a generator closed late
                node.bb.unregister(clear=False)
            self._motion = None

    def _bound(self) -> dict[str, Any]:
        """This node's motion ports as bound (literal, reference or remapped key), for a motion node."""
        return {ODOMETRY.name: self.inputs[ODOMETRY.name], STALLED.name: self.inputs[STALLED.name],
                COMMAND.name: self.output_key(COMMAND)}

    def rotate(self, angle: float, what: str = "turning") -> Step[None]:
        """Turn on the spot by ``angle`` (rad, counter-clockwise) with :class:`~behaviours.motion.Rotate`.

        The stall flag is not read: turning on the spot sweeps nothing for a disc robot, and the
        flag a contact left must not stop the turn that leads away from it."""
        if abs(angle) < MIN_TURN:
            return
        bound = {**self._bound(), STALLED.name: False}
        rate = self.get_input(TURN_SPEED)
        node = Rotate(name=f"{self.name}: {what}", angle=math.degrees(angle), speed=rate, tolerance=0.5, **bound)
        yield from self.run_motion(node, what, abs(math.degrees(angle)) / rate)

    def turn_to(self, heading: float, what: str = "turning") -> Step[None]:
        """Turn to an odometry heading (rad)."""
        pose = yield from self.pose()
        yield from self.rotate(wrap_angle(heading - pose.theta), what)

    def drive(self, distance: float, what: str = "driving", *, ignore_stall: bool = False) -> Step[None]:
        """Drive straight (negative: backwards) with :class:`~behaviours.motion.Drive`."""
        if abs(distance) < 0.005:
            return
        bound = self._bound()
        if ignore_stall:
            bound[STALLED.name] = False  # backing away from a contact: the stall flag stays up until it moves
        else:
            yield from self._clear_stall()
            self._last_direction = math.copysign(1.0, distance)
        speed = self.get_input(SPEED)
        node = Drive(name=f"{self.name}: {what}", distance=distance, speed=speed, **bound)
        yield from self.run_motion(node, what, abs(distance) / speed)

    def drive_to(self, x: float, y: float, what: str = "driving", tolerance: float = 0.02) -> Step[None]:
        """Drive to the odometry point (x, y): turn on the spot to face it, then
        :class:`~behaviours.motion.DriveTo`, so the path is the straight segment a planner or an edge
        assumes (DriveTo alone turns in place only beyond 30 degrees and arcs below that)."""
        pose = yield from self.pose()
        if math.hypot(x - pose.x, y - pose.y) <= tolerance:
            return
        yield from self._clear_stall()
        yield from self.turn_to(math.atan2(y - pose.y, x - pose.x), what)
        pose = yield from self.pose()
        self._last_direction = 1.0
        speed = self.get_input(SPEED)
        node = DriveTo(name=f"{self.name}: {what}", x=x, y=y, speed=speed, tolerance=tolerance, **self._bound())
        turn = abs(wrap_angle(math.atan2(y - pose.y, x - pose.x) - pose.theta))
        yield from self.run_motion(node, what, math.hypot(x - pose.x, y - pose.y) / speed
                                   + math.degrees(turn) / self.get_input(TURN_SPEED))

    def go_to_pose(self, pose: Pose2D, what: str = "driving") -> Step[None]:
        """Drive to an odometry pose: to its position, then turn to its heading."""
        yield from self.drive_to(pose.x, pose.y, what)
        yield from self.turn_to(pose.theta, what)

    def attempted(self, motion: Step[None]) -> Step[str]:
        """Run a motion; '' when it finished, the reason when it failed (held short by something in
        the way, a stall), for a caller that goes on from wherever it stopped."""
        try:
            yield from motion
        except Failed as exc:
            return str(exc)
        return ""

    def back_off(self, distance: float | None = None) -> Step[None]:
        """Move away from a contact after a stall (``distance`` signed; default 0.2 m against the last drive)."""
        step = -0.2 * self._last_direction if distance is None else distance
        yield from self.drive(step, "backing away from a contact", ignore_stall=True)

    def _clear_stall(self) -> Step[None]:
        """Before a drive: a stall flag still up from an earlier contact is backed away from first."""
        if self.get_input(STALLED, False):
            yield from self.back_off()

    # -- what the range sensors show ------------------------------------------------------------
    def _remember_echoes(self) -> None:
        """Every tick, for a node with ``ranges``: add the newest scan to the echoes remembered."""
        if RANGES_IN.name not in self.inputs:
            return
        scan, pose = self.get_input(RANGES_IN, None), self.get_input(ODOMETRY, None)
        if scan is not None and pose is not None:
            self._echoes = self._echoes.added(scan.points(), pose, scan.stamp)

    def sensed(self) -> np.ndarray | None:
        """The echoes of the last :data:`RANGES_MEMORY` seconds around the base now (base frame, N x 2),
        or None when the node reads no range sensors (no ``ranges`` port, or nothing read yet)."""
        pose = self.get_input(ODOMETRY, None)
        if RANGES_IN.name not in self.inputs or not self._echoes.stamps or pose is None:
            return None
        return self._echoes.around(pose, self.now())

    # -- state and images -------------------------------------------------------------------------
    def pose(self) -> Step[Pose2D]:
        """The odometry pose (waits for the first reading)."""
        while True:
            pose = self.get_input(ODOMETRY, None)
            if pose is not None:
                return pose
            self.feedback_message = "waiting for odometry"
            yield

    def level_head(self) -> Step[None]:
        """Bring the pan-tilt head to pan 0, tilt 0 (nothing to do without one)."""
        deadline = self.now() + HEAD_TIMEOUT
        while True:
            state = self.get_input(HEAD, None)
            if state is None or (abs(state.pan) <= HEAD_TOLERANCE and abs(state.tilt) <= HEAD_TOLERANCE
                                 and not state.moving):
                return
            if self.now() > deadline:
                raise Failed("the pan-tilt head does not reach pan 0, tilt 0")
            self.set_output(HEAD_COMMAND, PanTiltCommand(0.0, 0.0, HEAD_SPEED))
            yield

    def capture(self, camera: str | None = None) -> Step[tuple[Frame, Pose2D]]:
        """The next image of ``camera`` (default: the ``camera`` port) taken at rest, and the odometry
        pose it was taken from (see :meth:`capture_all`)."""
        name = camera or self.get_input(CAMERA)
        frames, pose = yield from self.capture_all((name,))
        return frames[name], pose

    def capture_all(self, cameras: tuple[str, ...]) -> Step[tuple[dict[str, Frame], Pose2D]]:
        """Images of several cameras taken at rest in the same tick, and the odometry pose: waits until
        the head is level, the odometry has not moved for a tick and ``settle`` seconds have passed,
        then for frames stamped after that."""
        yield from self.level_head()
        settle = self.get_input(SETTLE)
        start = self.now()
        last: Pose2D | None = None
        while True:
            pose = self.get_input(ODOMETRY, None)
            frames = self.get_input(FRAMES, None) or {}
            fresh = {n: f for n in cameras
                     if isinstance(f := frames.get(n), Frame) and f.stamp >= start + settle - 1e-6}
            if last is not None and pose is not None and _same_place(pose, last) and len(fresh) == len(cameras):
                return fresh, pose
            if self.now() - start > CAPTURE_TIMEOUT:
                raise Failed(f"no image from camera {', '.join(cameras)} at rest within {CAPTURE_TIMEOUT:g} s")
            last = pose
            self.feedback_message = f"waiting for an image from {', '.join(cameras)}"
            yield


def _same_place(a: Pose2D, b: Pose2D) -> bool:
    return abs(a.x - b.x) < 1e-4 and abs(a.y - b.y) < 1e-4 and abs(wrap_angle(a.theta - b.theta)) < 1e-4
