"""``bearings bench localisation``: named figures of the visual SLAM against the ideal EKF (no wall-clock asserts)."""

from __future__ import annotations

import json

import pytest

from experiments.bench import localisation


def test_bench_reports_the_cost_and_the_errors_of_both_localisations() -> None:
    figures = localisation.run(quick=True)
    json.dumps(figures)  # serialisable
    for key in ("ideal_ms_per_frame", "visual_stereo_ms", "visual_slam_ms"):
        assert figures[key] > 0
    assert figures["visual_ms_per_frame"] == pytest.approx(figures["visual_stereo_ms"] + figures["visual_slam_ms"],
                                                           abs=0.002)
    assert figures["visual_heading_error_deg"] < figures["odometry_heading_error_deg"]
    assert figures["visual_keyframes"] >= 1 and figures["visual_landmarks"] > 100
