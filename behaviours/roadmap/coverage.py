"""Coverage scoring: the next position to search from (docs/design.md, method 2, "Coverage").

The configuration space (x, y at 10 cm, heading at 5 degrees) inside the room's free space is
covered by the images taken at search positions; the next position is the one whose 12 images
would newly cover the most configurations without fragmenting what is left
(:func:`maps.coverage.choose_next`). This node keeps the coverage grid: it builds it from the room
estimate the first time, marks what each scan covered (``scan``, written by ``ScanForTargets``:
the position and the headings of the images actually taken, so a scan stopped early by a match
leaves the rest of that position to cover), then chooses.

Choices where the paper is vague:

- Candidates are the valid positions in the robot's own free region
  (:func:`maps.coverage.reachable_positions`); when the robot stands where the grid says it
  cannot (just after homing close to furniture), every valid position is a candidate.
- The search ends (FAILURE, "nothing left to cover") when the best position would newly cover
  fewer than ``min_new`` configurations (default 100: under a tenth of what a fresh position
  covers in the lab).
- The goal's heading is the direction of travel to it, so getting there needs no final turn.
- A goal given out and not followed by a scan (this node ticks again with no new ``scan``:
  the travel there failed) is taken as unreachable: positions within 0.3 m of it are no longer
  candidates. Otherwise the same best position would be chosen, and failed, round after round.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.footprint import FOOTPRINT
from behaviours.motion import ODOMETRY
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.roadmap.display import Drawn, coverage_drawings, roadmap_figures
from behaviours.roadmap.room import ROOM_IN
from behaviours.roadmap.routine import ROBOT_RADIUS, robot_disc
from behaviours.roadmap.values import ScanRecord
from behaviours.telemetry import Drawing, Figure
from maps.coverage import FRAGMENT_COST as DEFAULT_FRAGMENT_COST
from maps.coverage import CoverageGrid, choose_next, coverage_grid, reachable_positions
from perception.geometry import Pose2D

UNREACHABLE_RADIUS = 0.3  # m around a goal the robot did not reach: not a candidate again


@register
class CoverageScoring(BearingsBehaviour):
    """Choose the next search position: the most newly covered configurations, least fragmentation.

    Marks the last scan's images as covered, then writes the chosen position (``goal``,
    reference frame) and the coverage grid. FAILURE when nothing worth a visit is left.
    """

    SCAN = InputPort("scan", ScanRecord, Ref("/map/scan"), doc="the images of the last scan (none yet: nothing)")
    MIN_NEW = InputPort("min_new", int, 100, minimum=1, literal_only=True,
                        doc="fewest newly covered configurations that make a position worth a visit")
    FRAGMENT_COST = InputPort("fragment_cost", float, DEFAULT_FRAGMENT_COST, minimum=0.0, literal_only=True,
                              doc="configurations one more uncovered fragment is worth")
    COVERAGE = OutputPort("coverage", CoverageGrid, "/map/coverage", doc="the coverage grid")
    GOAL = OutputPort("goal", Pose2D, "/map/coverage_goal", doc="the next search position (reference frame)")
    PORTS = (ROOM_IN, SCAN, ROBOT_RADIUS, FOOTPRINT, MIN_NEW, FRAGMENT_COST, ODOMETRY, COVERAGE, GOAL)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.grid: CoverageGrid | None = None
        self.applied: set[int] = set()
        self.pending: Pose2D | None = None  # the last goal given, until a scan from it arrives
        self.unreachable: list[Pose2D] = []
        self.choices = 0
        self.drawn = Drawn()

    def update(self) -> Status:
        room = self.get_input(ROOM_IN, None)
        odometry = self.get_input(ODOMETRY, None)
        if room is None or odometry is None:
            self.feedback_message = "no room estimate" if room is None else "waiting for odometry"
            return Status.FAILURE if room is None else Status.RUNNING
        radius = robot_disc(self)
        grid = self.grid or coverage_grid(room, room.free, robot_radius=radius)
        scan = self.get_input(self.SCAN, None)
        if scan is not None and scan.seq not in self.applied:
            self.applied.add(scan.seq)
            grid = grid.cover(scan.x, scan.y, scan.headings)  # the headings actually imaged
            self.pending = None
        if self.pending is not None:  # asked for again with no scan since: the robot did not get there
            self.unreachable.append(self.pending)
        self.grid = grid
        self.set_output(self.COVERAGE, grid)
        here = room.to_reference(odometry)
        candidates = reachable_positions(grid, room.free, radius, here.x, here.y)
        candidates = self._without_unreachable(grid, candidates if candidates.any() else grid.valid)
        choice = choose_next(grid, candidates=candidates,
                             min_new=self.get_input(self.MIN_NEW), fragment_cost=self.get_input(self.FRAGMENT_COST))
        if choice is None:
            self.feedback_message = f"nothing left to cover ({100 * grid.fraction_covered:.0f} % covered)"
            return Status.FAILURE
        self.choices += 1
        self.pending = Pose2D(choice.x, choice.y, math.atan2(choice.y - here.y, choice.x - here.x))
        self.set_output(self.GOAL, self.pending)
        self.feedback_message = (f"position {self.choices} at ({choice.x:.1f}, {choice.y:.1f}): {choice.new} new, "
                                 f"{100 * grid.fraction_covered:.0f} % covered")
        return Status.SUCCESS

    def _without_unreachable(self, grid: CoverageGrid, candidates: np.ndarray) -> np.ndarray:
        """The candidates farther than ``UNREACHABLE_RADIUS`` from every goal the robot did not reach."""
        if not self.unreachable:
            return candidates
        x, y = grid.position(*np.indices(grid.valid.shape))
        keep = candidates.copy()
        for goal in self.unreachable:
            keep &= np.hypot(x - goal.x, y - goal.y) > UNREACHABLE_RADIUS
        return keep

    def figures(self) -> Iterator[Figure]:
        if self.grid is not None:
            yield from roadmap_figures({"positions_chosen": self.choices, "scans": len(self.applied),
                                        "unreachable": len(self.unreachable),
                                        "covered_fraction": round(self.grid.fraction_covered, 4)}, "search")

    def drawings(self) -> Iterator[Drawing]:
        if self.grid is not None and self.drawn.changed("coverage", self.grid):
            yield from coverage_drawings(self.grid)
