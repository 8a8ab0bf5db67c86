"""Small helpers the evaluation areas share to summarise episodes and print their tables."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from scipy.stats import binomtest

CONFIDENCE = 0.95  # of the interval printed beside a success count


def mean_present(values: Sequence[Any]) -> float | None:
    """Mean of the values that are there (None: an episode without that figure); None when none is."""
    present = [float(v) for v in values if v is not None]
    return float(np.mean(present)) if present else None


def success_interval(successes: int, trials: int, confidence: float = CONFIDENCE) -> tuple[float, float] | None:
    """Where the success rate behind ``successes`` of ``trials`` lies, with ``confidence``: the Wilson
    score interval (None without trials). Five of five seeds says the rate is above 0.57, not that it
    is 1: a table prints this beside its counts so that nobody reads more into a few seeds."""
    if trials <= 0:
        return None
    ci = binomtest(int(successes), int(trials)).proportion_ci(confidence, method="wilson")
    return float(ci.low), float(ci.high)


def interval_text(interval: tuple[float, float] | None) -> str:
    """``0.57-1.00`` for an interval (``-`` for none)."""
    return "-" if interval is None else f"{interval[0]:.2f}-{interval[1]:.2f}"


def interval_cell(successes: int, trials: int) -> str:
    """``95 % 0.57-1.00`` for a success count (``-`` without trials)."""
    interval = success_interval(successes, trials)
    return "-" if interval is None else f"{round(100 * CONFIDENCE)} % {interval_text(interval)}"


def cell(value: Any, digits: int = 3) -> str:
    """A table cell: ``-`` for a missing figure, floats to ``digits`` places."""
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def safety_figures(report: Mapping[str, Any] | None) -> dict[str, Any]:
    """What one run says about obstacles: ``collisions`` (the simulator's ground truth: contact
    episodes), ``safety_stops`` (the collision monitor's stop episodes) and ``min_clearance_m``
    (the true smallest distance from the robot to anything, when the simulator reports it; else
    None). Every evaluation's criterion requires ``collisions == 0``."""
    report = report or {}
    truth, safety = report.get("ground_truth", {}), report.get("safety", {})
    clearance = truth.get("min_clearance_m")
    return {"collisions": int(truth.get("collisions", 0)), "safety_stops": int(safety.get("safety_stops", 0)),
            "min_clearance_m": None if clearance is None else float(clearance)}


def safety_totals(runs: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Over runs: collisions and safety stops summed (counts, not means), the smallest clearance."""
    clearances = [float(r["min_clearance_m"]) for r in runs if r.get("min_clearance_m") is not None]
    return {"collisions": sum(int(r.get("collisions", 0)) for r in runs),
            "safety_stops": sum(int(r.get("safety_stops", 0)) for r in runs),
            "min_clearance_m": min(clearances) if clearances else None}


def safety_cells(figures: Mapping[str, Any]) -> str:
    """``collisions / safety stops / min clearance`` for a table line."""
    return (f"{figures.get('collisions', 0)} coll, {figures.get('safety_stops', 0)} stops, clear "
            f"{cell(figures.get('min_clearance_m'), 2)}")
