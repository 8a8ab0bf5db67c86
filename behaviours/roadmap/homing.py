"""Homing to a target image by the planar essential matrix (docs/design.md, method 2, "Homing").

The routine :func:`home` drives the robot to where a target image was taken; ``TargetHoming``,
``ReturnToReference``, ``BuildGraph`` and ``NavigateToTarget`` all use it.

Paper: the planar essential matrix between the current image and the target image gives the
turn and the direction of travel (:mod:`perception.planar`); the distance comes "from a third
image after a step of known length". One round here:

1. **Look**: an image at rest, compared with the target (upright SIFT, ratio 0.65, planar
   essential matrix). Too few inliers: the target is lost, homing fails.
2. **Align**: when the target image faces more than ``align`` (20 deg) away, turn by the
   estimated turn first (at most twice), so the views overlap as much as possible.
3. **Step**: move the camera ``step`` metres PERPENDICULAR to the estimated direction of the
   target (best conditioned triangle), driving backwards when that is closer to the current
   heading than driving forwards (no turn over 90 deg), then turn back to the first heading and
   look again: the third image. With a room estimate (``room``), the side whose step ends on
   free floor goes first; a stall, or no match after the step, tries the other side. With range
   sensors (``ranges``) the step is judged before it starts (:mod:`behaviours.roadmap.room_to_move`):
   a side with something in the way gives way to the other side, and with neither free for the
   whole step, the side with more room is taken with the step shortened to it (at least
   ``MIN_STEP``; less on both sides: homing fails, "no room to step sideways").
4. **Triangulate** (:func:`perception.planar.distance_from_third_image`): the two homing rays
   meet where the target image was taken. The camera pose there is that point with the mean of
   the two estimated headings; the robot pose follows from the camera's place on the robot. The
   two images must agree on the target's heading within ``HEADING_AGREEMENT`` (3 deg): a view
   dominated by one flat wall makes the planar essential matrix ambiguous, and the two estimates
   of one such pair then disagree by 5-15 degrees (measured in a 4.5 x 3.5 m room). A triangle
   that fails (no match after the step, no parallax, disagreement) is not driven on: the image
   after the step starts the next triangle, on the other side.
5. **Go**: drive there (along a planned path when a room estimate is known and the goal is more
   than 0.5 m away) and turn to its heading. When the estimate is within ``done_distance``
   of where the robot stood when the round began, the robot was there already: homing
   succeeds, and the result is that estimated pose (in the odometry frame), not the odometry
   after driving (which adds the drive's error). So homing takes at least two rounds: one to
   get there, one to confirm.

A first image that gives the turn but no direction (no parallax left after the turn: the
camera is within a few centimetres of the target, or along its optical axis within about 3 %
of the scene's depth) cannot be one end of the triangle either. More than ``max_rounds``
rounds, or more than three failed triangles: homing failed.

Why the sidestep and not the step along the homing direction: a step towards the target gives
no parallax (``distance_from_third_image`` refuses it). Why drive to the estimate rather than
servo on the image: the paper's method measures distance once per round; two rounds bring a
target seen 2 m away to within a few centimetres (errors shrink with the distance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from behaviours.ports import InputPort, OutputPort, Port, Ref
from behaviours.registry import register
from behaviours.roadmap.paths import travel
from behaviours.roadmap.room import ROOM_IN
from behaviours.roadmap.room_to_move import straight_reach
from behaviours.roadmap.routine import (
    RANGES_IN,
    ROBOT_RADIUS,
    ROUTINE_PORTS,
    Failed,
    RoutineBehaviour,
    Step,
    robot_disc,
)
from behaviours.roadmap.scan import MIN_INLIERS_IN
from behaviours.roadmap.targets import TARGETS_IN
from behaviours.roadmap.values import HomingResult, TargetView
from behaviours.roadmap.vision import (
    Comparison,
    camera_pose,
    compare_frame,
    mean_angle,
    optical_step,
    robot_pose,
)
from maps.room import RoomEstimate
from perception.geometry import Pose2D, wrap_angle
from perception.planar import distance_from_third_image

ALIGN = math.radians(20.0)  # turn towards the target's heading first beyond this
MAX_ALIGNS = 2
MAX_SIDESTEP_FAILURES = 3
HEADING_AGREEMENT = math.radians(3.0)  # the two images must agree on the target's heading
PLANNED_BEYOND = 0.5  # m: longer homing drives follow a planned path when the room is known
MIN_STEP = 0.10  # m: a sidestep shortened to the room the range sensors show is no shorter than this

STEP = InputPort("step", float, 0.25, unit="m", minimum=0.05, maximum=1.0,
                 doc="sidestep for the third image (paper: a step of known length)")
DONE_DISTANCE = InputPort("done_distance", float, 0.08, unit="m", minimum=0.005, maximum=1.0,
                          doc="homing ends after driving to an estimate measured from closer than this")
MAX_ROUNDS = InputPort("max_rounds", int, 5, minimum=1, maximum=20, literal_only=True,
                       doc="triangulation rounds before homing gives up")
ROOM_OPTIONAL = InputPort("room", RoomEstimate, None, doc="room estimate (optional): sidestep towards free floor first")
HOMING_PORTS: tuple[Port, ...] = (STEP, DONE_DISTANCE, MAX_ROUNDS, MIN_INLIERS_IN, ROOM_OPTIONAL, ROBOT_RADIUS,
                                  RANGES_IN)
REQUIRED_ROOM: tuple[Port, ...] = (STEP, DONE_DISTANCE, MAX_ROUNDS, MIN_INLIERS_IN, ROBOT_RADIUS, ROOM_IN, RANGES_IN)
"""The homing ports of a node that cannot work without the room estimate."""


@dataclass(frozen=True, slots=True)
class HomingSettings:
    """The homing ports of a behaviour, read once per homing."""

    step: float
    done_distance: float
    max_rounds: int
    min_inliers: int

    @classmethod
    def of(cls, host: RoutineBehaviour) -> HomingSettings:
        return cls(host.get_input(STEP), host.get_input(DONE_DISTANCE), host.get_input(MAX_ROUNDS),
                   host.get_input(MIN_INLIERS_IN))


def room_of(host: RoutineBehaviour) -> RoomEstimate | None:
    """The host's room estimate, whether it declares the room optional (``HOMING_PORTS``) or required
    (``REQUIRED_ROOM``): both ports are named ``room``."""
    return host.get_input(ROOM_OPTIONAL, None)


@dataclass(frozen=True, slots=True)
class Look:
    """An image compared with a target: robot and camera odometry poses, the comparison."""

    odometry: Pose2D
    camera: Pose2D
    comparison: Comparison
    stamp: float

    @property
    def turn(self) -> float:
        return self.comparison.planar.theta

    @property
    def bearing(self) -> float:
        return self.comparison.planar.bearing


def look(host: RoutineBehaviour, target: TargetView) -> Step[Look]:
    """Take an image at rest and compare it with the target."""
    frame, odometry = yield from host.capture()
    comparison = compare_frame(frame, target.features, target.camera)
    return Look(odometry, camera_pose(odometry, host.camera_offset), comparison, frame.stamp)


def home(host: RoutineBehaviour, target: TargetView, settings: HomingSettings) -> Step[HomingResult]:
    """Drive to where ``target`` was taken (module docstring); :class:`Failed` when it cannot."""
    aligns, failures, rounds, side = 0, 0, 0, 1
    ready: Look | None = None  # a look already taken from where the robot stands
    start: Pose2D | None = None  # where the robot stood when the round began
    while rounds < settings.max_rounds:
        host.feedback_message = f"homing on {target.name}: round {rounds + 1}"
        first = ready or (yield from look(host, target))
        start = first.odometry if ready is None else start
        ready = None
        if not first.comparison.matched(settings.min_inliers):
            raise Failed(f"lost sight of {target.name} ({first.comparison.inliers} inliers)")
        if abs(first.turn) > ALIGN and aligns < MAX_ALIGNS:
            aligns += 1
            yield from host.rotate(first.turn, f"facing as {target.name} does")
            continue
        side, length = _step_plan(host, first, settings, _free_side(host, first, settings, side))
        second = yield from _sidestep(host, target, first, side, length, settings)
        estimate = _triangulate(first, second, host.camera_offset) if second is not None else None
        if estimate is None:
            failures += 1
            if failures > MAX_SIDESTEP_FAILURES:
                raise Failed(f"no distance to {target.name}: the third image did not match or showed no parallax")
            if second is not None:
                ready = second  # the next triangle starts from the image just taken
            side = -side
            continue
        rounds += 1
        goal = estimate[0]
        correction = goal.distance_to(start) if start is not None else math.inf
        yield from _go(host, goal, f"homing on {target.name} ({correction:.2f} m)")
        if correction < settings.done_distance:  # the round found the robot where it started: it is there
            return HomingResult(target.name, goal, correction, rounds, first.comparison.inliers, host.now())
    raise Failed(f"homing on {target.name} did not converge in {settings.max_rounds} rounds")


def home_after(host: RoutineBehaviour, target: TargetView, settings: HomingSettings, held: str
               ) -> Step[HomingResult]:
    """:func:`home` after a motion towards ``target``; ``held``: why that motion stopped short of its
    end ('' when it arrived), named in the failure (a drive held short homes from where it stopped)."""
    try:
        return (yield from home(host, target, settings))
    except Failed as exc:
        raise Failed(f"{held}; homing from there: {exc}" if held else str(exc)) from None


def _go(host: RoutineBehaviour, goal: Pose2D, what: str) -> Step[None]:
    """Drive to an odometry pose: along a planned path when a room estimate is known and the goal is
    farther than ``PLANNED_BEYOND`` (homing from afar must not run into the furniture in between),
    else straight."""
    room = room_of(host)
    here = yield from host.pose()
    if room is not None and here.distance_to(goal) > PLANNED_BEYOND:
        try:
            yield from travel(host, room, room.to_reference(goal), turn=True)
            return
        except Failed:
            pass  # no path in the room estimate (a target off the free polygon): straight, as without a room
    yield from host.go_to_pose(goal, what)


def _step_motion(first: Look, side: int) -> tuple[float, float]:
    """(turn, signed distance factor) of the sidestep: perpendicular to the homing direction,
    backwards when that needs the smaller turn."""
    direction = wrap_angle(first.bearing + side * math.pi / 2.0)
    if abs(direction) > math.pi / 2.0:
        return wrap_angle(direction - math.pi), -1.0
    return direction, 1.0


def _free_side(host: RoutineBehaviour, first: Look, settings: HomingSettings, side: int) -> int:
    """With a room estimate, the side whose sidestep ends on free floor (``side`` when both or neither)."""
    room = room_of(host)
    if room is None:
        return side
    free = []
    for candidate in (side, -side):
        turn, sign = _step_motion(first, candidate)
        heading = first.odometry.theta + turn
        end = Pose2D(first.odometry.x + sign * settings.step * math.cos(heading),
                     first.odometry.y + sign * settings.step * math.sin(heading))
        there = room.to_reference(end)
        free.append(bool(room.free.can_stand(np.array([[there.x, there.y]]), robot_disc(host))[0]))
    return -side if (free[1] and not free[0]) else side


def _step_plan(host: RoutineBehaviour, first: Look, settings: HomingSettings, side: int) -> tuple[int, float]:
    """The side and the length of the sidestep, judged against the range sensors before it starts
    (module docstring, step 3): ``side`` when it has room for the whole step (or nothing is sensed),
    else the other side when that has, else the side with more room, the step shortened to it."""
    points = host.sensed()
    if points is None:
        return side, settings.step
    radius = robot_disc(host)
    room: dict[int, float] = {}
    for candidate in (side, -side):
        turn, sign = _step_motion(first, candidate)
        room[candidate] = straight_reach(points, radius, turn if sign > 0 else wrap_angle(turn + math.pi),
                                         settings.step)
        if room[candidate] >= settings.step:
            return candidate, settings.step
    best = max(room, key=lambda c: room[c])
    if room[best] < MIN_STEP:
        raise Failed(f"no room to step sideways for the third image ({room[side]:.2f} m and {room[-side]:.2f} m "
                     f"free, at least {MIN_STEP:g} m needed)")
    return best, room[best]


def _sidestep(host: RoutineBehaviour, target: TargetView, first: Look, side: int, length: float,
              settings: HomingSettings) -> Step[Look | None]:
    """Step sideways ``length`` metres, turn back to the first heading and look again (None: stalled
    or no match)."""
    turn, sign = _step_motion(first, side)
    yield from host.rotate(turn, "turning for the sidestep")
    try:
        yield from host.drive(sign * length, "sidestep for the third image")
    except Failed:
        yield from host.back_off(-sign * 0.1)
        yield from host.turn_to(first.odometry.theta, "turning back")
        return None
    yield from host.turn_to(first.odometry.theta, "turning back")
    second = yield from look(host, target)
    return second if second.comparison.matched(settings.min_inliers) else None


def _triangulate(first: Look, second: Look, offset: tuple[float, float]) -> tuple[Pose2D, float] | None:
    """The robot pose of the target (odometry frame) and the first camera's distance to it."""
    step, turn = optical_step(first.camera, second.camera)
    found = distance_from_third_image(first.comparison.planar, second.comparison.planar, step, turn)
    headings = (first.camera.theta + first.turn, second.camera.theta + second.turn)
    if not found.ok or abs(wrap_angle(headings[0] - headings[1])) > HEADING_AGREEMENT:
        return None
    b, d = first.bearing, found.from_first
    there = first.camera.compose(Pose2D(d * math.cos(b), d * math.sin(b), 0.0))
    heading = mean_angle(*headings)
    return robot_pose(Pose2D(there.x, there.y, heading), offset), d


@register
class TargetHoming(RoutineBehaviour):
    """Home to a target image (planar essential matrix, distance from a third image); write where it is.

    The result (``homing``) is the robot pose of the target in the odometry frame, the robot
    standing there. The homing procedure is in this module's docstring.
    """

    TARGET = InputPort("target", str, Ref("/map/sighting.target"), doc="name of the target to home to")
    HOMING = OutputPort("homing", HomingResult, "/map/homing", doc="where the target is (odometry frame)")
    PORTS = (TARGET, TARGETS_IN, *HOMING_PORTS, *ROUTINE_PORTS, HOMING)

    def routine(self) -> Step[None]:
        name = self.get_input(self.TARGET, None)
        targets = self.get_input(TARGETS_IN, None)
        if not name or targets is None:
            raise Failed("no target to home to" if not name else "no target images")
        try:
            view = targets.get(name)
        except KeyError as exc:
            raise Failed(str(exc.args[0])) from None
        result = yield from home(self, view, HomingSettings.of(self))
        self.set_output(self.HOMING, result)
        self.feedback_message = f"at {name} after {result.iterations} rounds"
