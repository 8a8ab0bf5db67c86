"""The end-of-run line: the figures that say how a run went, next to its status.

``goto_target`` printed SUCCESS and its path length while its report counted two collisions:
the line under the status now shows, when the report has them,

- always: the collisions and the closest approach to an obstacle (``ground_truth``) and the
  safety layer's stops (``safety``), whatever the mission;
- the figures each capability declares as its headline, next to the figures themselves: a
  node's :class:`~behaviours.telemetry.Figure` with ``headline=True`` (the LT-map's viewframes
  reached, the map file written), and an observer's or a device's ``HEADLINE`` (the simulator's
  goal and path errors).

The run report lists the declared paths under ``headline`` (``section.name``, in order), so
tools that read reports (``bearings plot``, sweeps) show the same figures.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

ALWAYS = ("ground_truth.collisions", "ground_truth.min_clearance_m", "safety.safety_stops", "safety.slowdowns",
          "safety.bumper_hits", "safety.min_range_m", "safety.sources")
"""Shown on every end-of-run line whose report has them: what the robot touched or came close to
(the simulator's ground truth) and what the collision monitor did about it."""

UNITS = (("_m2", "m^2"), ("_m", "m"), ("_s", "s"), ("_deg", "deg"), ("_rad", "rad"), ("_hz", "Hz"))
"""Unit suffixes of report names, and how the line writes the unit."""


def declared_headline(sources: Iterable[object], figures: Iterable[str]) -> list[str]:
    """The report paths the line shows besides :data:`ALWAYS`: each source's ``HEADLINE`` (an
    observer, a device), then the headline figures of the tree's nodes."""
    paths: list[str] = []
    for source in sources:
        paths.extend(getattr(source, "HEADLINE", ()))
    paths.extend(figures)
    return list(dict.fromkeys(paths))


def lookup(report: Mapping[str, Any], path: str) -> Any:
    """The value at ``section.name[.more]`` in a report, or None."""
    value: Any = report
    for part in path.split("."):
        if not isinstance(value, Mapping) or part not in value:
            return None
        value = value[part]
    return value


def summary_line(report: Mapping[str, Any]) -> str:
    """``ground truth: collisions 2, goal error 0.210 m; ltmap: switches 12`` (empty: nothing to show)."""
    groups: dict[str, list[str]] = {}
    for path in dict.fromkeys([*ALWAYS, *report.get("headline", ())]):
        value = lookup(report, path)
        if value is None or isinstance(value, (Mapping, list)):
            continue
        section, _, name = path.partition(".")
        groups.setdefault(section, []).append(figure_text(name, value))
    return "; ".join(f"{section.replace('_', ' ')}: {', '.join(shown)}" for section, shown in groups.items())


def figure_text(name: str, value: Any) -> str:
    """``goal_error_m``, 0.2104 -> ``goal error 0.210 m``; a dotted name reads as words."""
    unit = ""
    for suffix, written in UNITS:
        if name.endswith(suffix):
            name, unit = name[: -len(suffix)], " " + written
            break
    label = name.replace(".", " ").replace("_", " ")
    if isinstance(value, bool):
        return f"{label} {'yes' if value else 'no'}"
    if isinstance(value, float):
        return f"{label} {value:.3f}{unit}"
    return f"{label} {value}{unit}"
