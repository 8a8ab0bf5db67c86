"""Following the exploration goal's path through the known free floor, safely.

:class:`FollowPath` drives along the path of the goal on its ``goal`` input (the travel-cost path of
:mod:`maps.exploration.travel`: 8-connected cells through known free space with clearance) with the
control of :class:`behaviours.motion.DriveTo`: turn on the spot towards a carrot ``lookahead``
metres down the path when it is more than ``turn_in_place`` off the heading, else drive while
steering, speed ramped down near the end within the deceleration limit, capped by ``speed_limit``
(the gaze's eq. 4).

Collision safety has its own checks, because the cameras see nothing nearer than ~0.66 m (96
disparities) and may be looking sideways:

- **Path ahead**: the path's next ``check_distance`` metres must keep the robot's disc clear of
  obstacle cells in the current map; otherwise it is planned again from here
  (:func:`maps.exploration.travel.travel_cost`), and FAILURE when the target cannot be reached any more.
  Where the path runs on the robot's own trail, only obstacle cells on the trail itself block it
  (:func:`maps.exploration.queries.blocking_cells`): it fitted there, as the travel cost says too;
  in `flat` a robot in a slot its map had since narrowed gave up every goal for 690 s.
- **Motion**: the speed lets the base stop (within its deceleration) before the arc it is driving
  brings an obstacle cell within ``robot_radius + clearance`` of its centre, nearer than now
  (:func:`maps.exploration.queries.free_travel`). Pure pursuit cuts corners, and a stop commanded at once still coasts a
  quarter of a metre at 0.4 m/s (0.3 m/s^2): in one simulated run the robot swung round a table's
  corner on a path planned clear of it and touched it while coasting. Where that stops the robot,
  it steers to the path point ``CLOSE_LOOKAHEAD`` away instead (turning on the spot to it when
  that is farther off than ``turn_in_place``): it follows the path itself where cutting its corner
  would come too near something (in `flat` the robot stood beside a dining table, the carrot 30
  degrees off, the arc to it closing on the table's edge, until each goal was given up).
- **Seen floor ahead only**: the robot does not drive *into* floor it has not seen: it brakes to
  ``crawl`` ``unseen_margin`` before the first point of the path ahead where the front of its disc
  (within ``front`` of the direction of travel) covers an unknown cell (beyond the disc it covers
  now), and stops before its disc covers it. Those cells go to ``unseen_ahead`` (None when the
  next ``guard`` metres are seen), for the gaze to look at, since the cameras may be watching
  something else (:class:`behaviours.exploration.gaze.WatchInterestEdges`). The margin is where the cameras can
  still see that floor (their near edge is ~0.36 m from the lens at the lowest tilt), and the
  crawl stops within 2 cm when they find an obstacle there (in one simulated run the robot, at
  full speed with unseen floor 0.6 m ahead round a table's corner, saw the corner, gave the goal
  up and touched it while coasting). Stopping at the margin instead deadlocks at corners: the
  floor round a corner is seen only by moving along the path. Unknown floor *beside* the path does
  not hold the robot: within ~0.5 m of the lens the cameras see nothing, so floor beside a path
  along a border would never become seen from it (tried: the robot stalled at every border it
  drove along); a tall obstacle there would have been seen ahead, from farther away, by cameras
  looking where the robot goes. The goal itself is a border point, next to the unknown: the robot
  stops about a radius before it unless the cameras see beyond it first.
- **Someone walking towards the robot**: the echoes of the range sensors that look along the
  line of travel (whose cone holds the heading: the Pioneer's two front sonars at +-10 degrees)
  cap the speed at one from which the robot stops before an obstacle there reaches it, were it
  walking towards the robot at ``approach`` m/s (:func:`approach_speed`, eq. A). Echoes are
  placed on a sensor's axis, anywhere in its 30-degree cone: the +-30 and +-50 degree sonars put
  a corridor's walls 0.55 m beside the line of travel, which held the robot to a crawl when they
  counted. The map and the avoidance judge the way against where things
  are *now*: in a simulated office run the robot drove at 0.36 m/s through a door into the meeting
  room towards a person walking at 0.6 m/s towards it, 0.84 m away; the avoidance's check (the
  braking distance and 0.5 s of travel, 0.57 m) found the way free until 0.4 s before the contact,
  and the base, braking, touched the person who had stopped for it. A person 1 m ahead walking
  towards the robot at 1 m/s leaves it 0.2 m/s; 2 m ahead, full speed.
- **Something stepping onto the path**: when the path ahead is blocked and no path round reaches
  the goal, but the obstacle cells that block it were free floor on the last map on which the way
  was clear (something moved there: a person walking past or standing in a door), the robot stops
  and waits up to ``wait`` seconds for them to clear (the map clears a cell once the floor past it
  is seen) before it gives the goal up. What was unknown before (a wall just seen) gives it up at
  once. Before, a person crossing a door the robot was about to pass made it give every goal
  beyond the door up, one after another, and end "done" with the rooms behind unvisited.
- **Progress**: no metre of path gained for ``stuck_time`` seconds (a stop before unseen floor the
  cameras cannot see from here: nearer than their ~0.5 m blind zone): FAILURE, so that a recovery
  looks around and the goal is chosen again.
- **Stall** (a collision after all): back away for ``backoff`` seconds, then go on; FAILURE after
  ``max_stalls`` stalls on one goal.

It never succeeds: it follows whatever goal is on the blackboard, stopping on arrival until the
next one (run it beside :class:`behaviours.exploration.select_goal.SelectGoalPoint` in a parallel whose
success is the selection's). FAILURE (unreachable, stalls) lets a recovery run and the selection
choose again.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.exploration.ports import CLEARANCE, GOAL, MAP, MARGIN, PENALTY, POSE, ROBOT_RADIUS, disc_radius
from behaviours.footprint import FOOTPRINT
from behaviours.keys import RANGES_KEY
from behaviours.motion import ANGULAR_DECEL, COMMAND, LINEAR_DECEL, STALLED, ramp
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.telemetry import Drawing, Figure, Lines
from drivers.interfaces import STOP, VelocityCommand
from maps import pursuit
from maps.exploration.goal import Goal
from maps.exploration.grid import Cell, ExplorationMap
from maps.exploration.queries import blocking_cells, cells_around, free_travel, moved_onto
from maps.exploration.travel import travel_cost
from perception.geometry import Pose2D, wrap_angle
from perception.ranges import RangeScan

CLOSE_LOOKAHEAD = 0.1  # m: the carrot when the one ``lookahead`` away cuts a corner too near something


@dataclass(frozen=True, slots=True)
class _Step:
    """One tick's command towards a carrot: ``error`` its bearing off the heading (rad); ``turning`` on
    the spot first; ``blind``: stopped short of unseen floor; ``held_by_map``: stopped by an obstacle
    cell the arc would bring within the room."""

    v: float
    w: float
    error: float
    turning: bool = False
    blind: bool = False
    held_by_map: bool = False


def approach_speed(gap: float, approach: float, decel: float, reaction: float, clearance: float) -> float:
    """The top speed (m/s) from which the robot stops, ``reaction`` s after seeing it and braking at
    ``decel``, before an obstacle ``gap`` metres ahead of its disc that walks towards it at
    ``approach`` m/s comes within ``clearance``: the largest v with
    ``v^2 / (2 decel) + (v + approach) reaction + approach v / decel <= gap - clearance`` (eq. A)."""
    room = gap - clearance - approach * reaction
    if room <= 0.0:
        return 0.0
    b = reaction + approach / decel  # eq. A as a v^2 + b v - room <= 0, a = 1 / (2 decel)
    return decel * (math.sqrt(b * b + 2.0 * room / decel) - b)


@register
class FollowPath(BearingsBehaviour):
    """Follow the exploration goal's path with collision checks; RUNNING for ever, FAILURE when blocked.

    See :mod:`behaviours.exploration.follow_path` for the control and the safety checks.
    """

    SPEED = InputPort("speed", float, 0.4, unit="m/s", minimum=0.01, maximum=1.2, doc="top speed")
    SPEED_LIMIT = InputPort("speed_limit", float, 1.2, unit="m/s", minimum=0.0, maximum=5.0,
                            doc="a further cap (the gaze's eq. 4: {/robot/speed_limit})")
    TURN_RATE = InputPort("turn_rate", float, 60.0, unit="deg/s", minimum=1.0, maximum=300.0, literal_only=True,
                          doc="top turn rate")
    TOLERANCE = InputPort("tolerance", float, 0.3, unit="m", minimum=0.01, maximum=5.0, literal_only=True,
                          doc="stop this close to the goal")
    LOOKAHEAD = InputPort("lookahead", float, 0.4, unit="m", minimum=0.05, maximum=5.0, literal_only=True,
                          doc="steer towards the path point this far ahead")
    TURN_IN_PLACE = InputPort("turn_in_place", float, 35.0, unit="deg", minimum=1.0, maximum=180.0,
                              literal_only=True, doc="turn on the spot when the carrot is this far off the heading")
    CHECK_DISTANCE = InputPort("check_distance", float, 0.8, unit="m", minimum=0.0, maximum=10.0, literal_only=True,
                               doc="how much of the path ahead must stay clear")
    BACKOFF = InputPort("backoff", float, 1.0, unit="s", minimum=0.0, maximum=10.0, literal_only=True,
                        doc="after a stall, back away this long")
    MAX_STALLS = InputPort("max_stalls", int, 3, minimum=1, maximum=100, literal_only=True,
                           doc="stalls on one goal before giving it up")
    GUARD = InputPort("guard", float, 1.0, unit="m", minimum=0.0, maximum=10.0, literal_only=True,
                      doc="how much of the path ahead must be seen floor before the cameras may look elsewhere")
    STUCK_TIME = InputPort("stuck_time", float, 8.0, unit="s", minimum=0.5, maximum=600.0, literal_only=True,
                           doc="give the goal up after this long without progress")
    UNSEEN_MARGIN = InputPort("unseen_margin", float, 0.3, unit="m", minimum=0.0, maximum=5.0, literal_only=True,
                              doc="brake to a crawl this far before unseen floor ahead (the cameras can still see it)")
    CRAWL = InputPort("crawl", float, 0.1, unit="m/s", minimum=0.0, maximum=1.0, literal_only=True,
                      doc="the speed from there on, until the disc would touch it")
    FRONT = InputPort("front", float, 60.0, unit="deg", minimum=0.0, maximum=180.0, literal_only=True,
                      doc="unseen floor within this of the direction of travel holds the robot (180: the whole disc)")
    APPROACH = InputPort("approach", float, 1.0, unit="m/s", minimum=0.0, maximum=3.0, literal_only=True,
                         doc="stop in time for an obstacle in the lane ahead walking towards the robot this fast "
                             "(0: never mind)")
    REACTION = InputPort("reaction", float, 0.2, unit="s", minimum=0.0, maximum=5.0, literal_only=True,
                         doc="from an echo to braking (a tick, the sensors' cycle)")
    WAIT = InputPort("wait", float, 6.0, unit="s", minimum=0.0, maximum=600.0, literal_only=True,
                     doc="stopped, wait this long for free floor something moved onto (a person) to clear from a "
                         "blocked path before giving the goal up")
    RANGES = InputPort("ranges", RangeScan, Ref(RANGES_KEY.path), doc=RANGES_KEY.doc)
    UNSEEN_AHEAD: OutputPort[Pose2D | None] = OutputPort(
        "unseen_ahead", Pose2D, "/robot/unseen_ahead",
        doc="the first point of the path ahead whose disc covers unseen floor (None: none)")
    PORTS = (SPEED, SPEED_LIMIT, TURN_RATE, TOLERANCE, LOOKAHEAD, TURN_IN_PLACE, CHECK_DISTANCE, CLEARANCE,
             ROBOT_RADIUS, FOOTPRINT, MARGIN, PENALTY, BACKOFF, MAX_STALLS, GUARD, STUCK_TIME, UNSEEN_MARGIN, CRAWL,
             FRONT, APPROACH, REACTION, RANGES, GOAL, MAP, POSE, STALLED, COMMAND, UNSEEN_AHEAD, WAIT)
    RANGES_OPTIONAL = True  # without range sensors nothing is in the lane: the map's checks alone

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.goal: Goal | None = None
        self.path = np.zeros((0, 2))
        self.index = 0
        self.stalls = 0
        self.total_stalls = 0
        self.backing_until = -math.inf
        self.replans = 0
        self.safety_stops = 0
        self.blind_stops = 0
        self.stuck = 0
        self.waits = 0  # times the robot stopped for something that moved onto its path
        self.clear_map: ExplorationMap | None = None  # the last map on which the path ahead was clear
        self.waiting_since: float | None = None
        self.progress: tuple[float, float] = (math.inf, 0.0)  # best path length left, and when
        self._drawn: np.ndarray | None = None  # the path last drawn

    def initialise(self) -> None:
        self.goal, self.path, self.index, self.stalls = None, np.zeros((0, 2)), 0, 0
        self.backing_until = -math.inf
        self.clear_map, self.waiting_since = None, None

    def command(self, v: float, w: float) -> None:
        self.set_output(COMMAND, VelocityCommand(v, w))

    def update(self) -> Status:
        pose = self.get_input(POSE, None)
        m = self.get_input(MAP, None)
        self.set_output(self.UNSEEN_AHEAD, None)
        if pose is None or m is None:
            self.feedback_message = "waiting for a pose and the map"
            return Status.RUNNING
        if self.get_input(STALLED, False) and self.now() >= self.backing_until:
            self.stalls += 1
            self.total_stalls += 1
            if self.stalls > self.get_input(self.MAX_STALLS):
                self.command(0.0, 0.0)
                self.feedback_message = f"stalled {self.stalls} times: giving the goal up"
                return Status.FAILURE
            self.backing_until = self.now() + self.get_input(self.BACKOFF)
        if self.now() < self.backing_until:
            self.command(-0.1, 0.0)
            self.feedback_message = "stalled: backing away"
            return Status.RUNNING
        goal = self.get_input(GOAL, None)
        if goal is None:
            self.command(0.0, 0.0)
            self.feedback_message = "no goal"
            return Status.RUNNING
        if goal is not self.goal:
            fresh = self.goal is None or math.dist(goal.target, self.goal.target) > 0.25
            self.goal, self.path, self.index = goal, np.asarray(goal.path), 0
            if fresh:
                self.stalls, self.progress = 0, (math.inf, self.now())
        return self._follow(pose, m, goal)

    def _follow(self, pose: Pose2D, m: ExplorationMap, goal: Goal) -> Status:
        here = np.array([pose.x, pose.y])
        if math.dist(goal.target, here) <= self.get_input(self.TOLERANCE) or len(self.path) == 0:
            self.command(0.0, 0.0)
            self.feedback_message = "at the goal"
            return Status.RUNNING
        blocking = self._blocking(m, self.path[self.index:])
        if len(blocking):
            self.replans += 1
            planned = disc_radius(self) + self.get_input(CLEARANCE)
            travel = travel_cost(m, (pose.x, pose.y), planned,
                                 margin=self.get_input(MARGIN), penalty=self.get_input(PENALTY))
            path = travel.path_to(goal.target)
            if len(path) and not len(self._blocking(m, path)):
                self.path, self.index, self.waiting_since = path, 0, None
            elif self.clear_map is not None and moved_onto(self.clear_map, blocking):
                return self._wait()
            else:
                self.command(0.0, 0.0)
                self.feedback_message = "the goal cannot be reached any more"
                return Status.FAILURE
        else:
            self.clear_map, self.waiting_since = m, None
        self.index = self._nearest(here)
        carrot, remaining = self._carrot(here)
        if remaining < self.progress[0] - 0.05:
            self.progress = (remaining, self.now())
        elif self.now() - self.progress[1] > self.get_input(self.STUCK_TIME):
            self.stuck += 1
            self.command(0.0, 0.0)
            self.feedback_message = f"no progress for {self.get_input(self.STUCK_TIME):g} s: giving the goal up"
            return Status.FAILURE
        seen = self._seen_distance(m, here)
        step = self._towards(pose, m, carrot, remaining, seen)
        if step.held_by_map:  # the chord to the carrot cuts a corner too near something: follow the path itself
            near, _ = self._carrot(here, CLOSE_LOOKAHEAD)
            close = self._towards(pose, m, near, remaining, seen)
            step = close if close.turning or close.v > step.v else step
        if step.turning:
            self.command(0.0, step.w)
            self.feedback_message = f"turning towards the path ({math.degrees(step.error):+.0f} deg)"
            return Status.RUNNING
        self.blind_stops += int(step.blind)
        self.safety_stops += int(step.held_by_map)
        self.command(step.v, step.w)
        self.feedback_message = f"{remaining:.2f} m to go" + ("" if math.isinf(seen) else f", {seen:.2f} m seen")
        return Status.RUNNING

    def _towards(self, pose: Pose2D, m: ExplorationMap, carrot: np.ndarray, remaining: float, seen: float) -> _Step:
        """The command that steers to ``carrot``: a turn on the spot beyond ``turn_in_place``, else a
        drive capped by the path left, the speed limit, the unseen floor ahead, the lane's echoes and
        the map (the base stops before the arc brings an obstacle cell within the room)."""
        error = wrap_angle(math.atan2(carrot[1] - pose.y, carrot[0] - pose.x) - pose.theta)
        top_w = math.radians(self.get_input(self.TURN_RATE))
        w = ramp(error, top_w, ANGULAR_DECEL, 0.0) if error else 0.0
        if abs(error) > math.radians(self.get_input(self.TURN_IN_PLACE)):
            return _Step(0.0, w, error, turning=True)
        see = self.get_input(self.UNSEEN_MARGIN)  # brake to a crawl where the cameras can still see it
        crawl = self.get_input(self.CRAWL) if seen > m.frame.resolution else 0.0
        blind = max(math.sqrt(2.0 * LINEAR_DECEL * max(seen - see, 0.0)), crawl)
        v = min(ramp(remaining, self.get_input(self.SPEED), LINEAR_DECEL, 0.02),
                self.get_input(self.SPEED_LIMIT, math.inf), blind)
        v = max(0.0, min(v, self._lane_speed()) * math.cos(error))
        room = disc_radius(self) + self.get_input(CLEARANCE)
        reach = self.get_input(self.SPEED) ** 2 / (2.0 * LINEAR_DECEL) + 0.1
        free = free_travel(m, pose, w / max(v, 0.05), room, reach)
        v = min(v, math.sqrt(2.0 * LINEAR_DECEL * max(free - m.frame.resolution, 0.0)))  # stops in time
        return _Step(v, w, error, blind=blind < 0.02, held_by_map=free < reach and v < 0.02)

    def _lane_speed(self) -> float:
        """The speed cap of the echoes straight ahead (eq. A; inf without range sensors or such echoes):
        those of the sensors whose cone holds the heading, each at its range along its axis."""
        scan = self.get_input(self.RANGES, None)
        approach = self.get_input(self.APPROACH)
        if not isinstance(scan, RangeScan) or approach <= 0.0:
            return math.inf
        gaps = [math.hypot(s.x + r * math.cos(s.heading), s.y + r * math.sin(s.heading))
                for s, r in zip(scan.sensors, np.asarray(scan.ranges, dtype=float), strict=True)
                if math.isfinite(r) and abs(wrap_angle(s.heading)) <= s.fov / 2.0]
        if not gaps:
            return math.inf
        gap = min(gaps) - disc_radius(self)
        return approach_speed(gap, approach, LINEAR_DECEL, self.get_input(self.REACTION), self.get_input(CLEARANCE))

    def _nearest(self, here: np.ndarray) -> int:
        """The path point nearest the robot, searching forward from the last one (no going back)."""
        return pursuit.place_along(self.path, self.index, self.index + 40, here)

    def _carrot(self, here: np.ndarray, lookahead: float | None = None) -> tuple[np.ndarray, float]:
        """The first path point ``lookahead`` (default: the input's) away from the robot, and the path
        length left."""
        ahead = self.path[self.index :]
        steps = np.hypot(*np.diff(ahead, axis=0).T) if len(ahead) > 1 else np.zeros(0)
        remaining = float(steps.sum()) + float(np.hypot(*(ahead[0] - here)))
        lookahead = self.get_input(self.LOOKAHEAD) if lookahead is None else lookahead
        return pursuit.carrot(self.path, self.index, here, lookahead), remaining

    def _ahead(self, ahead: np.ndarray) -> np.ndarray:
        """The points of the path ``ahead`` within its first ``check_distance``."""
        along = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(ahead, axis=0).T))))
        return ahead[along <= self.get_input(self.CHECK_DISTANCE)]

    def _blocking(self, m: ExplorationMap, ahead: np.ndarray) -> np.ndarray:
        """The obstacle cells (K x 2) the disc covers along the path ``ahead``'s first ``check_distance``
        (beside the robot's trail, only those on the trail itself: :func:`maps.exploration.queries.blocking_cells`).
        Were they all free floor on the last map on which the way was clear, something moved onto it
        (:func:`maps.exploration.queries.moved_onto`): a wait, not a give-up."""
        return blocking_cells(m, self._ahead(ahead), disc_radius(self), trail=True) if len(ahead) else np.zeros((0, 2))

    def _wait(self) -> Status:
        """Stopped for something that moved onto the path: RUNNING for ``wait`` seconds, then FAILURE."""
        now = self.now()
        if self.waiting_since is None:
            self.waiting_since = now
            self.waits += 1
        self.command(0.0, 0.0)
        self.progress = (self.progress[0], now)  # waiting is not being stuck
        waited = now - self.waiting_since
        if waited >= self.get_input(self.WAIT):
            self.feedback_message = f"the way stayed blocked for {waited:.0f} s: giving the goal up"
            return Status.FAILURE
        self.feedback_message = f"something moved onto the path: waiting for it to clear ({waited:.0f} s)"
        return Status.RUNNING

    def _seen_distance(self, m: ExplorationMap, here: np.ndarray) -> float:
        """Distance to the first point of the path ahead (within ``guard``) where the front of the disc
        (within ``front`` of the direction of travel) covers an unknown cell that the disc does not
        cover now (inf: none). The unknown cells found there go to ``unseen_ahead`` (their centroid).
        Unknown cells under the robot already (at the start, after a recovery) do not hold it, nor
        unknown floor beside the path: the cameras cannot see within ~0.5 m of the lens, so the floor
        beside a path along a border would never become seen from it."""
        radius = disc_radius(self)
        ahead = self.path[self.index :]
        along = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(ahead, axis=0).T))))
        cos_front = math.cos(math.radians(self.get_input(self.FRONT)))
        for k, (point, s) in enumerate(zip(ahead, along, strict=True)):
            if s > self.get_input(self.GUARD):
                break
            centres, rel, dist, states = cells_around(m, point, radius)
            heading = ahead[min(k + 1, len(ahead) - 1)] - ahead[max(k - 1, 0)]
            heading = heading / max(float(np.hypot(*heading)), 1e-9)
            new = (dist <= radius) & (np.hypot(*(centres - here).T) > radius) & (rel @ heading >= cos_front * dist)
            unknown = states == Cell.UNKNOWN
            if np.any(unknown & new):
                centroid = centres[unknown & new].mean(axis=0)
                self.set_output(self.UNSEEN_AHEAD, Pose2D(float(centroid[0]), float(centroid[1])))
                return float(np.hypot(*(point - here)))
        return math.inf

    def terminate(self, new_status: Status) -> None:
        if new_status != Status.RUNNING:
            self.set_output(COMMAND, STOP)
            self.set_output(self.UNSEEN_AHEAD, None)

    def figures(self) -> Iterator[Figure]:
        """The ``exploration`` section's driving part: stalls, re-plans, safety stops."""
        yield from (Figure("exploration", name, value) for name, value in (
            ("stalls", self.total_stalls), ("replans", self.replans), ("stuck", self.stuck), ("waits", self.waits),
            ("safety_stops", self.safety_stops), ("blind_stops", self.blind_stops)))

    def drawings(self) -> Iterator[Drawing]:
        """The path being followed (odometry frame), when it changed."""
        if len(self.path) < 2 or self._drawn is self.path:
            return
        self._drawn = self.path
        yield Lines("odometry_frame/exploration/followed", [self.path], (255, 255, 255), radius=0.015)
