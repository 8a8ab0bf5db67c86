"""``bearings bench sim``: named figures of the simulator's speed (no wall-clock asserts)."""

from __future__ import annotations

import json

import pytest

from drivers.sim.world_file import LEVEL_PANORAMA_BYTES_PER_PIXEL, RENDER_BYTES_PER_PIXEL
from experiments.bench import sim as bench_sim


def test_bench_reports_named_json_figures() -> None:
    figures = bench_sim.run(quick=True)
    json.dumps(figures)  # serialisable
    for key in ("panoramas_per_s_lab", "panoramas_per_s_outdoor", "panoramas_per_s_lab_people", "steps_per_s_bearings",
                "remap_reference_ms"):
        assert figures[key] > 0
    assert figures["sonar_read_ms"] >= 0
    assert figures["panorama_cost_ratio_lab"] == pytest.approx(
        1e3 / figures["panoramas_per_s_lab"] / figures["remap_reference_ms"], rel=0.01
    )
    # the world loader budgets cameras with fixed figures (a world is valid or not on any machine):
    # they must cover the renderer's measured peak memory per pixel (a memory figure, not a time)
    measured = figures["render_bytes_per_pixel"]
    assert 300 < measured["pinhole"] <= RENDER_BYTES_PER_PIXEL
    assert 0 < measured["level_panorama"] <= LEVEL_PANORAMA_BYTES_PER_PIXEL
    assert figures["render_bytes_per_pixel_budgeted"] == {"pinhole": RENDER_BYTES_PER_PIXEL,
                                                          "level_panorama": LEVEL_PANORAMA_BYTES_PER_PIXEL}
