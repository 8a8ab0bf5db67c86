"""The LT-map on the blackboard: load it from a file, prune it to a memory budget.

The map of a taught route (:class:`maps.ltmap.tree.LandmarkTree`, docs/design.md method 1) travels
between nodes on ``/map/ltmap``: ``LearnRoute`` (:mod:`behaviours.teach`) or :class:`LoadMap`
write it, :class:`PruneMap` shrinks it, the route-following nodes (:mod:`behaviours.route`,
:mod:`behaviours.search`) read it. The file path is a literal port, so missions pass it as an
input (``path: "${map}"``) and ``--set map=...`` picks another file.

Both nodes add to the report's ``ltmap`` section (their ``figures``): the map's shape and
size, and for a pruned map the memory it kept and where each of its viewframes came from
(``viewframe_source``: the index in the loaded map), so an evaluation can compare a viewframe
reached while following a pruned map with the place it was taught.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.ports import READS, WRITES, InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.telemetry import Figure, section
from maps.ltmap.file import load_ltmap, save_ltmap
from maps.ltmap.prune import DEFAULT_MIN_LANDMARKS
from maps.ltmap.tree import LandmarkTree, MapSummary
from maps.store import InputError, check_not_redirected

LTMAP_KEY = "/map/ltmap"
LTMAP_IN = InputPort("ltmap", LandmarkTree, Ref(LTMAP_KEY), doc="the LT-map of the taught route")
LTMAP_OUT = OutputPort("ltmap", LandmarkTree, LTMAP_KEY, doc="the LT-map of the taught route")


def summary_section(summary: MapSummary) -> dict[str, Any]:
    """The map's figures as the report's ``ltmap`` section holds them."""
    return {
        "landmark_kind": summary.kind,
        "viewframes": summary.viewframes,
        "landmarks": summary.landmarks,
        "nodes": summary.nodes,
        "height": summary.height,
        "bytes": summary.memory_bytes,
        "landmarks_per_level": list(summary.landmarks_per_level),
        "threshold": summary.threshold,
    }


def save_map(path: str, tree: LandmarkTree) -> None:
    """Save atomically (a failed save keeps the previous file): the one way the nodes write maps.
    Never through a symbolic link put in the way since the mission was loaded (its path was checked
    to lie in the output folder then)."""
    check_not_redirected(path)
    save_ltmap(path, tree)


@register
class LoadMap(BearingsBehaviour):
    """Load an LT-map file onto the blackboard; FAILURE (with the file's problem) when it cannot.

    Loads once per run of the node (a mission that loads the same map twice reads it twice);
    the file is checked whole (version, checksum, tree consistency) before anything follows it.
    """

    PATH = InputPort("path", str, doc="the LT-map file (a mission input: --set map=route.ltmap)", literal_only=True,
                     file=READS)
    PORTS = (PATH, LTMAP_OUT)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.summary: MapSummary | None = None

    def update(self) -> Status:
        path = self.get_input(self.PATH)
        try:
            tree = load_ltmap(path)
        except (InputError, OSError) as exc:
            self.feedback_message = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            return Status.FAILURE
        if tree.viewframe_count == 0:
            self.feedback_message = f"{path}: the map has no viewframes"
            return Status.FAILURE
        self.summary = tree.summary()
        self.set_output(LTMAP_OUT, tree)
        self.feedback_message = f"{tree.viewframe_count} viewframes, {tree.memory_bytes()} bytes"
        return Status.SUCCESS

    def figures(self) -> Iterator[Figure]:
        if self.summary is not None:
            yield from section("ltmap", {"map_file": os.path.abspath(self.get_input(self.PATH)),
                                         **summary_section(self.summary)})


@register
class PruneMap(BearingsBehaviour):
    """Cut the lowest levels of the LT-map until it fits a memory budget (the paper's Table I).

    The budget is ``budget`` bytes, or ``fraction`` of the map's size when it arrives (the
    smaller of the two when both are given; 0 and 1 mean no limit). FAILURE, with the map left
    as it was, when even a single level exceeds the budget. The pruned map replaces the input
    on the blackboard (``ltmap`` output, the same key by default); with ``path`` it is also
    saved atomically.
    """

    BUDGET = InputPort("budget", int, 0, unit="B", minimum=0, doc="memory budget in bytes; 0: none")
    FRACTION = InputPort("fraction", float, 1.0, minimum=0.0, maximum=1.0,
                         doc="memory budget as a fraction of the map's size; 1: none")
    MIN_LANDMARKS = InputPort("min_landmarks", int, DEFAULT_MIN_LANDMARKS, minimum=0,
                              doc="viewframes left with fewer landmarks are deleted (the paper: 50, enough for homing)")
    PATH = InputPort("path", str, "", literal_only=True, file=WRITES,
                     doc="save the pruned map here too (empty: do not save)")
    SOURCE = InputPort("source", LandmarkTree, Ref(LTMAP_KEY), doc="the LT-map to prune")
    PORTS = (BUDGET, FRACTION, MIN_LANDMARKS, PATH, SOURCE, LTMAP_OUT)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.section: dict[str, Any] = {}

    def budget_bytes(self, size: int) -> int | None:
        """The budget for a map of ``size`` bytes, or None for no limit."""
        limits = []
        budget, fraction = self.get_input(self.BUDGET), self.get_input(self.FRACTION)
        if budget > 0:
            limits.append(budget)
        if fraction < 1.0:
            limits.append(math.floor(fraction * size))
        return min(limits) if limits else None

    def update(self) -> Status:
        tree = self.get_input(self.SOURCE, None)
        if tree is None:
            self.feedback_message = "no LT-map to prune"
            return Status.FAILURE
        before = tree.memory_bytes()
        budget = self.budget_bytes(before)
        pruned = tree.copy()  # the input stays as it was for whoever else holds it
        source = np.arange(tree.viewframe_count)
        if budget is not None:
            report = pruned.prune_to(budget, self.get_input(self.MIN_LANDMARKS))
            if not report.fits:
                self.feedback_message = f"{report.smallest_bytes} bytes at the least, over the {budget} byte budget"
                return Status.FAILURE
            source = np.array([int(np.flatnonzero(report.viewframe_index == k)[0])
                               for k in range(pruned.viewframe_count)], dtype=np.int64)
        path = self.get_input(self.PATH)
        if path:
            save_map(path, pruned)
        self.set_output(LTMAP_OUT, pruned)
        after = pruned.memory_bytes()
        self.section = {**summary_section(pruned.summary()), "bytes_before_pruning": before,
                        "memory_fraction": round(after / before, 4) if before else 1.0,
                        "viewframe_source": source.tolist()}
        self.feedback_message = f"{before} -> {after} bytes, {pruned.viewframe_count} viewframes"
        if budget is not None and before:
            # whole tree levels are cut: the map lands on the nearest cut under the budget, often well under it
            self.section["memory_fraction_asked"] = round(budget / before, 4)
            self.feedback_message += (f" ({after / before:.1%} of the map for {budget / before:.1%} asked: pruning "
                                      "cuts whole tree levels, this is the nearest cut under the budget)")
        return Status.SUCCESS

    def figures(self) -> Iterator[Figure]:
        asked = "memory_fraction_asked" in self.section  # a budget was given: say what it gave
        shown = ("memory_fraction_asked", "memory_fraction") if asked else ()
        yield from section("ltmap", self.section, headline=shown)
