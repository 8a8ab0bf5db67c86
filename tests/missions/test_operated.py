"""A simulated run keeps wall-clock speed from when an operator takes the keyboard; progress on stderr."""

from __future__ import annotations

import io
import textwrap
from types import SimpleNamespace

from behaviours.clock import ManualClock
from drivers.fake import FakeKeys, fake_robot
from missions.clocks import Paced, paced_when_operated
from missions.loader import load_mission
from missions.progress import LINE_EVERY_S, Progress, progress_for
from missions.runner import Runner


class _Inner:
    timeline = "sim_time"

    def __init__(self) -> None:
        self.t = 0.0

    def now(self) -> float:
        return self.t

    def next_tick(self, period: float) -> None:
        self.t += period


def _mission(tmp_path, tree: str):
    path = tmp_path / "m.yaml"
    path.write_text("mission: m\ntree:\n" + textwrap.indent(textwrap.dedent(tree), "  "))
    return load_mission(path)


def test_opening_the_keyboard_engages_the_pace_and_says_so_once():
    clock, said = Paced(_Inner(), engaged=False), []
    opener = paced_when_operated(lambda: FakeKeys([["q"]]), clock, said=said.append)
    assert not clock.engaged
    opener()
    opener()
    assert clock.engaged and len(said) == 1


def test_a_mission_that_could_drive_by_keys_but_does_not_runs_free(tmp_path):
    clock = Paced(ManualClock(), engaged=False)
    unused = _mission(tmp_path, "Selector:\n  children:\n    - Success\n    - KeyboardTeleop\n")
    keyboard = paced_when_operated(lambda: FakeKeys([["q"]]), clock)
    assert Runner(unused, fake_robot(), clock=clock, keyboard=keyboard).run().status == "SUCCESS"
    assert not clock.engaged
    driven = _mission(tmp_path, "KeyboardTeleop: {speed: 0.25}\n")
    assert Runner(driven, fake_robot(), clock=clock, keyboard=keyboard).run().status == "SUCCESS"
    assert clock.engaged


def _runner(t: float, ticks: int):
    tip = SimpleNamespace(name="drive", feedback_message="1.0 m to go")
    return SimpleNamespace(task=SimpleNamespace(tip=lambda: tip), clock=SimpleNamespace(now=lambda: t), ticks=ticks)


def test_progress_off_a_terminal_is_a_whole_line_every_few_seconds():
    stream, wall = io.StringIO(), [0.0]
    progress = Progress("m", stream, terminal=False, clock=lambda: wall[0])
    for tick in range(100):  # ten wall seconds at 10 ticks per second
        wall[0] = tick * 0.1
        progress(_runner(tick * 1.0, tick))
    progress.close()
    lines = stream.getvalue().splitlines()
    assert len(lines) == 1 + int(9.9 // LINE_EVERY_S)
    assert lines[0].startswith("[m] t=") and lines[0].endswith("drive: 1.0 m to go") and "\r" not in stream.getvalue()


def test_progress_is_printed_off_a_terminal_only_when_asked():
    assert progress_for("m", io.StringIO(), asked=False, quiet=False) is None
    assert progress_for("m", io.StringIO(), asked=True, quiet=False) is not None
    assert progress_for("m", io.StringIO(), asked=True, quiet=True) is None
