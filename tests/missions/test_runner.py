"""The runner: whole missions in the simulator, reports, recordings, and the safety rules."""

from __future__ import annotations

import json
import math
import os
import signal
import textwrap

import pytest

from behaviours.clock import ManualClock
from drivers.fake import fake_robot
from drivers.sim.simulation import Simulation
from missions.cli import main
from missions.loader import load_mission
from missions.runner import Runner, RunOptions

BOOM_PLUGIN = """
from py_trees.common import Status
from behaviours.base import BearingsBehaviour
from behaviours.registry import register

@register
class Boom(BearingsBehaviour):
    '''Raises on its third tick (a test plugin).'''
    def initialise(self):
        self.count = 0
    def update(self):
        self.count += 1
        if self.count == 3:
            raise ZeroDivisionError("the flux capacitor")
        return Status.RUNNING
"""


def test_square_mission_report_shows_the_square(tmp_path):
    report, recording = tmp_path / "square.json", tmp_path / "square.rrd"
    code = main(["run", "square", "--seed", "3", "--quiet", "--report", str(report), "--save", str(recording)])
    assert code == 0
    data = json.loads(report.read_text())
    assert data["mission"] == "square" and data["status"] == "SUCCESS"
    assert data["ticks"] > 100 and data["sim_time_s"] == pytest.approx(data["ticks"] / 10 - 0.1, abs=0.11)
    gt = data["ground_truth"]
    assert gt["trajectory_length_m"] == pytest.approx(4.0, abs=0.1)
    assert gt["path_error_m"] < 0.05
    assert gt["goal_error_m"] < 0.2
    xy = [(row[1], row[2]) for row in gt["trajectory"]]
    corners = [(1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    for cx, cy in corners:  # the true path passes near every corner of the square
        assert min(math.hypot(x - cx, y - cy) for x, y in xy) < 0.12
    assert recording.stat().st_size > 10_000


def test_same_seed_same_report_different_seed_different_run(tmp_path):
    def run(seed: int) -> dict:
        path = tmp_path / f"r{seed}.json"
        assert main(["run", "square", "--seed", str(seed), "--quiet", "--report", str(path)]) == 0
        data = json.loads(path.read_text())
        data.pop("wall_time_s")
        return data

    first, again, other = run(7), run(7), run(8)
    assert first == again
    assert first["ground_truth"]["trajectory"] != other["ground_truth"]["trajectory"]


def _mission(write_mission, tree: str, **extra: str):
    head = "".join(f"{k}: {v}\n" for k, v in extra.items())
    return load_mission(write_mission(head + "tree:\n" + textwrap.indent(textwrap.dedent(tree), "  ")))


def test_exception_in_a_behaviour_is_a_failure_with_a_reason_and_a_stop(write_mission, tmp_path):
    (tmp_path / "boom.py").write_text(BOOM_PLUGIN)
    mission = _mission(write_mission, """
        Parallel:
          children:
            - Drive: {distance: 10.0}
            - Boom
    """, plugins="[./boom.py]")
    robot = fake_robot()
    result = Runner(mission, robot, options=RunOptions(report_path=tmp_path / "r.json"), clock=ManualClock()).run()
    assert result.status == "FAILURE"
    assert result.reason == "Boom (Boom) raised ZeroDivisionError: the flux capacitor"
    assert any(v > 0 for v, _ in robot.base.commands)  # it was driving ...
    assert robot.base.commands[-1] == (0.0, 0.0)  # ... and the last command is a stop
    assert robot.base.closed is False  # closing is the caller's job, after the stop
    assert json.loads((tmp_path / "r.json").read_text())["reason"] == result.reason


def test_failure_of_the_tree_stops_the_robot(write_mission):
    mission = _mission(write_mission, """
        Sequence:
          children:
            - Timeout:
                duration: 1.0
                child: {Drive: {distance: 10.0}}
    """)
    robot = fake_robot()
    result = Runner(mission, robot, clock=ManualClock()).run()
    assert result.status == "FAILURE" and result.ticks == 11
    assert "timed out after 1 s" in result.reason
    assert robot.base.commands[-1] == (0.0, 0.0)


def test_sigterm_stops_the_robot_and_reports(write_mission, tmp_path):
    mission = _mission(write_mission, "Drive: {distance: 100.0}\n")
    robot = fake_robot()

    def terminate_at_tick_5(runner: Runner) -> None:
        if runner.ticks == 5:
            os.kill(os.getpid(), signal.SIGTERM)

    previous = signal.getsignal(signal.SIGTERM)
    result = Runner(mission, robot, clock=ManualClock(), on_tick=terminate_at_tick_5,
                    options=RunOptions(report_path=tmp_path / "r.json")).run()
    assert result.status == "INTERRUPTED" and result.reason == "interrupted by SIGTERM"
    assert result.ticks == 5 and result.exit_code == 143
    assert robot.base.commands[-1] == (0.0, 0.0)
    assert signal.getsignal(signal.SIGTERM) is previous  # handlers restored
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["status"] == "INTERRUPTED" and report["last_command"] == {"v": 0.0, "w": 0.0}


def test_a_dead_sensor_fails_the_mission_and_stops(write_mission):
    mission = _mission(write_mission, "Drive: {distance: 1.0}\n")
    robot = fake_robot()
    robot.base.fail_on_odometry = OSError("serial port vanished")
    result = Runner(mission, robot, clock=ManualClock()).run()
    assert result.reason == "ReadOdometry (ReadOdometry) raised OSError: serial port vanished"
    assert robot.base.commands == [(0.0, 0.0)]


def test_max_time_is_a_failure(write_mission):
    mission = _mission(write_mission, "Wait: {duration: 100.0}\n")
    result = Runner(mission, fake_robot(), clock=ManualClock(), options=RunOptions(max_time_s=2.0)).run()
    assert result.status == "FAILURE" and result.reason == "time limit of 2 s reached"
    assert result.ticks == 20


def test_commands_do_not_outlive_their_tick(write_mission):
    mission = _mission(write_mission, """
        Sequence:
          children:
            - Drive: {distance: 0.02, speed: 0.2}
            - Wait: {duration: 0.5}
    """)
    sim = Simulation.load(None, seed=0)
    Runner(mission, sim.robot, clock=sim.clock(), observers=[sim]).run()
    commands = sim.robot.base.commands
    moving = [i for i, (_, v, _w) in enumerate(commands) if v != 0.0]
    assert moving and all(v == 0.0 for _, v, _w in commands[moving[-1] + 1:])
    assert len(commands) - moving[-1] > 4  # the waiting ticks sent stops, not the old command


def test_cli_exit_codes(write_mission, capsys):
    good = write_mission("tree: Stop\n", name="good.yaml")
    bad = write_mission("tree: Stpo\n", name="bad.yaml")
    failing = write_mission("tree: Failure\n", name="failing.yaml")
    assert main(["run", str(good), "--quiet"]) == 0
    assert main(["run", str(failing), "--quiet"]) == 1
    assert main(["run", str(bad), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:1:7: unknown node type 'Stpo'; did you mean 'Stop'?" in err
    assert "Traceback" not in err
    assert main(["run", str(good), "--sim", "no-such-world", "--quiet"]) == 2
    assert main(["run", str(good), "--set", "novalue", "--quiet"]) == 2
    assert main(["validate", str(good), str(bad)]) == 2
    assert main(["validate", str(good)]) == 0


def test_show_formats(capsys):
    import xml.etree.ElementTree as ET

    assert main(["show", "square", "--format", "xml"]) == 0
    root = ET.fromstring(capsys.readouterr().out.split("\n", 1)[1])
    assert root.tag == "root" and root.get("BTCPP_format") == "4"
    assert root.find("BehaviorTree/Sequence/Repeat").get("num_cycles") == "4"
    assert root.find("TreeNodesModel/Action[@ID='Drive']/input_port[@name='distance']") is not None
    assert main(["show", "square", "--format", "dot"]) == 0
    assert capsys.readouterr().out.startswith('digraph "square"')
    assert main(["show", "square"]) == 0
    assert "└── --> Stop" in capsys.readouterr().out


def test_reactive_composites_export_as_reactive(write_mission, capsys):
    path = write_mission("tree:\n  Selector:\n    memory: false\n    children: [Stop, Failure]\n")
    assert main(["show", str(path), "--format", "xml"]) == 0
    assert "<ReactiveFallback>" in capsys.readouterr().out


def test_showcase_in_the_lab_is_deterministic_on_rendered_pixels(tmp_path):
    def run(name: str) -> dict:
        path = tmp_path / f"{name}.json"
        code = main(["run", "showcase", "--sim", "lab", "--seed", "5", "--max-time", "4", "--quiet",
                     "--report", str(path)])
        assert code == 1  # cut short by --max-time ...
        data = json.loads(path.read_text())
        assert data["reason"] == "time limit of 4 s reached"  # ... and not blind: the guard held
        data.pop("wall_time_s")
        return data

    first, second = run("a"), run("b")
    assert first == second
    assert first["ground_truth"]["trajectory_length_m"] > 0.5


def test_a_mission_needing_a_camera_the_world_lacks_is_invalid(write_mission, capsys):
    path = write_mission("cameras: [periscope]\ntree: Stop\n")
    assert main(["run", str(path), "--sim", "lab", "--quiet"]) == 2
    assert "the mission uses camera(s) periscope, which world lab does not have" in capsys.readouterr().err


def test_runner_refuses_a_missing_camera_at_setup_before_any_motion(write_mission):
    mission = load_mission(write_mission("cameras: [periscope]\ntree: {Drive: {distance: 1.0}}\n"))
    robot = fake_robot(cameras=("front",))
    result = Runner(mission, robot, clock=ManualClock()).run()
    assert result.status == "FAILURE" and result.ticks == 0
    assert "has no camera periscope (it has: front)" in result.reason
    assert robot.base.commands == [(0.0, 0.0)]


REPORTING_PLUGIN = """
from py_trees.common import Status
from behaviours.base import BearingsBehaviour
from behaviours.registry import register
from behaviours.telemetry import Event, Figure

@register
class CountTicks(BearingsBehaviour):
    '''Counts its ticks; reports them as figures and draws an event per tick (a test plugin).'''
    def initialise(self):
        self.ticks, self.logged = 0, 0
    def update(self):
        self.ticks += 1
        return Status.SUCCESS if self.ticks == 5 else Status.RUNNING
    def figures(self):
        yield Figure("counting", "ticks", self.ticks)
        yield Figure("counting", "logged", self.logged)
    def drawings(self):
        self.logged += 1
        yield Event("counting/events", f"tick {self.ticks}")
"""


def test_nodes_add_report_sections_and_recordings(write_mission, tmp_path):
    (tmp_path / "count.py").write_text(REPORTING_PLUGIN)
    mission = _mission(write_mission, "CountTicks\n", plugins="[count.py]", cameras="[]")
    result = Runner(mission, fake_robot(), clock=ManualClock(),
                    options=RunOptions(save_path=tmp_path / "run.rrd")).run()
    assert result.status == "SUCCESS"
    assert result.report["counting"] == {"ticks": 5, "logged": 5}


def test_the_runner_hands_the_tree_a_keyboard_opened_only_by_a_node_that_drives_by_keys(write_mission):
    from drivers.fake import FakeKeys

    opened: list[FakeKeys] = []

    def keyboard() -> FakeKeys:
        opened.append(FakeKeys([["up"], ["up"], ["q"]]))
        return opened[-1]

    unused = _mission(write_mission, """
        Selector:
          children:
            - Success
            - KeyboardTeleop
    """)
    assert Runner(unused, fake_robot(), clock=ManualClock(), keyboard=keyboard).run().status == "SUCCESS"
    assert opened == []  # the teleop node never ran: the keyboard was never opened
    robot = fake_robot()
    driven = _mission(write_mission, "KeyboardTeleop: {speed: 0.25}\n")
    result = Runner(driven, robot, clock=ManualClock(), keyboard=keyboard).run()
    assert result.status == "SUCCESS" and result.reason == "mission tree succeeded"
    assert robot.base.commands[:2] == [(0.25, 0.0), (0.25, 0.0)] and robot.base.commands[-1] == (0.0, 0.0)
    assert len(opened) == 1 and opened[0].closed  # opened once, given back when the drive ended
