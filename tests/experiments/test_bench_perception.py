"""``bearings bench perception``: one JSON object of named figures (no wall-clock asserts)."""

from __future__ import annotations

import json

import pytest

from experiments.bench.perception import run
from missions.cli import main


@pytest.fixture(scope="module")
def figures() -> dict:
    return run(quick=True)


def test_figures_are_named_numbers_and_serialisable(figures):
    json.dumps(figures)
    for key in (
        "pipeline_fps",
        "pipeline_cost_ratio",
        "bare_orb_detect_knn_ms",
        "zinf_ms",
        "poselib_ms",
        "opencv_essential_ms",
        "planar_ms",
        "poselib_relpose_ms",
        "opencv_ransac_ms",
        "planar_vs_poselib_relpose_time_ratio",
        "planar_vs_opencv_ransac_time_ratio",
    ):
        assert isinstance(figures[key], float) and figures[key] > 0, key
    assert figures["frames_source"].startswith(("simulator:", "synthetic:"))


def test_accuracy_figures_are_sane(figures):
    assert figures["zinf_ok_fraction"] == 1.0
    assert figures["zinf_rotation_error_deg"] < 0.2
    assert figures["zinf_translation_error_deg"] < 2.0
    assert figures["planar_ok_fraction"] == 1.0
    assert figures["planar_rotation_error_deg"] < 0.5 and figures["planar_direction_error_deg"] < 3.0
    for other in ("poselib_relpose", "opencv_ransac", "opencv_magsac"):  # measured on the same scenes
        assert figures[f"{other}_rotation_error_deg"] < 5.0 and figures[f"{other}_direction_error_deg"] < 20.0
        assert figures[f"planar_vs_{other}_rotation_error_ratio"] == pytest.approx(
            figures["planar_rotation_error_deg"] / figures[f"{other}_rotation_error_deg"], rel=0.01
        )
    assert figures["pipeline_rotation_found_fraction"] > 0.8
    assert figures["pipeline_yaw_error_deg"] < 3.0


def test_cli_prints_one_json_object(capsys):
    assert main(["bench", "perception", "--json", "--quick"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["area"] == "perception" and "pipeline_cost_ratio" in printed
