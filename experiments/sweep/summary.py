"""Summaries of a results table: per parameter combination, the success rate, the commonest reasons
of the runs that did not succeed, and the mean and spread of every numeric figure; a printed table
(with the reasons under it: a sweep whose runs fail says why without opening ``results.jsonl``);
a plot of one figure against one swept parameter.

Collisions decide success: an episode succeeded when its mission ended in SUCCESS *and* the
simulator counted no collision (``ground_truth.collisions``); a SUCCESS that touched something is
counted in ``collided`` (with every other episode that collided), not in ``success``. The printed
table shows the collided episodes, the collision monitor's stops and the true minimum clearance.

A parameter combination is everything that defines an episode except its seed: mission, world,
``max_time_s`` and every ``inputs.<name>``. The spread is the sample standard deviation (0 for a
single episode), with the minimum and maximum beside it.
"""

from __future__ import annotations

import json
import statistics
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from experiments.sweep.table import is_number

Row = dict[str, Any]

GROUP_KEYS = ("mission", "world", "max_time_s")
NOT_FIGURES = frozenset({"id", "seed", "exit_code", "max_time_s"})
HEADLINE = ("sim_time_s", "ground_truth.goal_error_m", "ground_truth.path_error_m", "ground_truth.trajectory_length_m",
            "safety.safety_stops", "ground_truth.min_clearance_m")
"""Figures the printed table shows when they exist (every figure is in summary.json)."""
REASONS = 3
"""The commonest reasons of failure kept per parameter combination."""
COLLISIONS = "ground_truth.collisions"


def collided(row: Row) -> bool:
    """Did the episode touch anything (the simulator's ground truth)?"""
    count = row.get(COLLISIONS, 0)
    return is_number(count) and count > 0


def succeeded(row: Row) -> bool:
    """SUCCESS without a collision."""
    return row.get("status") == "SUCCESS" and not collided(row)


def failure_reason(row: Row) -> str:
    """Why an episode did not succeed: its reason, or that it collided although its mission succeeded."""
    if row.get("status") == "SUCCESS":
        return "the mission succeeded but the robot collided"
    return str(row.get("reason") or row.get("error") or "no reason")


def parameter_keys(rows: Sequence[Row]) -> list[str]:
    """The columns that define a parameter combination, in a stable order."""
    inputs = sorted({k for row in rows for k in row if k.startswith("inputs.")})
    return [*GROUP_KEYS, *inputs]


def figure_keys(rows: Sequence[Row]) -> list[str]:
    """Numeric outcome columns (anything numeric that is not a parameter), sorted."""
    params = set(parameter_keys(rows))
    keys = {k for row in rows for k, v in row.items() if is_number(v)}
    return sorted(k for k in keys - params - NOT_FIGURES if not k.endswith(".seed"))


def summarise(rows: Sequence[Row]) -> list[dict[str, Any]]:
    """One entry per parameter combination: its parameters, ``episodes``, ``success`` (SUCCESS
    without a collision), ``failure``, ``error``, ``collided`` (episodes with a collision, whatever
    their status), ``success_rate``, ``reasons`` (the commonest reasons of the runs that did not
    succeed, ``[{reason, count}]``, most frequent first) and ``figures`` {name: {n, mean, std, min,
    max}}."""
    params = parameter_keys(rows)
    figures = figure_keys(rows)
    groups: dict[str, list[Row]] = {}
    for row in rows:
        key = json.dumps([row.get(k) for k in params], default=str)
        groups.setdefault(key, []).append(row)
    out = []
    for members in groups.values():
        entry: dict[str, Any] = {k: members[0].get(k) for k in params}
        statuses = [m.get("status") for m in members]
        entry.update(episodes=len(members), success=sum(succeeded(m) for m in members),
                     failure=statuses.count("FAILURE"),
                     error=len(members) - statuses.count("SUCCESS") - statuses.count("FAILURE"),
                     collided=sum(collided(m) for m in members))
        entry["success_rate"] = entry["success"] / len(members)
        why = Counter(failure_reason(m) for m in members if not succeeded(m))
        entry["reasons"] = [{"reason": reason, "count": count} for reason, count in why.most_common(REASONS)]
        entry["figures"] = {}
        for name in figures:
            values = [m[name] for m in members if is_number(m.get(name))]
            if values:
                mean, std = mean_and_spread(values)
                entry["figures"][name] = {"n": len(values), "mean": mean, "std": std,
                                          "min": min(values), "max": max(values)}
        out.append(entry)
    return sorted(out, key=lambda e: [_order(e[k]) for k in params])


def mean_and_spread(values: Sequence[float]) -> tuple[float, float]:
    """Mean and sample standard deviation (0 for one value) of finite numbers, whatever their size:
    computed on the values divided by the largest magnitude, so 1e308 figures do not overflow."""
    scale = max(abs(float(v)) for v in values) or 1.0
    scaled = [float(v) / scale for v in values]
    spread = statistics.stdev(scaled) if len(scaled) > 1 else 0.0
    return statistics.fmean(scaled) * scale, spread * scale  # an inf spread becomes null in JSON


def format_summary(summary: Sequence[dict[str, Any]], figures: Sequence[str] | None = None) -> str:
    """A plain-text table: the parameters that vary, counts, success rate, mean +- std of figures."""
    if not summary:
        return "no results"
    params = [k for k in summary[0] if k not in ("episodes", "success", "failure", "error", "collided", "success_rate",
                                                 "reasons", "figures")]
    varying = [k for k in params if len({json.dumps(e.get(k), default=str) for e in summary}) > 1]
    shown = varying or [k for k in params if summary[0].get(k) is not None][:2]
    present = sorted({name for e in summary for name in e["figures"]})
    figures = [f for f in (_full_name(f, present) for f in figures or HEADLINE) if f]
    counts = ["runs", "success", "fail", "error", "collided"]
    header = [_short(k) for k in shown] + counts + [_short(f) for f in figures]
    lines = [header]
    for entry in summary:
        cells = [_cell(entry.get(k)) for k in shown]
        cells += [str(entry["episodes"]), f"{entry['success_rate']:.0%}", str(entry["failure"]), str(entry["error"]),
                  str(entry.get("collided", 0))]
        for name in figures:
            stats = entry["figures"].get(name)
            cells.append(f"{stats['mean']:.3g} +- {stats['std']:.2g}" if stats else "-")
        lines.append(cells)
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    table = "\n".join("  ".join(c.ljust(w) for c, w in zip(line, widths, strict=True)).rstrip() for line in lines)
    return table + _format_reasons(summary, shown)


def _format_reasons(summary: Sequence[dict[str, Any]], shown: Sequence[str]) -> str:
    """Under the table, per combination with failed runs: ``lab, 2: 8 x Drive failed: stalled``."""
    lines = []
    for entry in summary:
        if entry.get("reasons"):
            where = ", ".join(f"{_short(k)}={_cell(entry.get(k))}" for k in shown)
            said = "; ".join(f"{r['count']} x {r['reason']}" for r in entry["reasons"])
            lines.append(f"  {where}: {said}")
    return "\n\nwhy runs did not succeed (commonest first):\n" + "\n".join(lines) if lines else ""


def _full_name(name: str, present: Sequence[str]) -> str | None:
    if name in present:
        return name
    matches = [p for p in present if p.endswith("." + name)]
    return matches[0] if len(matches) == 1 else None


def resolve_column(rows: Sequence[Row], name: str, *, parameter: bool) -> str:
    """A column by its full name, or by a unique ending (``goal_error_m``, ``speed``)."""
    columns = parameter_keys(rows) + ["seed"] if parameter else [*figure_keys(rows), "success"]
    if name in columns:
        return name
    matches = [c for c in columns if c.endswith("." + name)]
    if len(matches) == 1:
        return matches[0]
    what = "parameter" if parameter else "figure"
    known = ", ".join(columns) or "none"
    if matches:
        raise ValueError(f"{what} {name!r} is ambiguous: {', '.join(matches)}")
    raise ValueError(f"no {what} {name!r} in the results (known: {known})")


def plot(rows: Sequence[Row], figure: str, against: str, path: str | Path) -> Path:
    """A PNG of ``figure`` (every episode, and the mean +- std per value) against the parameter
    ``against``, one line per combination of the other parameters. Needs ``bearings[plot]``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure = resolve_column(rows, figure, parameter=False)
    against = resolve_column(rows, against, parameter=True)
    others = [k for k in parameter_keys(rows) if k != against and len({_key(r.get(k)) for r in rows}) > 1]
    xs = sorted({_key(r.get(against)) for r in rows}, key=lambda k: _order(json.loads(k)))
    numeric = all(is_number(json.loads(x)) for x in xs)
    position = {x: (json.loads(x) if numeric else i) for i, x in enumerate(xs)}
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=100)
    lines: dict[str, list[Row]] = {}
    for row in rows:
        lines.setdefault(", ".join(f"{_short(k)}={_cell(row.get(k))}" for k in others), []).append(row)
    for label, members in sorted(lines.items()):
        _plot_line(ax, members, figure, against, position, label or None)
    if not numeric:
        ax.set_xticks(list(position.values()), [_cell(json.loads(x)) for x in xs])
    ax.set_xlabel(_short(against))
    ax.set_ylabel(figure)
    ax.set_title(f"{figure} against {_short(against)} ({len(rows)} episodes)")
    ax.grid(alpha=0.3)
    if any(lines):
        ax.legend(fontsize=8)
    fig.tight_layout()
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(target)
    plt.close(fig)
    return target


def _plot_line(ax: Any, members: list[Row], figure: str, against: str, position: dict[str, Any],
               label: str | None) -> None:
    by_x: dict[Any, list[float]] = {}
    for row in members:
        value = (1.0 if succeeded(row) else 0.0) if figure == "success" else row.get(figure)
        if is_number(value):
            by_x.setdefault(position[_key(row.get(against))], []).append(float(value))  # type: ignore[arg-type]
    if not by_x:
        return
    xs = sorted(by_x)
    means, stds = zip(*(mean_and_spread(by_x[x]) for x in xs), strict=True)
    line = ax.errorbar(xs, means, yerr=stds, marker="o", capsize=3, label=label)
    scatter_x = [x for x in xs for _ in by_x[x]]
    scatter_y = [v for x in xs for v in by_x[x]]
    ax.scatter(scatter_x, scatter_y, s=8, alpha=0.3, color=line[0].get_color())


def _key(value: Any) -> str:
    return json.dumps(value, default=str)


def _order(value: Any) -> tuple[int, Any]:
    if value is None:
        return (0, 0)
    if is_number(value):
        return (1, value)
    return (2, str(value))


def _short(key: str) -> str:
    for prefix in ("inputs.", "ground_truth.", "safety."):
        if key.startswith(prefix):
            return key[len(prefix):]
    return key


def _cell(value: Any) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:g}"
    text = str(value)
    return text if len(text) <= 24 else "..." + text[-21:]
