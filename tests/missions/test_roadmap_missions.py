"""The roadmap missions end to end in the simulator (short runs; the long measurements are by hand,
``python -m tests.missions.measure_roadmap``, figures in docs/roadmap.md)."""

from __future__ import annotations

import contextlib
import io
import json
import math

import numpy as np
import pytest

from maps.roadmap import EdgeMotion, Roadmap
from missions.cli import main
from perception.geometry import Pose2D
from tests.missions.roadmap_world import named_poses, pose_error, world_with, write_target_images


def run(*args: str) -> int:
    with contextlib.redirect_stdout(io.StringIO()):
        return main(list(args))


@pytest.mark.parametrize("mission", ["learn_targets", "goto_target"])
def test_the_library_missions_validate(mission):
    assert run("validate", mission) == 0


def test_goto_target_reaches_the_goal_through_the_graph(tmp_path):
    """A roadmap made from the lab's true poses (reference frame = world frame), one edge window -> centre;
    the robot starts near the window, not knowing where it is."""
    poses = named_poses("lab")
    images = write_target_images("lab", ["window", "centre"], tmp_path / "targets")
    covariance = np.diag([1e-4, 1e-4, 1e-4])
    edge = EdgeMotion.from_relative_pose(poses["centre"].relative_to(poses["window"]), covariance)
    roadmap = (Roadmap().with_target("window", poses["window"], "targets/window.png")
               .with_target("centre", poses["centre"], "targets/centre.png").with_edge("window", "centre", edge))
    roadmap.save(tmp_path / "lab.roadmap")
    assert (images / "window.png").is_file()
    world = world_with("lab", tmp_path / "lab.yaml", start=Pose2D(3.6, 1.6, math.radians(60)))
    report = tmp_path / "goto.json"
    code = run("run", "goto_target", "--sim", str(world), "--quiet", "--report", str(report),
               "--set", f"roadmap={tmp_path / 'lab.roadmap'}", "--set", "target=centre")
    data = json.loads(report.read_text())
    assert code == 0, data["reason"]
    navigation = data["roadmap"]["navigation"]
    assert navigation["reached"] and navigation["visited"] == ["window", "centre"]
    final = data["ground_truth"]["final_pose"]
    distance, heading = pose_error(Pose2D(final["x"], final["y"], final["theta"]), poses["centre"])
    assert distance < 0.05 and heading < 2.0
    assert data["last_command"] == {"v": 0.0, "w": 0.0}


def test_goto_target_without_a_target_name_fails_saying_so(tmp_path):
    write_target_images("lab", ["door"], tmp_path)
    Roadmap().with_target("door", Pose2D(), "door.png").save(tmp_path / "r.roadmap")
    report = tmp_path / "r.json"
    code = run("run", "goto_target", "--sim", "lab", "--quiet", "--report", str(report),
               "--set", f"roadmap={tmp_path / 'r.roadmap'}")
    assert code == 1
    assert json.loads(report.read_text())["reason"] == ("NavigateToTarget failed: no target given (goto_target: "
                                                         "--set target=NAME)")
