"""``bearings bench sim``: named figures of the simulator's speed (no wall-clock asserts)."""

from __future__ import annotations

import json

import pytest

from experiments.bench import sim as bench_sim


def test_bench_reports_named_json_figures() -> None:
    figures = bench_sim.run(quick=True)
    json.dumps(figures)  # serialisable
    for key in ("panoramas_per_s_lab", "panoramas_per_s_outdoor", "steps_per_s_bearings", "remap_reference_ms"):
        assert figures[key] > 0
    assert figures["panorama_cost_ratio_lab"] == pytest.approx(
        1e3 / figures["panoramas_per_s_lab"] / figures["remap_reference_ms"], rel=0.01
    )
