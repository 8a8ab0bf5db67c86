"""The shipped explore mission end to end in a small simulated room (docs/exploration.md)."""

from __future__ import annotations

import json
from pathlib import Path

from drivers.sim.world import load_world
from experiments.eval.exploration import check_world, episode_figures
from missions.cli import main

BOX = str(Path(__file__).resolve().parents[1] / "data" / "worlds" / "box.yaml")


def test_the_library_mission_validates():
    assert main(["validate", "explore"]) == 0


def test_explores_a_room_and_ends_by_itself_recorded(tmp_path):
    out, rrd = tmp_path / "explore.json", tmp_path / "explore.rrd"
    assert main(["run", "explore", "--sim", BOX, "--seed", "2", "--quiet", "--report", str(out),
                 "--save", str(rrd)]) == 0  # a logging error would fail the run
    report = json.loads(out.read_text())
    assert report["status"] == "SUCCESS" and report["exploration"]["done"] is True
    figures = episode_figures(report, check_world(BOX), load_world(BOX).robot_radius)
    assert figures["collisions"] == 0 and figures["coverage"] >= 0.9
    located = report["exploration"]["localisation"]  # on the stereo pair's own features
    assert located["source"] == "visual" and located["landmarks"] > 100 and located["keyframes"] >= 1
    assert figures["pose_error_m"] < 0.1 and figures["heading_error_deg"] < 2.0
    assert report["exploration"]["integrations"] > 10 and report["exploration"]["scans"]
    recorded = rrd.read_bytes()
    for entity in ("exploration/map", "exploration/borders", "exploration_3d/points", "exploration/gaze",
                   "localisation/pose"):
        assert entity.encode() in recorded, entity
