"""The table of ``bearings eval ltmap``: one row per number of tree levels cut (the paper's Table I),
the headline memory limits, and how the repeats estimated their motion.

Besides the paper's columns, a row shows the map's bytes per metre of taught route (``B/m``:
what gap filling saves) and, as percentages of the repeats' estimates, the rule that made each
(``FollowRoute``'s ``ltmap.estimates``): ``z1`` .. ``z8`` Z-infinity's far threshold of 1, 2, 4
or 8 degrees (the paper's is 1), ``cmp`` the compass of all landmarks, ``none`` no rotation,
``lost`` too few matches.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from behaviours.route import ESTIMATE_RULES
from experiments.eval import people as crowd
from experiments.eval.figures import cell, interval_cell, mean_present, safety_cells, safety_totals, success_interval

RULE_COLUMNS = {"zinf_1deg": "z1", "zinf_2deg": "z2", "zinf_4deg": "z4", "zinf_8deg": "z8", "compass": "cmp",
                "no_rotation": "none", "lost": "lost"}


def _per_metre(figures: Mapping[str, Any]) -> float | None:
    rows = figures.get("rows") or []
    return rows[0].get("bytes_per_m") if rows else None


def estimate_shares(counts: Mapping[str, int]) -> dict[str, float] | None:
    """Per rule (:data:`behaviours.route.ESTIMATE_RULES`) its percentage of a repeat's estimates
    (None: the repeat made none, or its report predates the counts)."""
    total = sum(int(counts.get(rule, 0)) for rule in ESTIMATE_RULES)
    return {rule: 100.0 * int(counts.get(rule, 0)) / total for rule in ESTIMATE_RULES} if total else None


def row_figures(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """One Table-I row: means over the seeds' repeats of one number of levels cut."""
    heights = sorted({r["height"] for r in runs})
    good = [r for r in runs if r.get("status") != "ERROR"]
    reached = [r for r in runs if r["reached"]]
    row: dict[str, Any] = {
        "levels_cut": runs[0]["cut"],
        "height": heights[0] if len(heights) == 1 else None,
        "height_range": [heights[0], heights[-1]],
        "seeds": len(runs),
        "viewframes": mean_present([r["viewframes"] for r in runs]),
        "landmarks": mean_present([r["landmarks"] for r in runs]),
        "bytes": mean_present([r["bytes"] for r in runs]),
        "memory_pct": 100.0 * (mean_present([r["memory_fraction"] for r in runs]) or 0.0),
        "viewframe_error_m": mean_present([r.get("viewframe_error_m") for r in good]),
        "path_error_m": mean_present([r.get("path_error_m") for r in good]),
        "path_error_reached_m": mean_present([r.get("path_error_m") for r in reached]),
        "goal_error_m": mean_present([r.get("goal_error_m") for r in good]),
        "goal_reached": len(reached),
        "goal_reached_interval": success_interval(len(reached), len(runs)),
        "viewframes_reached_pct": 100.0 * (mean_present([r.get("viewframes_reached") for r in good]) or 0.0),
        "bytes_per_m": mean_present([r.get("bytes_per_m") for r in runs]),
        "estimates_pct": {rule: mean_present([(r.get("estimates_pct") or {}).get(rule) for r in good])
                          for rule in ESTIMATE_RULES},
        "recoveries": mean_present([r.get("recoveries") for r in good]),
        "sim_time_s": mean_present([r.get("sim_time_s") for r in good]),
        **safety_totals(good),
    }
    if len(good) < len(runs):
        row["errors"] = len(runs) - len(good)
    return row




def memory_limits(rows: list[dict[str, Any]]) -> dict[str, float | None]:
    """As the paper puts it ("goal still reached at 57 % memory, lost at 35 %"): going down from the
    full tree, the memory of the last row where every taught seed reached the goal, and of the first
    row where one did not (None: no such row)."""
    still, lost = None, None
    for row in rows:  # a row of fewer seeds (their trees were not that tall) counts by the seeds it has
        if row["goal_reached"] == row["seeds"]:
            still = row["memory_pct"]
        else:
            lost = row["memory_pct"]
            break
    return {"goal_reached_down_to_memory_pct": still, "goal_first_missed_memory_pct": lost}


def format_table(figures: Mapping[str, Any]) -> str:
    """The rows as the paper's Table I, with the setting above them."""
    route = f"{figures['route_source']} of {figures['route_length_m']:.1f} m"
    lines = [
        f"LT-map teach and repeat in {figures['world']}: {figures['seeds']} seed(s), camera {figures['camera']}, "
        f"rotation {figures.get('rotation', 'zinf')}, route: {route}, taught {figures['taught']}/{figures['seeds']}",
        f"goal reached: {figures['criterion']}; min_landmarks {figures['min_landmarks']}; path error of the repeats "
        "that reached the goal (of all repeats)",
        f"gap filling {'on' if figures.get('gap_filling', True) else 'off'}: "
        f"{cell(figures.get('teach.shifted'), 1)} landmarks shifted to a common node and "
        f"{cell(figures.get('teach.loop_closures'), 1)} loops closed per teach; "
        f"{cell(_per_metre(figures), 0)} B per metre of route (full tree)",
        "estimates % by rule: z1..z8 Z-infinity's far threshold 1..8 deg, cmp the compass, none no rotation, "
        "lost too few matches",
        f"{'height':>6} {'cut':>3} {'viewframes':>10} {'landmarks':>9} {'memory %':>8} {'B/m':>6} {'vf err m':>8} "
        f"{'path err m':>16} {'goal err m':>10} {'vf reached %':>12} {'goal reached':>12} "
        + " ".join(f"{name:>4}" for name in RULE_COLUMNS.values()) + "  obstacles",
    ]
    for row in figures["rows"]:
        low, high = row["height_range"]
        height = str(low) if low == high else f"{low}-{high}"
        path = f"{cell(row['path_error_reached_m'])} ({cell(row['path_error_m'])})"
        shares = row.get("estimates_pct") or {}
        lines.append(f"{height:>6} {row['levels_cut']:>3} {cell(row['viewframes'], 1):>10} "
                     f"{cell(row['landmarks'], 0):>9} {cell(row['memory_pct'], 1):>8} "
                     f"{cell(row.get('bytes_per_m'), 0):>6} "
                     f"{cell(row['viewframe_error_m']):>8} {path:>16} {cell(row['goal_error_m']):>10} "
                     f"{cell(row['viewframes_reached_pct'], 0):>12} {row['goal_reached']:>7} of {row['seeds']:<3} "
                     + " ".join(f"{cell(shares.get(rule), 0):>4}" for rule in RULE_COLUMNS)
                     + f"  {safety_cells(row)}" + (f"  ({row['errors']} errors)" if row.get("errors") else ""))
    still, lost = figures.get("goal_reached_down_to_memory_pct"), figures.get("goal_first_missed_memory_pct")
    if figures["rows"]:
        full = figures["rows"][0]
        lines.append(f"goal reached by every seed down to {cell(still, 1)} % memory; first missed at "
                     f"{cell(lost, 1)} %; on the full map {full['goal_reached']} of {full['seeds']}, the rate "
                     f"{interval_cell(full['goal_reached'], full['seeds'])} (Wilson)")
    lines.append(f"teaching: {safety_cells({k[6:]: v for k, v in figures.items() if k.startswith('teach.')})}")
    lines += crowd.table_line(figures)
    for fail in figures["teach_failed"]:
        lines.append(f"seed {fail['seed']}: no map to repeat ({fail['problem']})")
    if figures.get("warning"):
        lines.append(f"warning: {figures['warning']}")
    return "\n".join(lines)
