"""The roadmap missions end to end in the simulator (short runs; the long measurements are
``bearings eval roadmap``'s, figures in docs/roadmap.md)."""

from __future__ import annotations

import contextlib
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest

from experiments.eval.roadmap_world import named_poses, pose_error, world_with, write_target_images
from experiments.eval.trajectory import TrueTrajectory
from maps.roadmap import EdgeMotion, Roadmap
from missions.cli import main
from perception.geometry import Pose2D

SMALL_ROOM = """
    # a 5 x 4 m room with a box and a pillar; cameras at half resolution, so a whole learning run
    # takes seconds (the geometry of the lab's robot: pan-tilt at 1 m, cameras 5 cm ahead of it)
    format: 1
    name: small
    seed: 4
    ceiling: 2.4
    ground_margin: 3
    start: {x: 2.5, y: 2.2, theta_deg: -90}
    poses:
      a: {x: 1.4, y: 1.2, theta_deg: 40}
      b: {x: 3.6, y: 1.3, theta_deg: 140}
    walls:
      - points: [[0, 0], [5, 0], [5, 4], [0, 4]]
        closed: true
        height: 2.4
        texture: {seed: 21, pixels_per_m: 60, feature_size: 0.2}
    boxes:
      - {center: [4.3, 3.4], size: [1.0, 0.8], height: 0.9}
    pillars:
      - {center: [1.2, 3.0], radius: 0.15, height: 2.4}
    ptu: {position: [0.1, 0.0, 1.0]}
    cameras:
      - name: front
        kind: pinhole
        mount: ptu
        pose: {x: 0.05, z: 0.08}
        model: {width: 320, height: 240, fx: 262.5, fy: 262.5, cx: 159.5, cy: 119.5}
      - name: stereo
        kind: stereo
        mount: ptu
        pose: {x: 0.05, z: 0.08}
        model: {width: 320, height: 240, fx: 262.5, fy: 262.5, cx: 159.5, cy: 119.5, baseline: 0.12}
    """


def run(*args: str) -> int:
    with contextlib.redirect_stdout(io.StringIO()):
        return main(list(args))


def goto(world: Path, roadmap: Path, target: str, report: Path) -> dict:
    """The report of a ``goto_target`` run that succeeded."""
    code = run("run", "goto_target", "--sim", str(world), "--quiet", "--report", str(report),
               "--set", f"roadmap={roadmap}", "--set", f"target={target}")
    data = json.loads(report.read_text())
    assert code == 0, data["reason"]
    return data


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
    data = goto(world, tmp_path / "lab.roadmap", "centre", tmp_path / "goto.json")
    navigation = data["roadmap"]["navigation"]
    assert navigation["reached"] and navigation["visited"] == ["window", "centre"]
    final = data["ground_truth"]["final_pose"]
    distance, heading = pose_error(Pose2D(final["x"], final["y"], final["theta"]), poses["centre"])
    assert distance < 0.05 and heading < 2.0
    assert data["last_command"] == {"v": 0.0, "w": 0.0}


def test_goto_target_without_a_target_name_stops_before_anything_moves(tmp_path, capsys):
    write_target_images("lab", ["door"], tmp_path)
    Roadmap().with_target("door", Pose2D(), "door.png").save(tmp_path / "r.roadmap")
    report = tmp_path / "r.json"
    code = run("run", "goto_target", "--sim", "lab", "--quiet", "--report", str(report),
               "--set", f"roadmap={tmp_path / 'r.roadmap'}")
    assert code == 2 and not report.exists()  # the target input is declared required: refused at load
    assert "input 'target' is required: give it with --set target=VALUE" in capsys.readouterr().err


def test_learn_targets_then_goto_target_in_a_small_room(tmp_path, world_file):
    """The whole learning mission (dodecagon, search, homing, graph), then navigation on what it learned."""
    world = world_file(SMALL_ROOM, "small.yaml")
    folder = write_target_images(world, ["a", "b"], tmp_path / "targets")
    roadmap, report = tmp_path / "small.roadmap", tmp_path / "learn.json"
    code = run("run", "learn_targets", "--sim", str(world), "--quiet", "--report", str(report),
               "--set", f"targets={folder}", "--set", f"roadmap={roadmap}", "--output-dir", str(tmp_path))
    data = json.loads(report.read_text())
    assert code == 0, data["reason"]
    section = data["roadmap"]
    assert section["connected"] and [(e["from"], e["to"]) for e in section["edges"]] in ([("a", "b")], [("b", "a")])
    reference = TrueTrajectory(data["ground_truth"]).at(section["room"]["reference_stamp"])
    truth = named_poses(world)
    for name, estimate in section["targets"].items():  # the done-when thresholds: 0.15 m, 5 deg
        distance, heading = pose_error(Pose2D(estimate["x"], estimate["y"], math.radians(estimate["theta_deg"])),
                                       truth[name].relative_to(reference))
        assert distance < 0.15 and heading < 5.0, name
    assert Roadmap.load(roadmap).names == ("a", "b")
    start = world_with(world, tmp_path / "start.yaml", start=Pose2D(3.4, 2.9, math.radians(-150)))
    data = goto(start, roadmap, "a", tmp_path / "goto.json")
    final = data["ground_truth"]["final_pose"]
    distance, heading = pose_error(Pose2D(final["x"], final["y"], final["theta"]), truth["a"])
    assert distance < 0.05 and heading < 2.0
