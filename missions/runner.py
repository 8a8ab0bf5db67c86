"""Run a mission: tick the tree at a fixed rate, turn its commands into driver calls, stop safely.

The tree is a py_trees :class:`~py_trees.trees.BehaviourTree`: its ``setup`` hands every node the
clock, the drivers and the operator's keyboard (an opener,
:data:`~drivers.interfaces.KeyboardOpener`: the terminal by default, opened only by a node that
drives by keys when it runs), a pre-tick handler clears the command keys (a command lives for the
tick that wrote it), post-tick handlers dispatch the commands to the drivers and record the tick.
Between ticks the runner calls ``clock.next_tick(period)``: on a robot that waits for wall
time, in the simulator it steps the world (the simulator is a driver the clock steps), so the
loop has no simulation branch. Whatever ends the run, the report is written:

=========================  ===========  =======================================================
how the run ends           status       exit code
=========================  ===========  =======================================================
the tree succeeds          SUCCESS      0
the tree fails             FAILURE      1
a behaviour raises         FAILURE      1 (reason names the behaviour; SystemExit included)
the time limit             FAILURE      1
the tick watchdog          FAILURE      1 (reason names the blocking behaviour; on a robot,
                                        or in simulation with ``--overrun``)
SIGINT / SIGTERM           INTERRUPTED  130 / 143, even while a behaviour blocks
=========================  ===========  =======================================================

In every case the base and the pan-tilt unit are commanded to stop before any driver closes,
and the last command recorded (report and recording) is a zero velocity.

The collision monitor sits between the tree and the base on every run: the runner wraps
``robot.base`` in a :class:`~drivers.safety.guarded_base.GuardedBase` before the tree is set up,
so every command (the tree's, or a node's own call to the base) is limited against the robot's
range source (``robot.ranges``) with the footprint and zones of ``safety`` (a
:class:`~perception.collision_monitor.MonitorConfig`; default: a Pioneer 3-DX's). After each
tick ``/robot/safety`` holds the monitor's state, the recording gets an event line per
intervention, and the report a ``safety`` section (stops and slow-downs counted as episodes,
bumper hits, the nearest range, the first events).

With ``record_path`` (``--record``) every device of the robot records what it delivers and what
it is sent (:class:`~drivers.logs.record.SensorLog`, inside the collision monitor: the base's
commands are the ones sent), the tree's own command and the clock once per tick; the file is
closed on every way the run ends and the report gets a ``record`` section.

Capabilities add to the report and the recording without touching the runner: any node of the
tree may report ``figures()`` (named values, gathered into the report's sections: ``ltmap``,
``roadmap``, ``exploration``; numbers are plotted in the recording too) and ``drawings()``
(geometry and events for the recording), as :mod:`behaviours.telemetry` declares. A driver of
the robot may add report sections through ``report_sections() -> dict``
(``report_sections() -> dict``: the Pioneer base says which model and conversion factors it
used, and where they came from). Behaviours still never see ground truth: the simulator adds its
``ground_truth`` section as an observer, and evaluations combine the two.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import sys
import time
import traceback
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import py_trees
from py_trees.common import Status

from behaviours.clock import TickClock
from behaviours.keys import COMMAND_KEYS, FOOTPRINT_KEY, SAFETY_KEY, input_key
from behaviours.telemetry import Draws, Event, Plot, Reports, Sections
from drivers.interfaces import STOP, KeyboardOpener, PanTiltCommand, Robot, VelocityCommand
from drivers.keyboard import TerminalKeys
from drivers.logs.camera_codec import ImageFormat
from drivers.pioneer_body import BODIES
from drivers.safety.guarded_base import GuardedBase
from drivers.safety.settings import monitor_config
from maps.store import write_json
from missions.builder import build_root
from missions.clocks import WallClock
from missions.images import DEFAULT_RATE_HZ
from missions.language import MissionSpec
from missions.recording import Recorder
from missions.safety import Interrupted, SafetyMonitor, exit_code
from missions.summary import declared_headline
from perception.collision_monitor import CollisionMonitor, MonitorConfig

if TYPE_CHECKING:
    from drivers.logs.record import SensorLog


class RunObserver(Protocol):
    """Something beside the robot that watches a run (the simulator's ground truth)."""

    def report_sections(self, evaluation: Mapping[str, Any]) -> dict[str, Any]: ...

    def log_rerun(self, rec: Any) -> None: ...


@dataclass
class RunOptions:
    """How to run: tick rate (None: the mission's), limits, outputs."""

    rate_hz: float | None = None
    max_time_s: float | None = None
    overrun_s: float | None = None  # tick watchdog limit; None: the mission's on a robot, none in simulation
    report_path: Path | None = None
    save_path: Path | None = None
    image_rate_hz: float | None = DEFAULT_RATE_HZ  # camera images per second in the recording; None or 0: every frame
    seed: int = 0
    debug: bool = False  # print the traceback of an exception in the tree
    record_path: Path | None = None  # --record: every sensed input and command, as ROS 2 messages in MCAP
    record_images: ImageFormat = field(default_factory=ImageFormat)


@dataclass
class RunResult:
    """The outcome of one run; ``report`` is the JSON written with ``--report``."""

    status: str
    reason: str
    ticks: int
    time_s: float
    report: dict[str, Any] = field(default_factory=dict)
    signum: int | None = None

    @property
    def exit_code(self) -> int:
        if self.signum is not None:
            return exit_code(self.signum)
        return 0 if self.status == "SUCCESS" else 1


class Runner:
    """Ticks one mission on one robot (real or simulated)."""

    def __init__(
        self,
        mission: MissionSpec,
        robot: Robot,
        *,
        clock: TickClock | None = None,
        options: RunOptions | None = None,
        observers: Sequence[RunObserver] = (),
        on_tick: Callable[[Runner], None] | None = None,
        keyboard: KeyboardOpener = TerminalKeys,
        safety: MonitorConfig | None = None,
    ) -> None:
        self.mission = mission
        self.options = options or RunOptions()
        self.clock: TickClock = clock or WallClock()
        self.sensor_log: SensorLog | None = None
        if self.options.record_path is not None:  # devices record what they deliver and are sent, inside the monitor
            from drivers.logs.record import SensorLog  # MCAP's libraries load only when a run records

            self.sensor_log = SensorLog(self.options.record_path, images=self.options.record_images)
            robot = self.sensor_log.wrap(robot, self.clock.now)
            keyboard = self.sensor_log.wrap_keyboard(keyboard)
        self.keyboard = keyboard  # opened by a node that drives by keys, when it first runs
        config = safety or monitor_config(None, BODIES["p3dx"].footprint)
        self.guard = GuardedBase(robot.base, CollisionMonitor(config), robot.ranges, self.clock.now)
        self.robot = dataclasses.replace(robot, base=self.guard)  # the tree and the stops see the guarded base
        self.observers = tuple(observers)
        self.on_tick = on_tick
        self.rate_hz = self.options.rate_hz or mission.rate_hz
        self.period = 1.0 / self.rate_hz
        self.max_time = self.options.max_time_s if self.options.max_time_s is not None else mission.max_time_s
        self.last_command: VelocityCommand = STOP
        self._last_ptu: PanTiltCommand | None = None
        self._recorder: Recorder | None = None
        self._drawers: list[Any] = []
        self._wall_start = time.monotonic()
        py_trees.blackboard.Blackboard.clear()  # one run, one blackboard: nothing leaks between runs
        root, self.task = build_root(mission)
        self.tree = py_trees.trees.BehaviourTree(root)
        self.tree.add_pre_tick_handler(self._clear_commands)
        self.tree.add_post_tick_handler(self._dispatch)
        self.blackboard = py_trees.blackboard.Client(name="runner")
        for spec in (*COMMAND_KEYS, SAFETY_KEY, FOOTPRINT_KEY):
            self.blackboard.register_key(key=spec.path, access=py_trees.common.Access.WRITE)
        overrun = self.options.overrun_s
        if overrun is None and self.clock.timeline == "wall_time":
            overrun = mission.overrun_s  # simulated time stands still during a slow tick: no watchdog by default
        self.monitor = SafetyMonitor(robot, period=self.period, overrun_limit=overrun,
                                     emergency_exit=self._emergency_exit)

    @property
    def root(self) -> py_trees.behaviour.Behaviour:
        return self.tree.root

    @property
    def ticks(self) -> int:
        return self.tree.count

    # -- the run ---------------------------------------------------------------------------------
    def run(self) -> RunResult:
        status, reason = "FAILURE", "not started"
        with self.monitor:
            try:
                self._start()
                status, reason = self._loop()
            except Interrupted:
                status, reason = "INTERRUPTED", self.monitor.stopped_reason or "interrupted"
            except BaseException as exc:  # noqa: BLE001 - whatever a behaviour raises ends the run as FAILURE
                status, reason = "FAILURE", describe_exception(exc)
                if self.options.debug:
                    traceback.print_exc()
            finally:
                self.monitor.disarm()
                self._finish()
            if self.monitor.signum is not None:  # a signal during the last tick or the wind-down
                status, reason = "INTERRUPTED", self.monitor.stopped_reason or reason
        return self._result(status, reason)

    def _start(self) -> None:
        if self.options.save_path is not None:
            self._recorder = Recorder(self.options.save_path, mission=self.mission.name,
                                      recording_id=f"{self.mission.name}-seed{self.options.seed}",
                                      timeline=self.clock.timeline, image_rate_hz=self.options.image_rate_hz)
        if self.sensor_log is not None:
            self.sensor_log.open(mission=self.mission.name, timeline=self.clock.timeline, rate_hz=self.rate_hz,
                                 footprint=self.guard.monitor.config.footprint)
        for name, value in self.mission.values.items():  # inputs are readable at run time: /mission/<name>
            py_trees.blackboard.Blackboard.set(input_key(name), value)
        self.blackboard.set(SAFETY_KEY.path, self.guard.state)
        self.blackboard.set(FOOTPRINT_KEY.path, self.guard.monitor.config.footprint)
        # hand every node the clock and the drivers (the keyboard as an opener: a terminal is taken only if used)
        self.tree.setup(clock=self.clock, robot=self.robot, keyboard=self.keyboard)
        self._drawers = [node for node in self.root.iterate() if isinstance(node, Reports | Draws)]

    def _loop(self) -> tuple[str, str]:
        while True:
            stop = self.monitor.stopped_reason
            if stop is not None:
                return ("INTERRUPTED" if self.monitor.signum is not None else "FAILURE"), stop
            now = self.clock.now()
            if self.max_time is not None and now >= self.max_time - 1e-9:
                return "FAILURE", f"time limit of {self.max_time:g} s reached"
            self.monitor.tick_started()
            try:
                self.tree.tick()
            finally:
                self.monitor.tick_finished()
            if self.monitor.fault is not None:
                return "FAILURE", self.monitor.fault
            if self.on_tick is not None:
                self.on_tick(self)
            if self.root.status in (Status.SUCCESS, Status.FAILURE):
                return self.root.status.value, self._outcome_reason()
            self.clock.next_tick(self.period)

    def _finish(self) -> None:
        """Stop everything, halt the tree, record the stop (runs whatever happened)."""
        self.robot.stop_all()  # the last command sent is always a stop
        self.last_command = STOP
        if self.sensor_log is not None:
            self.sensor_log.close()
        with contextlib.suppress(Exception):  # halting must not mask the outcome
            if self.root.status == Status.RUNNING:
                self.root.stop(Status.INVALID)
        if self._recorder is not None:
            with contextlib.suppress(Exception):  # the run's outcome matters more than the file
                self._recorder.log_stop(time_s=self.clock.now(), tick=self.ticks)
                self._recorder.close()

    def _result(self, status: str, reason: str) -> RunResult:
        result = RunResult(status, reason, self.ticks, self.clock.now(), signum=self.monitor.signum)
        result.report = self._report(result)
        if self.options.report_path is not None:
            try:
                write_json(self.options.report_path, result.report)
            except OSError as exc:  # a full disk must not turn the run's outcome into a traceback
                sys.stderr.write(f"bearings run: the report was not written to {self.options.report_path}: "
                                 f"{exc.strerror or exc}; the run ended {status} ({reason})\n")
        return result

    def _emergency_exit(self, signum: int) -> None:
        """Called by the monitor when a signal came and the loop is stuck: report, then end the process."""
        self.robot.stop_all()
        if self.sensor_log is not None:
            self.sensor_log.close()
        with contextlib.suppress(Exception):
            reason = f"{self.monitor.stopped_reason}; the tree did not return, the process was ended"
            self._result("INTERRUPTED", reason)
        with contextlib.suppress(Exception):
            if self._recorder is not None:
                self._recorder.log_stop(time_s=self.clock.now(), tick=self.ticks)
                self._recorder.close()
        os._exit(exit_code(signum))

    # -- tick handlers ---------------------------------------------------------------------------
    def _clear_commands(self, _tree: py_trees.trees.BehaviourTree) -> None:
        for spec in COMMAND_KEYS:  # a command is valid for the tick that wrote it only
            self.blackboard.unset(spec.path)

    def _dispatch(self, _tree: py_trees.trees.BehaviourTree) -> None:
        if self.monitor.stopped_reason is not None:
            return  # the monitor stopped the base: the tree's command must not restart it
        command = self._get("/robot/command")
        asked = command if isinstance(command, VelocityCommand) else STOP
        self.robot.base.drive(asked.v, asked.w)  # through the collision monitor
        self.last_command = VelocityCommand(asked.v * self.guard.state.ratio, asked.w * self.guard.state.ratio)
        self.blackboard.set(SAFETY_KEY.path, self.guard.state)
        if self.sensor_log is not None:
            self.sensor_log.tick(asked)
        ptu_command = self._get("/ptu/command")
        if self.robot.ptu is not None and isinstance(ptu_command, PanTiltCommand) and ptu_command != self._last_ptu:
            self.robot.ptu.move(ptu_command.pan, ptu_command.tilt, ptu_command.speed)
            self._last_ptu = ptu_command
        if self._recorder is not None:
            self._recorder.log_tick(time_s=self.clock.now(), tick=self.ticks + 1, root=self.root,
                                    odometry=self._get("/robot/odometry"), command=self.last_command,
                                    observers=self.observers, nodes=self._drawers,
                                    frames=self._get("/perception/frames"))
            self._recorder.draw(Plot("safety/ratio", self.guard.state.ratio))
            for event in self.guard.log.take_new():
                self._recorder.draw(Event("safety/events", event.line()))

    # -- helpers ---------------------------------------------------------------------------------
    def _get(self, key: str) -> Any:
        try:
            return py_trees.blackboard.Blackboard.get(key)
        except KeyError:
            return None

    def _node_sections(self) -> Sections:
        """What the tree's nodes add to the report (a node that fails to say is noted, not fatal)."""
        gathered = Sections()
        for node in self.root.iterate():
            try:
                if isinstance(node, Reports):
                    gathered.add(node.figures())
            except Exception as exc:  # noqa: BLE001 - the report must be written whatever a node does
                gathered.sections.setdefault("report_errors", {})[node.name] = describe_exception(exc)
        return gathered

    def _outcome_reason(self) -> str:
        if self.root.status == Status.SUCCESS:
            return "mission tree succeeded"
        failed = [n for n in self.root.iterate() if n.status == Status.FAILURE  # the deepest failures
                  and not any(c.status == Status.FAILURE for c in n.children)]
        if failed:
            node = failed[0]
            detail = f": {node.feedback_message}" if node.feedback_message else ""
            return f"{node.name} failed{detail}"
        return "mission tree failed"

    def _report(self, result: RunResult) -> dict[str, Any]:
        mission = self.mission
        report: dict[str, Any] = {
            "mission": mission.name,
            "file": mission.file,
            "status": result.status,
            "reason": result.reason,
            "ticks": result.ticks,
            "rate_hz": self.rate_hz,
            "wall_time_s": round(time.monotonic() - self._wall_start, 3),
            "inputs": {k: v for k, v in mission.values.items() if _jsonable(v)},
            "seed": self.options.seed,
            "last_command": {"v": self.last_command.v, "w": self.last_command.w},
        }
        if self.clock.timeline == "sim_time":
            report["sim_time_s"] = round(result.time_s, 6)
        for observer in self.observers:
            report.update(observer.report_sections(mission.evaluation))
        nodes = self._node_sections()
        for name, values in nodes.sections.items():
            report.setdefault(name, {}).update(values)
        report["safety"] = {**self.guard.log.summary(),  # and the outline collisions were judged with
                            "footprint": np.round(self.guard.monitor.config.footprint, 4).tolist()}
        if self.sensor_log is not None:
            report["record"] = self.sensor_log.summary()
        for device in (self.guard.base, self.robot.ptu):
            sections = getattr(device, "report_sections", None)
            if callable(sections):
                report.update(sections())
        report["headline"] = declared_headline([*self.observers, self.robot.base, self.robot.ptu], nodes.headline)
        odometry = self._get("/robot/odometry")
        if odometry is not None:
            report["odometry"] = {"x": odometry.x, "y": odometry.y, "theta": odometry.theta}
        return report


def describe_exception(exc: BaseException) -> str:
    """One line: which behaviour raised what (the innermost py_trees behaviour on the stack)."""
    where = None
    tb = exc.__traceback__
    while tb is not None:
        candidate = tb.tb_frame.f_locals.get("self")
        if isinstance(candidate, py_trees.behaviour.Behaviour):
            where = candidate
        tb = tb.tb_next
    message = str(exc).splitlines()[0] if str(exc) else ""
    text = f"{type(exc).__name__}: {message}" if message else type(exc).__name__
    if where is not None:
        return f"{where.name} ({type(where).__name__}) raised {text}"
    return f"runner raised {text}"


def _jsonable(value: Any) -> bool:
    return isinstance(value, (int, float, str, bool, list)) or value is None
