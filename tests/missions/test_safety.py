"""The robot stops whatever a behaviour does: signals during a blocked tick, the tick watchdog,
behaviours that raise SystemExit or KeyboardInterrupt, and signals before the loop starts.

The signal tests run a real ``bearings run`` in a child process on a base that logs every
command with its ``time.monotonic()`` stamp (the same clock in both processes on Linux), so the
200 ms bound is measured on the real code path, wall clock included.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from behaviours.clock import ManualClock
from drivers.interfaces import Robot
from missions.cli import main
from missions.loader import load_mission
from missions.runner import Runner, RunOptions

BLOCKING_PLUGIN = """
import os, time
from py_trees.common import Status
from behaviours.base import BearingsBehaviour
from behaviours.registry import register

@register
class Stuck(BearingsBehaviour):
    '''Blocks in update() (a hostile test plugin): politely, or swallowing every exception.'''
    def update(self):
        with open(os.environ["STUCK_MARKER"], "w") as marker:
            marker.write(str(time.monotonic()))
        if os.environ.get("STUCK_SWALLOW"):
            while True:
                try:
                    time.sleep(10)
                except BaseException:
                    pass
        time.sleep(1000)
        return Status.SUCCESS

@register
class Leave(BearingsBehaviour):
    '''Raises what the environment says on its second tick (a hostile test plugin).'''
    def initialise(self):
        self.ticks = 0
    def update(self):
        self.ticks += 1
        if self.ticks == 2:
            raise {"exit": SystemExit(5), "ctrl-c": KeyboardInterrupt()}[os.environ["LEAVE_WITH"]]
        return Status.RUNNING
"""

CHILD = """
import json, sys, time
from drivers.fake import FakeBase
from drivers.interfaces import Robot
from missions.loader import load_mission
from missions.runner import Runner, RunOptions
from pathlib import Path

class LoggingBase(FakeBase):
    def drive(self, v, w):
        super().drive(v, w)
        with open(sys.argv[2], "a") as log:
            log.write(json.dumps([time.monotonic(), v, w]) + "\\n")

mission = load_mission(sys.argv[1])
robot = Robot(base=LoggingBase())
options = RunOptions(report_path=Path(sys.argv[3]), save_path=Path(sys.argv[4]))
result = Runner(mission, robot, options=options).run()
sys.exit(result.exit_code)
"""


@pytest.fixture
def stuck_mission(tmp_path: Path) -> Path:
    (tmp_path / "stuck.py").write_text(BLOCKING_PLUGIN)
    path = tmp_path / "stuck.yaml"
    path.write_text("plugins: [stuck.py]\ncameras: []\noverrun: 60\ntree:\n  Parallel:\n    children:\n"
                    "      - Drive: {distance: 100.0}\n      - Stuck\n")
    return path


def _run_child(tmp_path: Path, mission: Path, signum: int, **env: str) -> tuple[float, int, float, list]:
    """Start the child, signal it once it blocks; (signal time, exit code, exit time, base log)."""
    (tmp_path / "child.py").write_text(CHILD)
    marker, log = tmp_path / "marker", tmp_path / "base.log"
    environment = {**os.environ, "STUCK_MARKER": str(marker), **env}
    child = subprocess.Popen([sys.executable, str(tmp_path / "child.py"), str(mission), str(log),
                              str(tmp_path / "report.json"), str(tmp_path / "run.rrd")], env=environment,
                             cwd=Path(__file__).resolve().parents[2])
    try:
        deadline = time.monotonic() + 60
        while not marker.exists() or not marker.read_text():
            assert child.poll() is None and time.monotonic() < deadline, "the child never reached the blocking tick"
            time.sleep(0.02)
        time.sleep(0.3)  # well inside the blocking update()
        sent = time.monotonic()
        child.send_signal(signum)
        code = child.wait(timeout=10)
        ended = time.monotonic()
    finally:
        if child.poll() is None:
            child.kill()
    commands = [json.loads(line) for line in log.read_text().splitlines()]
    return sent, code, ended, commands


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_the_base_while_a_behaviour_blocks(tmp_path, stuck_mission, signum):
    sent, code, ended, commands = _run_child(tmp_path, stuck_mission, signum)
    assert code == 128 + signum
    assert ended - sent < 2.0
    stops = [t for t, v, w in commands if t >= sent and v == 0.0 and w == 0.0]
    assert stops and stops[0] - sent < 0.2, (sent, commands[-3:])
    assert commands[-1][1:] == [0.0, 0.0]
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["status"] == "INTERRUPTED" and report["reason"] == f"interrupted by {signal.Signals(signum).name}"
    assert report["last_command"] == {"v": 0.0, "w": 0.0}
    assert (tmp_path / "run.rrd").stat().st_size > 1000


def test_a_behaviour_that_swallows_the_interruption_still_cannot_keep_the_robot_going(tmp_path, stuck_mission):
    sent, code, ended, commands = _run_child(tmp_path, stuck_mission, signal.SIGINT, STUCK_SWALLOW="1")
    assert code == 130 and ended - sent < 2.5  # the monitor's grace period, then the process is ended
    stops = [t for t, v, w in commands if t >= sent and v == 0.0 and w == 0.0]
    assert stops and stops[0] - sent < 0.2
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["status"] == "INTERRUPTED" and "the tree did not return" in report["reason"]


class TimedBase:
    """A base that stamps every command with the wall clock (for the watchdog test)."""

    def __init__(self) -> None:
        self.commands: list[tuple[float, float, float]] = []

    def drive(self, v: float, w: float) -> None:
        self.commands.append((time.monotonic(), v, w))

    def stop(self) -> None:
        self.drive(0.0, 0.0)

    def odometry(self):
        from perception.geometry import Pose2D

        return Pose2D()

    def stalled(self) -> bool:
        return False

    def close(self) -> None:
        pass


SLOW_PLUGIN = """
import time
from py_trees.common import Status
from behaviours.base import BearingsBehaviour
from behaviours.registry import register

@register
class Slow(BearingsBehaviour):
    '''Takes 1.2 s on its third tick (a test plugin).'''
    def initialise(self):
        self.ticks = 0
    def update(self):
        self.ticks += 1
        if self.ticks == 3:
            self.started = time.monotonic()
            time.sleep(1.2)
        return Status.RUNNING
"""


def test_the_tick_watchdog_stops_the_base_and_names_the_blocking_node(write_mission, tmp_path):
    (tmp_path / "slow.py").write_text(SLOW_PLUGIN)
    mission = load_mission(write_mission(textwrap.dedent("""
        plugins: [slow.py]
        tree:
          Parallel:
            children:
              - Drive: {distance: 100.0}
              - Slow: {name: the slow one}
    """)))
    base = TimedBase()
    runner = Runner(mission, Robot(base=base), clock=ManualClock(), options=RunOptions(overrun_s=0.3))
    result = runner.run()
    assert result.status == "FAILURE" and result.exit_code == 1
    assert result.reason.startswith("tick watchdog: a tick ran longer than 0.40 s in the slow one (Slow)")
    slow = next(node for node in runner.root.iterate() if node.name == "the slow one")
    first_stop = next(t for t, v, w in base.commands if t > slow.started and v == 0.0 and w == 0.0)
    assert first_stop - slow.started < 0.4 + 0.1  # the limit, plus the monitor's polling
    assert all(v == 0.0 for t, v, _ in base.commands if t > slow.started)  # nothing restarted it
    assert result.ticks == 3


@pytest.mark.parametrize(("how", "reason"), [("exit", "raised SystemExit: 5"), ("ctrl-c", "raised KeyboardInterrupt")])
def test_exits_raised_by_a_behaviour_end_the_run_with_a_report(write_mission, tmp_path, monkeypatch, how, reason):
    (tmp_path / "stuck.py").write_text(BLOCKING_PLUGIN)
    monkeypatch.setenv("LEAVE_WITH", how)
    path = write_mission("plugins: [stuck.py]\ncameras: []\ntree: {Parallel: {children: [Drive: {distance: 9}, "
                         "Leave]}}\n")
    report = tmp_path / "out" / "report.json"
    code = main(["run", str(path), "--quiet", "--report", str(report)])
    data = json.loads(report.read_text())
    assert code == 1 and data["status"] == "FAILURE" and data["reason"] == f"Leave (Leave) {reason}"
    assert data["last_command"] == {"v": 0.0, "w": 0.0}


def test_a_signal_before_the_loop_starts_is_reported(write_mission, tmp_path, monkeypatch):
    from drivers.sim import world

    def interrupted_load(*_args, **_kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(1.0)  # the handler interrupts this
        raise AssertionError("not interrupted")

    monkeypatch.setattr(world, "load_world", interrupted_load)  # loading the world: before the loop
    report = tmp_path / "report.json"
    assert main(["run", "square", "--quiet", "--report", str(report)]) == 130
    data = json.loads(report.read_text())
    assert data["status"] == "INTERRUPTED" and data["reason"] == "interrupted before the mission started"
