"""What every evaluation reads about obstacles from a run report, and how runs add up."""

from __future__ import annotations

from experiments.eval.figures import safety_cells, safety_figures, safety_totals


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
