"""Navigating the roadmap to a target from an unknown pose (docs/design.md, method 2, "Navigation").

Paper: rotate and try to match any graph image; when none matches, move randomly and retry;
then take the shortest path (edge cost sigma_x + sigma_y), homing at each node to remove drift.

1. **Localise**: scan (12 images turning on the spot, :func:`behaviours.roadmap.scan.scan`) for
   any target of the roadmap; home to the one matched. Nothing matched (or homing lost it): a
   random move, then scan again, at most ``max_random_moves`` times.
2. **Path**: :meth:`maps.roadmap.Roadmap.shortest_path` from the target homed at to the goal.
3. **Edges**: each edge is replayed as stored, ``Rotate(angle1)``, ``Drive(distance)``,
   ``Rotate(angle2)`` (odometry units: the robot's odometry errors replay the way they were
   learned), then homing to the edge's target removes the drift. A drive held short (the
   collision monitor stops the robot before furniture beside the target, a stall) still makes
   the second turn and homes from where it stopped, as the learning did (``homed_short``). A
   failed edge (the target not found at its end) sends the robot back to step 1 and a new path.

Choices where the paper is vague:

- **Random move**: a turn drawn uniformly in [-180, 180) degrees, then a straight drive of a length
  drawn in ``random_distance`` (0.4-1.2 m); a stall (the move ran into something) backs off
  0.2 m and counts as the move. Draws come from ``seed``, so a run is repeatable.
- **Start at the goal's image**: when the first target matched is the goal, homing to it is the
  whole navigation.
- **Success** means homed at the goal: within homing's ``done_distance`` of where the goal image
  was taken, facing as it does.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import replace
from typing import Any

import numpy as np

from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.roadmap.display import Drawn, roadmap_drawings, roadmap_figures
from behaviours.roadmap.homing import HOMING_PORTS, HomingSettings, home, home_after
from behaviours.roadmap.routine import ROUTINE_PORTS, Failed, RoutineBehaviour, Step
from behaviours.roadmap.scan import scan
from behaviours.roadmap.values import NavigationResult, TargetImages
from behaviours.telemetry import Drawing, Figure
from maps.located import suggest
from maps.roadmap import EdgeMotion, Roadmap


@register
class NavigateToTarget(RoutineBehaviour):
    """From an unknown pose, reach a target of the roadmap: match a target (random moves until one
    matches), then follow the shortest path, homing at every node. Writes how it went (``navigation``)."""

    TARGET = InputPort("target", str, doc="name of the target to reach")
    ROADMAP = InputPort("roadmap", Roadmap, Ref("/map/roadmap"), doc="the learned roadmap")
    TARGETS = InputPort("targets", TargetImages, Ref("/map/target_images"), doc="the roadmap's target images")
    IMAGES = InputPort("images", int, 12, minimum=1, maximum=72, literal_only=True,
                       doc="images per localisation scan, evenly spaced over a full turn")
    MAX_RANDOM_MOVES = InputPort("max_random_moves", int, 12, minimum=0, maximum=1000, literal_only=True,
                                 doc="random moves before giving up when no target matches")
    RANDOM_DISTANCE = InputPort("random_distance", list[float], [0.4, 1.2], unit="m", literal_only=True,
                                doc="shortest and longest random move")
    SEED = InputPort("seed", int, 0, minimum=0, literal_only=True, doc="seed of the random moves")
    NAVIGATION = OutputPort("navigation", NavigationResult, "/map/navigation", doc="how the navigation went")
    PORTS = (TARGET, ROADMAP, TARGETS, IMAGES, MAX_RANDOM_MOVES, RANDOM_DISTANCE, SEED, *HOMING_PORTS,
             *ROUTINE_PORTS, NAVIGATION)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        low_high = self.get_input(self.RANDOM_DISTANCE)
        if len(low_high) != 2 or not 0 <= low_high[0] <= low_high[1]:
            raise ValueError(f"NavigateToTarget.random_distance takes [shortest, longest], got {low_high}")
        self.random_distance: tuple[float, float] = (low_high[0], low_high[1])
        self.result: NavigationResult | None = None
        self.rng = np.random.default_rng(0)  # re-seeded from the seed port when the routine starts
        self.drawn = Drawn()

    @classmethod
    def check_inputs(cls, inputs: dict[str, Any]) -> list[str]:
        """At load time: the target is one the roadmap has, when the roadmap file exists already."""
        goal, roadmap = inputs.get(cls.TARGET.name), inputs.get(cls.ROADMAP.name)
        if not isinstance(goal, str) or not isinstance(roadmap, Roadmap) or goal in roadmap.names:
            return []
        return [f"no target named {goal!r} in the roadmap{suggest(goal, roadmap.names)} "
                f"(it has: {', '.join(roadmap.names) or 'none'})"]

    def routine(self) -> Step[None]:
        goal = self.get_input(self.TARGET)
        roadmap = self.get_input(self.ROADMAP, None)
        targets = self.get_input(self.TARGETS, None)
        if roadmap is None or targets is None:
            raise Failed("no roadmap" if roadmap is None else "no target images")
        if not goal:
            raise Failed("no target given (goto_target: --set target=NAME)")
        if goal not in roadmap.names or goal not in targets.names:
            raise Failed(f"no target named {goal!r} in the roadmap (it has: {', '.join(roadmap.names)})")
        self.result = NavigationResult(goal, False)
        self.rng = np.random.default_rng(self.get_input(self.SEED))
        try:
            yield from self._navigate(goal, roadmap, targets)
        except Failed as exc:
            self._note(reason=str(exc))
            raise
        self._note(reached=True)
        self.feedback_message = f"at {goal} via {' -> '.join(self.result.visited)}"

    def _navigate(self, goal: str, roadmap: Roadmap, targets: TargetImages) -> Step[None]:
        at = yield from self._localise(targets)
        while at != goal:
            path = roadmap.shortest_path(at, goal)
            if path is None:
                raise Failed(f"no path from {at} to {goal} in the roadmap")
            for name, motion in zip(path.names[1:], path.motions, strict=True):
                try:
                    yield from self._edge(motion, name, targets)
                except Failed:
                    assert self.result is not None
                    self._note(rescans=self.result.rescans + 1)
                    at = yield from self._localise(targets)
                    break
                at = name

    def _localise(self, targets: TargetImages) -> Step[str]:
        """Scan, move randomly when nothing matches, home to the first target matched: its name."""
        settings = HomingSettings.of(self)
        limit = self.get_input(self.MAX_RANDOM_MOVES)
        for attempt in range(limit + 1):
            sighting, _ = yield from scan(self, targets.views, self.get_input(self.IMAGES), settings.min_inliers)
            if sighting is not None:
                try:
                    yield from home(self, targets.get(sighting.target), settings)
                except Failed:
                    sighting = None
                else:
                    self._visit(sighting.target, first=True)
                    return sighting.target
            if attempt < limit:
                yield from self._random_move()
        raise Failed(f"no target matched after {limit} random moves")

    def _random_move(self) -> Step[None]:
        low, high = self.random_distance
        turn, distance = self.rng.uniform(-math.pi, math.pi), self.rng.uniform(low, high)
        assert self.result is not None
        self._note(random_moves=self.result.random_moves + 1)
        yield from self.rotate(float(turn), "random move: turning")
        try:
            yield from self.drive(float(distance), "random move: driving")
        except Failed:
            yield from self.back_off()

    def _edge(self, motion: EdgeMotion, name: str, targets: TargetImages) -> Step[None]:
        """Replay an edge (rotate, drive, rotate), then home to its target; a drive held short still
        turns and homes from where it stopped (module docstring)."""
        yield from self.rotate(motion.angle1, f"edge to {name}: turning")
        held = yield from self.attempted(self.drive(motion.distance, f"edge to {name}: driving"))
        yield from self.rotate(motion.angle2, f"edge to {name}: turning")
        yield from home_after(self, targets.get(name), HomingSettings.of(self), held)
        if held:
            assert self.result is not None
            self._note(homed_short=self.result.homed_short + 1)
        self._visit(name)

    def _visit(self, name: str, first: bool = False) -> None:
        assert self.result is not None
        self._note(visited=(*self.result.visited, name), **({"localised_at": name} if first and
                                                               not self.result.localised_at else {}))

    def _note(self, **changes: Any) -> None:
        assert self.result is not None
        self.result = replace(self.result, **changes)
        self.set_output(self.NAVIGATION, self.result)

    def figures(self) -> Iterator[Figure]:
        r = self.result
        if r is not None:
            yield from roadmap_figures({"goal": r.goal, "reached": r.reached, "localised_at": r.localised_at,
                                        "visited": list(r.visited), "random_moves": r.random_moves,
                                        "rescans": r.rescans, "homed_short": r.homed_short,
                                        "reason": r.reason}, "navigation")

    def drawings(self) -> Iterator[Drawing]:
        roadmap = self.get_input(self.ROADMAP, None)
        if roadmap is not None and self.drawn.changed("roadmap", roadmap):
            yield from roadmap_drawings(roadmap)
