"""Run a mission: tick the tree at a fixed rate, turn its commands into driver calls, stop safely.

Safety rules, whatever happens: when the tree ends, when a behaviour raises, on Ctrl-C or
SIGTERM, when the time limit passes, the runner commands the base and the pan-tilt unit to stop
before it closes any driver, and the report is written (atomically) before the process exits.
An exception inside the tree becomes a mission FAILURE with a one-line reason, not a crash.

In the simulator the runner steps the world by the tick period after every tick and runs as fast
as it can (or at wall-clock pace with ``realtime``); on a robot it paces ticks on the monotonic
clock. Behaviours only ever see the clock handed to them.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import py_trees
from py_trees.common import Status

from behaviours.clock import Clock, ManualClock, MonotonicClock
from drivers.interfaces import STOP, PanTiltCommand, Robot, VelocityCommand
from maps.store import write_json
from missions.builder import build_root
from missions.language import MissionSpec
from missions.recording import Recorder

COMMAND_KEYS = ("/robot/command", "/ptu/command")


@dataclass
class RunOptions:
    """How to run: tick rate (None: the mission's), time limit, pacing, outputs."""

    rate_hz: float | None = None
    max_time_s: float | None = None
    realtime: bool = False
    report_path: Path | None = None
    save_path: Path | None = None
    progress: bool = False
    seed: int = 0
    debug: bool = False  # print the traceback of an exception in the tree


@dataclass
class RunResult:
    """The outcome of one run; ``report`` is the JSON written with ``--report``."""

    status: str
    reason: str
    ticks: int
    time_s: float
    report: dict[str, Any] = field(default_factory=dict)

    @property
    def exit_code(self) -> int:
        return 0 if self.status == "SUCCESS" else 1


class Runner:
    """Ticks one mission on one robot (real or simulated)."""

    def __init__(
        self,
        mission: MissionSpec,
        robot: Robot,
        *,
        simulation: Any = None,
        clock: Clock | None = None,
        options: RunOptions | None = None,
        on_tick: Callable[[Runner], None] | None = None,
    ) -> None:
        self.mission = mission
        self.robot = robot
        self.simulation = simulation
        self.options = options or RunOptions()
        self.clock = clock or (ManualClock() if simulation is not None else MonotonicClock())
        self.on_tick = on_tick
        self.rate_hz = self.options.rate_hz or mission.rate_hz
        self.period = 1.0 / self.rate_hz
        self.max_time = self.options.max_time_s if self.options.max_time_s is not None else mission.max_time_s
        self.ticks = 0
        self._stop_request: str | None = None
        self._last_ptu: PanTiltCommand | None = None
        self.last_command: VelocityCommand = STOP
        py_trees.blackboard.Blackboard.clear()  # one run, one blackboard: nothing leaks between runs
        self.root, self.task = build_root(mission)
        self.blackboard = py_trees.blackboard.Client(name="runner")
        for key in COMMAND_KEYS:
            self.blackboard.register_key(key=key, access=py_trees.common.Access.WRITE)

    # -- control -------------------------------------------------------------------------------
    def request_stop(self, reason: str) -> None:
        """Ask the loop to end at the next tick boundary (signal handlers call this)."""
        self._stop_request = reason

    def run(self) -> RunResult:
        status, reason = "FAILURE", "not started"
        recorder = None
        restore = self._install_signal_handlers()
        start_wall = time.monotonic()
        try:
            if self.options.save_path is not None:
                recorder = Recorder(self.options.save_path, mission=self.mission.name,
                                    recording_id=f"{self.mission.name}-seed{self.options.seed}",
                                    timeline="sim_time" if self.simulation is not None else "wall_time")
            for node in self.root.iterate():  # hand every node the clock and the drivers
                node.setup(clock=self.clock, robot=self.robot)
            status, reason = self._loop(recorder, start_wall)
        except Exception as exc:  # noqa: BLE001 - any failure becomes a FAILURE, robot stopped
            status, reason = "FAILURE", describe_exception(exc)
            if self.options.debug:
                traceback.print_exc()
        finally:
            self.robot.stop_all()  # the last command sent is always a stop
            self._halt_tree()
            if recorder is not None:
                with contextlib.suppress(Exception):  # the run's outcome matters more than the file
                    recorder.close()
            restore()
            if self.options.progress:
                sys.stderr.write("\n")
        elapsed = self.clock.now()
        result = RunResult(status, reason, self.ticks, elapsed)
        result.report = self._report(result, time.monotonic() - start_wall)
        if self.options.report_path is not None:
            write_json(self.options.report_path, result.report)
        return result

    # -- the loop ------------------------------------------------------------------------------
    def _loop(self, recorder: Recorder | None, start_wall: float) -> tuple[str, str]:
        last_progress = 0.0
        while True:
            if self._stop_request:
                return "FAILURE", self._stop_request
            now = self.clock.now()
            if self.max_time is not None and now >= self.max_time - 1e-9:
                return "FAILURE", f"time limit of {self.max_time:g} s reached"
            for key in COMMAND_KEYS:  # a command is valid for the tick that wrote it only
                self.blackboard.unset(key)
            tick_started = time.monotonic()
            try:
                self.root.tick_once()
            except Exception as exc:  # noqa: BLE001
                if self.options.debug:
                    traceback.print_exc()
                return "FAILURE", describe_exception(exc)
            self.ticks += 1
            self._act()
            if recorder is not None:
                recorder.log_tick(time_s=now, tick=self.ticks, root=self.root,
                                  odometry=self._get("/robot/odometry"), command=self.last_command,
                                  simulation=self.simulation)
            if self.on_tick is not None:
                self.on_tick(self)
            if self.options.progress and time.monotonic() - last_progress > 0.2:
                last_progress = time.monotonic()
                self._print_progress(now)
            if self.root.status in (Status.SUCCESS, Status.FAILURE):
                return self.root.status.value, self._outcome_reason()
            self._advance(tick_started)

    def _act(self) -> None:
        command = self._get("/robot/command")
        if not isinstance(command, VelocityCommand):
            command = STOP
        self.last_command = command
        self.robot.base.drive(command.v, command.w)
        ptu_command = self._get("/ptu/command")
        if self.robot.ptu is not None and isinstance(ptu_command, PanTiltCommand) and ptu_command != self._last_ptu:
            self.robot.ptu.move(ptu_command.pan, ptu_command.tilt, ptu_command.speed)
            self._last_ptu = ptu_command

    def _advance(self, tick_started: float) -> None:
        if self.simulation is not None:
            self.simulation.step(self.period)
            self.clock.set(self.ticks * self.period)  # no drift from summing the period
            if self.options.realtime:
                time.sleep(max(0.0, self.period - (time.monotonic() - tick_started)))
        else:
            time.sleep(max(0.0, self.period - (time.monotonic() - tick_started)))

    # -- helpers -------------------------------------------------------------------------------
    def _get(self, key: str) -> Any:
        try:
            return py_trees.blackboard.Blackboard.get(key)
        except KeyError:
            return None

    def _halt_tree(self) -> None:
        try:
            if self.root.status == Status.RUNNING:
                self.root.stop(Status.INVALID)
        except Exception:  # noqa: BLE001 - halting must not mask the original outcome
            pass

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

    def _print_progress(self, now: float) -> None:
        tip = self.task.tip()
        active = f"{tip.name}" + (f": {tip.feedback_message}" if tip is not None and tip.feedback_message else "")
        line = f"[{self.mission.name}] t={now:7.1f} s  tick {self.ticks:6d}  {active if tip else ''}"
        sys.stderr.write("\r" + line[:110].ljust(110))
        sys.stderr.flush()

    def _install_signal_handlers(self) -> Callable[[], None]:
        if threading.current_thread() is not threading.main_thread():
            return lambda: None
        previous = {}

        def handler(signum: int, _frame: Any) -> None:
            self.request_stop(f"interrupted by {signal.Signals(signum).name}")

        for sig in (signal.SIGINT, signal.SIGTERM):
            previous[sig] = signal.signal(sig, handler)

        def restore() -> None:
            for sig, old in previous.items():
                signal.signal(sig, old)

        return restore

    def _report(self, result: RunResult, wall_s: float) -> dict[str, Any]:
        mission = self.mission
        report: dict[str, Any] = {
            "mission": mission.name,
            "file": mission.file,
            "status": result.status,
            "reason": result.reason,
            "ticks": result.ticks,
            "rate_hz": self.rate_hz,
            "wall_time_s": round(wall_s, 3),
            "inputs": {k: v for k, v in mission.values.items() if _jsonable(v)},
            "seed": self.options.seed,
        }
        if self.simulation is not None:
            report["sim_time_s"] = round(result.time_s, 6)
            report["ground_truth"] = self.simulation.ground_truth_report(
                goal=mission.evaluation.get("goal"), reference_path=mission.evaluation.get("reference_path"),
                frame=mission.evaluation.get("frame", "world"))
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
