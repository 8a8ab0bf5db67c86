"""What every evaluation reads about obstacles from a run report, and how runs add up."""

from __future__ import annotations

import pytest

from experiments.eval.figures import interval_cell, safety_cells, safety_figures, safety_totals, success_interval


def test_a_run_says_its_collisions_stops_and_clearance():
    report = {"ground_truth": {"collisions": 1, "min_clearance_m": 0.04}, "safety": {"safety_stops": 2}}
    assert safety_figures(report) == {"collisions": 1, "safety_stops": 2, "min_clearance_m": 0.04}
    # a report from before the monitor, or none at all: nothing counted, the clearance unknown
    assert safety_figures({"ground_truth": {}}) == {"collisions": 0, "safety_stops": 0, "min_clearance_m": None}
    assert safety_figures(None)["min_clearance_m"] is None


def test_runs_add_up_counts_and_keep_the_smallest_clearance():
    runs = [{"collisions": 1, "safety_stops": 2, "min_clearance_m": 0.3},
            {"collisions": 0, "safety_stops": 1, "min_clearance_m": None},
            {"collisions": 2, "safety_stops": 0, "min_clearance_m": 0.05}]
    totals = safety_totals(runs)
    assert totals == {"collisions": 3, "safety_stops": 3, "min_clearance_m": 0.05}
    assert safety_cells(totals) == "3 coll, 3 stops, clear 0.05"
    assert safety_totals([]) == {"collisions": 0, "safety_stops": 0, "min_clearance_m": None}


def test_a_success_count_comes_with_the_wilson_interval_of_its_rate():
    """Worked by hand, z = 1.96: centre (p + z^2 / 2n) / (1 + z^2 / n), half-width
    z / (1 + z^2 / n) sqrt(p (1 - p) / n + z^2 / 4n^2). 5 of 5: 0.7828 -+ 0.2172; 7 of 10: 0.6445 -+ 0.2477."""
    assert success_interval(5, 5) == pytest.approx((0.5655, 1.0), abs=1e-3)
    assert success_interval(7, 10) == pytest.approx((0.3968, 0.8922), abs=1e-3)
    assert success_interval(0, 0) is None
    assert interval_cell(5, 5) == "95 % 0.57-1.00" and interval_cell(0, 0) == "-"
