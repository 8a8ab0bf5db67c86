"""``bearings run --trace S``: a line every S seconds of run time, and the closest approaches."""

from __future__ import annotations

import io
from types import SimpleNamespace

import numpy as np
import py_trees

from drivers.interfaces import VelocityCommand
from missions import cli
from missions.trace import Trace
from perception.collision_monitor import SafetyState
from perception.geometry import Pose2D


def test_a_simulated_run_prints_a_line_every_period_of_sim_time(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["run", "square", "--sim", "lab", "--trace", "2", "--max-time", "5", "--quiet"]) == 1
    lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("t=")]
    assert [line.split()[0:2] for line in lines] == [["t=", "0.0"], ["t=", "2.0"], ["t=", "4.0"]]
    # the lab's start (1.5, 1.5, 30 deg), square's first side of 1 m at 0.3 m/s
    assert lines[0].startswith("t=    0.0 true=(1.50,1.50,  30deg) cmd=(0.30,") and "safety=clear" in lines[0]
    assert lines[0].endswith("| Drive: +1.00 m to go")


def test_a_period_that_is_not_positive_is_refused(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["run", "square", "--sim", "lab", "--trace", "0"]) != 0
    assert "--trace" in capsys.readouterr().err


def test_every_new_closest_approach_under_5_cm_is_a_line_of_its_own():
    leaf = py_trees.behaviours.Running(name="Hold")
    leaf.tick_once()
    clock = SimpleNamespace(now=lambda: 0.0)
    truth = SimpleNamespace(min_clearance=0.2, true_pose=lambda: Pose2D(1.0, 2.0, 0.0),
                            people_xy=lambda: np.array([[1.5, 2.0], [9.0, 9.0]]))
    runner = SimpleNamespace(clock=clock, last_command=VelocityCommand(0.1, 0.0), guard=SimpleNamespace(
        state=SafetyState(state="slowed")), root=leaf, observers=[truth])
    out = io.StringIO()
    trace = Trace(10.0, out)
    for t, clearance in ((0.0, 0.2), (0.1, 0.04), (0.2, 0.03), (0.3, 0.035), (0.4, 0.01)):
        clock.now = lambda t=t: t
        truth.min_clearance = clearance
        trace(runner)
    lines = out.getvalue().splitlines()
    assert lines[0] == ("t=    0.0 true=(1.00,2.00,   0deg) cmd=(0.10,0.00) safety=slowed "
                        "person0=(1.50,2.00) 0.50m | Hold: running")  # the person 9 m off is not named
    assert lines[1:] == [f"t=    {t} ** {c} m from something, the nearest yet"
                         for t, c in (("0.1", "0.040"), ("0.2", "0.030"), ("0.4", "0.010"))]
