"""``bearings sim`` commands and the rerun log of a run."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from drivers.sim.simulation import Simulation
from missions.cli import main
from perception.geometry import Pose2D


def test_snapshot_writes_the_panorama_the_simulation_renders(tmp_path: Path, capsys) -> None:
    out = tmp_path / "target.png"
    assert main(["sim", "snapshot", "--world", "lab", "--pose", "4,3,90deg", "-o", str(out)]) == 0
    written = cv2.imdecode(np.frombuffer(out.read_bytes(), np.uint8), cv2.IMREAD_UNCHANGED)
    expected = Simulation.load("lab").snapshot(Pose2D(4, 3, math.pi / 2)).image
    assert np.array_equal(written, expected)
    assert "wrote" in capsys.readouterr().out


def test_snapshot_of_a_named_pose_with_a_stereo_camera_is_side_by_side(tmp_path: Path) -> None:
    out = tmp_path / "pair.png"
    assert main(["sim", "snapshot", "--world", "lab", "--pose", "door", "--camera", "stereo", "-o", str(out)]) == 0
    assert cv2.imread(str(out), cv2.IMREAD_GRAYSCALE).shape == (480, 1280)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--world", "atlantis", "--pose", "1,1"], "no such world file or shipped world"),
        (["--world", "lab", "--pose", "1,one"], "numbers expected"),
        (["--world", "lab", "--pose", "1,2,3,4"], "x,y,theta or a named pose"),
        (["--world", "lab", "--pose", "1,1", "--camera", "landmarks"], "bearings sensor"),
        (["--world", "lab", "--pose", "1,1", "--camera", "thermal"], "no camera 'thermal'"),
    ],
)
def test_snapshot_bad_input_exits_2_with_a_message(tmp_path: Path, capsys, args, message) -> None:
    out = tmp_path / "x.png"
    assert main(["sim", "snapshot", *args, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not out.exists()


def test_snapshot_reports_a_broken_world_file_with_its_line(tmp_path: Path, capsys) -> None:
    world = tmp_path / "bad.yaml"
    world.write_text("walls:\n  - {points: [[0, 0], [1, 0]], height: tall}\n")
    assert main(["sim", "snapshot", "--world", str(world), "--pose", "0,0", "-o", str(tmp_path / "x.png")]) == 2
    assert f"{world}:2:" in capsys.readouterr().err


def test_sim_worlds_lists_the_shipped_worlds(capsys) -> None:
    assert main(["sim", "worlds"]) == 0
    out = capsys.readouterr().out
    for name in ("lab", "corridor", "outdoor", "unbalanced"):
        assert f"{name}:" in out


def test_log_rerun_records_world_trajectories_and_view_direction(tmp_path: Path) -> None:
    import rerun as rr

    rec = rr.RecordingStream("bearings-test")
    path = tmp_path / "run.rrd"
    rec.save(str(path))
    sim = Simulation.load("lab", seed=0)
    camera = sim.robot.cameras["panorama"]
    sim.robot.ptu.move(1.0, 0.2, 1.0)
    for tick in range(25):
        rec.set_time("sim_time", duration=sim.time)
        sim.robot.base.drive(0.3, 0.2)
        sim.step(0.1)
        if tick % 5 == 0:
            camera.grab()
        sim.log_rerun(rec)
    rec.flush()
    rec.disconnect()
    logged = path.read_bytes()
    assert b"camera/panorama" not in logged  # images are the recorder's, from the frames the mission grabbed
    entities = ["world/walls", "world/landmarks", "world/ground_truth/ptu_view"]
    entities += ["world/ground_truth/trajectory_true", "world/ground_truth/trajectory_odometry"]
    for entity in entities:
        assert entity.encode() in logged, entity
