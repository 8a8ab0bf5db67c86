"""Getting around what blocks the way: the ``AvoidObstacles`` decorator.

Wrapped around a motion node in a mission (``AvoidObstacles: {child: FollowRoute: {...}}``), it
lets the child steer as it always does and judges, after each tick of the child, the command the
child wrote (``child_command``: ``/robot/command`` unless remapped) against the range sensors
(``/robot/ranges``), the odometry and the collision monitor's verdict on the last command
(``/robot/safety``). It writes the command that gets around (``command``):

- the child's own, while its arc is free for as far as it means to go (no farther than the
  child's goal, when its command says how far that is: ``VelocityCommand.reach``);
- a stop while the way is blocked, for ``wait`` seconds, so a person walking across can pass;
- then a detour: of a histogram of directions, the free one closest to where the child heads, on
  one side of the obstacle, kept within ``max_stray`` of the line the robot was on (odometry),
  until the child's own arc is free again; the child then steers back to its route or path by
  itself;
- no direction will do: with ``plan``, a way round planned on the echoes of the last
  ``echo_memory`` seconds (:mod:`maps.avoidance.wayround`: back out of a pocket and round what
  holds the robot, to a metre past where it was held) and driven, the directions judged as before
  along it;
- no direction and no way round: backing away ``backoff`` metres along the way the robot came
  (:mod:`maps.avoidance.backoff`), then judging again from there;
- with ``undo``, a detour held until its ``timeout`` is driven back along its own way, once, and
  the other side tried for ``wait`` seconds more (a detour into a gap too narrow to pass);
- FAILURE, with the reason as the node's message ("blocked for 20 s by an obstacle 0.40 m
  ahead"), after ``timeout`` seconds held, or a detour of ``max_detour`` metres that did not get
  past, so that the mission's recovery (a search pattern, a new goal) takes over.

Otherwise its status is the child's. While it holds the robot for the way to clear by itself
(the first ``wait`` seconds of a wait, before it judges the ways round) it writes ``held`` true
(``/robot/held``; false otherwise, and when it ends): the child can tell that what it sees now is
partly hidden by the obstacle in front, and that the avoidance is about to act (``FollowRoute``
does not count losing the trail then, and leaves the avoidance its wait). The algorithm is
:mod:`maps.avoidance` (pure); the echoes of the last ``memory`` seconds are judged together
(:mod:`perception.obstacle_memory`). Without range sensors (no ``/robot/ranges``) it sees nothing and
passes every command on; the collision monitor still limits whatever reaches the base.
``enabled: false`` passes every command on, for runs that compare with and without it.

Report section ``avoidance``, per node (its name): ``waits``, ``waits_cleared`` (the way cleared by
itself), ``wait_time_s``, ``detours``, ``detour_length_m``, ``detour_time_s``, ``backoffs``,
``backoff_m``, ``ways`` (ways round planned) and ``way_m`` (driven along them), ``give_ups`` and
their ``reasons``. Recording: ``avoidance/events``,
``avoidance/phase`` (0 clear, 1 waiting, 2 detour, 3 backing away), the way round being driven
(``odometry_frame/avoidance/way``), the histogram of directions
judged (``avoidance/robot_frame/histogram``: a ray per direction as far as it is free up to 1 m,
the chosen one green, those that would do grey, the others red) with the chosen direction
(``avoidance/robot_frame/chosen``), and the detours driven (``odometry_frame/avoidance/detours``).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import numpy as np
import py_trees
from py_trees.common import Status

from behaviours.base import BearingsDecorator
from behaviours.footprint import DEFAULT_FOOTPRINT, FOOTPRINT, footprint_of
from behaviours.keys import RANGES_KEY, SAFETY_KEY
from behaviours.motion import COMMAND, ODOMETRY
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.telemetry import Arrows, Drawing, Event, Figure, Lines, Plot
from drivers.interfaces import STOP, VelocityCommand
from maps.avoidance.backoff import BackoffSettings
from maps.avoidance.detour import Avoidance
from maps.avoidance.directions import Choice
from maps.avoidance.state import Decision, DetourSettings, Phase
from maps.avoidance.sweep import AvoidSettings
from maps.avoidance.wayround import WayRound
from perception.collision_monitor import SafetyState
from perception.echo_map import EchoMap
from perception.geometry import Pose2D
from perception.obstacle_memory import ObstacleMemory
from perception.polygons import disc
from perception.ranges import RangeScan

PHASES: dict[Phase, float] = {"clear": 0.0, "waiting": 1.0, "detour": 2.0, "backoff": 3.0}
DRAWN_REACH = 1.0  # m: arcs are drawn as far as they are free, up to this
CHOSEN, FREE, BLOCKED = (0, 220, 0), (170, 170, 170), (230, 60, 40)
WAY = (60, 140, 255)
REASONS_KEPT = 5  # give-up reasons in the report


@register
class AvoidObstacles(BearingsDecorator):
    """Get the child's motion around what blocks its way: wait, detour, or give up (module docstring)."""

    ENABLED = InputPort("enabled", bool, True, literal_only=True,
                        doc="false: pass the child's command on unchanged (to compare runs with and without)")
    SPEED = InputPort("speed", float, 0.2, unit="m/s", minimum=0.01, maximum=1.2, literal_only=True,
                      doc="speed along a detour's arcs")
    CLEARANCE = InputPort("clearance", float, 0.10, unit="m", minimum=0.0, maximum=1.0, literal_only=True,
                          doc="kept between the footprint and every sensed point along an arc")
    HORIZON = InputPort("horizon", float, 0.5, unit="s", minimum=0.0, maximum=10.0, literal_only=True,
                        doc="an arc must be free for the braking distance plus this much travel")
    TURN_RATE = InputPort("turn_rate", float, 45.0, unit="deg/s", minimum=1.0, maximum=300.0, literal_only=True,
                          doc="turn rate on a detour")
    WAIT = InputPort("wait", float, 2.0, unit="s", minimum=0.0, maximum=600.0, literal_only=True,
                     doc="held this long before a detour is tried (a person walking across passes)")
    TIMEOUT = InputPort("timeout", float, 20.0, unit="s", minimum=0.1, maximum=3600.0, literal_only=True,
                        doc="held this long with no way around: FAILURE")
    MAX_STRAY = InputPort("max_stray", float, 1.5, unit="m", minimum=0.1, maximum=100.0, literal_only=True,
                          doc="a detour keeps within this of the line the robot was on when it was held")
    MAX_DETOUR = InputPort("max_detour", float, 6.0, unit="m", minimum=0.1, maximum=1000.0, literal_only=True,
                           doc="a detour this long that has not got past: FAILURE")
    BACKOFF = InputPort("backoff", float, 0.4, unit="m", minimum=0.0, maximum=5.0, literal_only=True,
                        doc="no direction will do: back away this far along the way the robot came (0: never)")
    PASS_TURNS = InputPort("pass_turns", bool, False, literal_only=True,
                           doc="a wish to turn on the spot passes in every phase (a child turning by a measured angle)")
    UNDO = InputPort("undo", bool, False, literal_only=True,
                     doc="a detour held with no direction until 'timeout': back along its own way (however "
                         "'backoff' is set), once, then try the other side for a 'wait' before giving up")
    GOING_ROUND = InputPort("going_round", bool, True, literal_only=True,
                            doc="give up a detour that has turned 180 deg (it goes round what the child heads for); "
                                "false for a child whose own path turns (a search pattern)")
    PLAN = InputPort("plan", bool, True, literal_only=True,
                     doc="no direction will do: plan a way round on the echoes of the last 'echo_memory' seconds")
    ECHO_MEMORY = InputPort("echo_memory", float, 20.0, unit="s", minimum=1.0, maximum=600.0, literal_only=True,
                            doc="echoes are kept this long for planning a way round, or until a newer reading "
                                "sees through them")
    MEMORY = InputPort("memory", float, 1.0, unit="s", minimum=0.0, maximum=10.0, literal_only=True,
                       doc="range echoes are remembered this long (odometry frame)")
    ROBOT_RADIUS = InputPort("robot_radius", float, 0.0, unit="m", minimum=0.0, maximum=2.0, literal_only=True,
                             doc="0: the robot's own footprint ('footprint'); a radius: a disc of it instead")
    CHILD_COMMAND = InputPort("child_command", VelocityCommand, Ref("/robot/command"), unit="m/s, rad/s",
                              doc="the command the child wrote this tick (its wish)")
    RANGES = InputPort("ranges", RangeScan, Ref(RANGES_KEY.path), doc=RANGES_KEY.doc)
    SAFETY = InputPort("safety", SafetyState, Ref(SAFETY_KEY.path), doc=SAFETY_KEY.doc)
    HELD = OutputPort("held", bool, "/robot/held",
                      doc="true while it holds the robot for the way to clear by itself (the first 'wait' seconds)")
    RANGES_OPTIONAL = True  # without ranges it passes every command on: a log without them replays (missions.log_check)
    PORTS = (ENABLED, SPEED, TURN_RATE, CLEARANCE, HORIZON, WAIT, TIMEOUT, MAX_STRAY, MAX_DETOUR, BACKOFF, PASS_TURNS,
             UNDO, GOING_ROUND, PLAN, ECHO_MEMORY, MEMORY, ROBOT_RADIUS, FOOTPRINT, CHILD_COMMAND, RANGES, ODOMETRY,
             SAFETY, COMMAND, HELD)

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, **ports: Any) -> None:
        super().__init__(name=name, child=child, **ports)
        self.avoidance = self._avoidance(DEFAULT_FOOTPRINT)  # until the robot's own is known (first tick)
        self._footprint_known = False
        self.memory = ObstacleMemory(self.get_input(self.MEMORY))
        self.echoes = EchoMap(self.get_input(self.ECHO_MEMORY))
        self.decision: Decision | None = None
        self._events: list[str] = []
        self._trail: list[list[float]] = []  # the current detour's odometry positions
        self._detours: list[np.ndarray] = []  # every detour driven, for the recording
        self._drawn = (0, False)  # (detours drawn, arcs drawn)
        self._way: WayRound | None = None  # the way round drawn

    def update(self) -> Status:
        child = self.decorated.status
        if child != Status.RUNNING:
            return child
        if not self.get_input(self.ENABLED):
            return Status.RUNNING
        wish = self.get_input(self.CHILD_COMMAND, None)
        pose = self.get_input(ODOMETRY, None)
        if wish is None or pose is None:  # the child commands nothing this tick: nothing to judge
            return Status.RUNNING
        if not self._footprint_known:
            self._footprint_known = True
            self.avoidance = self._avoidance(footprint_of(self))
        now = self.now()
        scan = self.get_input(self.RANGES, None)
        planning = self.get_input(self.PLAN)
        if scan is not None:
            self.memory = self.memory.added(scan.points(), pose, scan.stamp)
            if planning:
                self.echoes = self.echoes.added(scan, pose)
        safety = self.get_input(self.SAFETY, None)
        stopped = safety is not None and safety.state == "stopped"
        decision = self.avoidance.step(wish.v, wish.w, self.memory.around(pose, now), pose, now, stopped=stopped,
                                       reach=wish.reach, echoes=self.echoes if planning else None)
        self._record(decision, pose)
        # waiting, no way round judged yet (the fan is judged once the wait is over): the wait itself
        self.set_output(self.HELD, decision.phase == "waiting" and decision.choice is None)
        if decision.gave_up:
            self.feedback_message = decision.gave_up
            self.set_output(COMMAND, STOP)
            return Status.FAILURE
        if not decision.passed:
            self.set_output(COMMAND, VelocityCommand(decision.v, decision.w))
        self.feedback_message = "" if decision.phase == "clear" else decision.event or self.feedback_message
        return Status.RUNNING

    @property
    def settings(self) -> AvoidSettings:
        """The footprint and motions the avoidance judges with."""
        return self.avoidance.avoid

    def _avoidance(self, footprint: np.ndarray) -> Avoidance:
        """The avoidance for the robot's ``footprint``, or for the disc of ``robot_radius`` when that is set."""
        radius = self.get_input(self.ROBOT_RADIUS)
        settings = AvoidSettings(
            disc(radius) if radius > 0.0 else footprint, clearance=self.get_input(self.CLEARANCE),
            horizon=self.get_input(self.HORIZON), speed=self.get_input(self.SPEED),
            turn_rate=math.radians(self.get_input(self.TURN_RATE)), max_stray=self.get_input(self.MAX_STRAY))
        return Avoidance(settings, DetourSettings(
            wait=self.get_input(self.WAIT), timeout=self.get_input(self.TIMEOUT),
            max_length=self.get_input(self.MAX_DETOUR), pass_turns=self.get_input(self.PASS_TURNS),
            going_round=self.get_input(self.GOING_ROUND), undo=self.get_input(self.UNDO),
            plan=self.get_input(self.PLAN)),
            BackoffSettings(distance=self.get_input(self.BACKOFF)))

    def terminate(self, new_status: Status) -> None:
        if new_status != Status.RUNNING and self._clock is not None:
            self.avoidance.reset(self.now())
            self._close_trail()
            self.set_output(self.HELD, False)

    def _record(self, decision: Decision, pose: Pose2D) -> None:
        self.decision = decision
        if decision.event:
            self._events.append(decision.event)
        if decision.phase == "detour":
            self._trail.append([pose.x, pose.y])
        else:
            self._close_trail()

    def _close_trail(self) -> None:
        if len(self._trail) > 1:
            self._detours.append(np.array(self._trail))
        self._trail = []

    def figures(self) -> Iterator[Figure]:
        """The ``avoidance`` section: this node's tallies under its name."""
        tally = self.avoidance.tally
        key = self.name.replace(".", "_")
        values: dict[str, Any] = {
            "waits": tally.waits, "waits_cleared": tally.waits_cleared, "wait_time_s": round(tally.wait_time, 2),
            "detours": tally.detours, "detour_length_m": round(tally.detour_length, 3),
            "detour_time_s": round(tally.detour_time, 2), "backoffs": tally.backoffs,
            "backoff_m": round(tally.backoff_length, 3), "creeps": tally.creeps, "ways": tally.ways,
            "way_m": round(tally.way_length, 3), "give_ups": tally.give_ups,
            "reasons": tally.reasons[-REASONS_KEPT:]}
        for name, value in values.items():
            yield Figure("avoidance", f"{key}.{name}", value)

    def drawings(self) -> Iterator[Drawing]:
        """Events, the phase, the fan judged this tick (cleared once the way is clear) and the detours."""
        for text in self._events:
            yield Event("avoidance/events", text)
        self._events = []
        decision = self.decision
        if decision is None:
            return
        yield Plot("avoidance/phase", PHASES[decision.phase])
        detours, arcs_drawn = self._drawn
        if decision.choice is not None:
            yield from fan_drawings(decision.choice)
            arcs_drawn = True
        elif arcs_drawn and decision.phase == "clear":
            yield Lines("avoidance/robot_frame/histogram", [], FREE)
            yield Arrows("avoidance/robot_frame/chosen", np.zeros((0, 2)), CHOSEN)
            arcs_drawn = False
        way = self.avoidance.way
        if way is not self._way:  # a way round planned, planned again or over
            yield Lines("odometry_frame/avoidance/way", [] if way is None else [way.path], WAY, radius=0.015)
            self._way = way
        if len(self._detours) != detours:
            yield Lines("odometry_frame/avoidance/detours", list(self._detours), (255, 140, 0), radius=0.02)
            detours = len(self._detours)
        self._drawn = (detours, arcs_drawn)


def fan_drawings(choice: Choice) -> Iterator[Drawing]:
    """The histogram judged (robot frame): each direction as a ray as far as it is free, up to
    :data:`DRAWN_REACH`, and the chosen direction."""
    rays = [np.array([[0.0, 0.0], [math.cos(d.angle), math.sin(d.angle)]]) * min(d.free, DRAWN_REACH)
            for d in choice.directions]
    colours = [CHOSEN if i == choice.chosen else FREE if d.will_do(choice.reach) else BLOCKED
               for i, d in enumerate(choice.directions)]
    yield Lines("avoidance/robot_frame/histogram", rays, colours)
    direction = choice.direction
    if direction is not None:
        yield Arrows("avoidance/robot_frame/chosen", np.array([[math.cos(direction.angle), math.sin(direction.angle)]]),
                     CHOSEN)
