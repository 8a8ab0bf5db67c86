"""The LT-map missions: they validate, take their inputs, and teach and repeat a short route in the
simulator with the ideal bearings sensor (a fast run); rendered panoramas are measured by hand."""

from __future__ import annotations

import json
import math

import pytest

from maps.ltmap.file import load_ltmap
from missions.cli import main
from missions.loader import load_mission

MISSIONS = ("teach_route", "follow_route", "teach_and_repeat")


@pytest.mark.parametrize("name", MISSIONS)
@pytest.mark.parametrize("camera", ["panorama", "landmarks"])
def test_the_missions_validate_with_either_camera(name, camera):
    mission = load_mission(name, overrides={"camera": camera, "map": "some/where.ltmap"})
    assert mission.cameras == (camera,)  # only the camera the mission reads is grabbed
    assert main(["validate", name, "--set", f"camera={camera}"]) == 0


def test_follow_route_takes_its_evaluation_inputs():
    mission = load_mission("follow_route", overrides={"map": "m.ltmap", "memory": "0.6", "budget": "200000",
                                                      "direction": "forward", "camera": "landmarks"})
    assert mission.values["memory"] == 0.6 and mission.values["direction"] == "forward"


def test_teach_and_repeat_with_the_ideal_sensor_returns_home(tmp_path):
    path, report = tmp_path / "route.ltmap", tmp_path / "report.json"
    code = main(["run", "teach_and_repeat", "--sim", "lab", "--seed", "4", "--quiet", "--report", str(report),
                 "--set", "camera=landmarks", "--set", f"map={path}", "--set", "route=[1.6, 0.0]",
                 "--set", "min_landmarks=8", "--output-dir", str(tmp_path)])
    data = json.loads(report.read_text())
    assert code == 0, data["reason"]
    section = data["ltmap"]
    tree = load_ltmap(path)
    assert section["saved"] and len(section["taught"]) == tree.viewframe_count > 3
    assert section["switches"] == tree.viewframe_count and section["reached"][-1]["viewframe"] == 0
    assert [r["time_s"] for r in section["reached"]] == sorted(r["time_s"] for r in section["reached"])
    final = data["ground_truth"]["final_pose"]
    assert math.hypot(final["x"] - 1.5, final["y"] - 1.5) < 0.3  # home: the lab's start
    assert data["ground_truth"]["trajectory_length_m"] > 3.0


def test_teach_route_by_keyboard_needs_a_terminal(tmp_path):
    report = tmp_path / "report.json"
    code = main(["run", "teach_route", "--sim", "lab", "--quiet", "--report", str(report), "--max-time", "5",
                 "--set", "camera=landmarks", "--set", "drive=keyboard", "--set", f"map={tmp_path / 'r.ltmap'}",
                 "--output-dir", str(tmp_path)])
    data = json.loads(report.read_text())
    assert code == 1 and "terminal" in data["reason"] and not (tmp_path / "r.ltmap").exists()
