"""Building the roadmap's graph by driving between targets (docs/design.md, method 2, "Graph").

Paper: an edge a -> b exists when the robot went from a to b and back; the two estimates are
fused by covariance; an edge stores rotate(angle1), drive(dist), rotate(angle2). Every pair of
targets is tried; a failed edge returns the robot to the reference and is dropped; the graph
must end connected.

One pair (a, b):

1. get to a if the robot is not there: plan in the room estimate (:func:`travel`), home to a;
2. a -> b: drive straight to where the map puts b relative to a (``DriveTo`` then a turn: the
   rotate-drive-rotate of an edge), home to b. The odometry from the homed pose at a to the homed
   pose at b is the forward estimate;
3. b -> a: drive straight back to the odometry pose the robot left a from (the line just
   driven, retraced: no map error this time), home to a: the backward estimate;
4. :meth:`maps.roadmap.Roadmap.with_round_trip` fuses them (it refuses estimates that disagree
   beyond their covariances: the edge is dropped).

Choices where the paper is vague:

- **Which pairs**: first those whose straight segment stays on floor where the robot may stand
  (the room's free grid; the 0.3 m at each end, where a target may sit close to furniture, is
  not checked): edges are straight drives. The free polygon is star-shaped around the
  dodecagon, so the floor hidden behind a pillar is not known free although it often is: when
  the graph is not connected after those, the other pairs (``not_straight`` in the report) that
  would join two components are tried too, shortest first, one at a time until it is connected.
  Such a drive that runs into something stalls, fails and is dropped like any failed edge.
- **Order**: greedy, the untried pair with an end nearest to where the robot is (the target it
  is homed at first), starting from that end, so a chain of pairs needs no travel between them.
- **Covariance of one estimate** (over angle1, distance, angle2; independent): odometry errors
  grow with what was driven, homing adds a fixed error at each end:
  ``sigma_angle^2 = (0.01 |angle| + 0.5 deg)^2 + (0.6 deg)^2 distance[m]`` and
  ``sigma_distance = 0.02 distance + 0.02 m``. Measured in the simulator: calibrated turns
  (``CalibrateTurns``) leave about 0.3 deg per half turn; straight driving drifts 1 deg (one
  sigma) in heading over 3 m; homing ends within about 1 cm, its heading estimate within about
  0.2 deg. The edges are measured and replayed on the same (calibrated) odometry, so what is
  left of a robot's systematic error cancels between learning and navigation.
- **Target poses** (:mod:`maps.pose_graph`): each target's pose was measured once, by the trip
  from it back to the reference when it was found (covariance by the same model); after every
  new edge the targets' poses are refitted to those measurements and all the edges (weighted
  least squares), so a far target joined to a near one is placed by both routes. The edges
  themselves are kept as measured.
- **Drift**: every homing at a target anchors the room there (the reference pose in odometry
  becomes the homed pose composed with the inverse of the target's pose in the map), so travel
  between pairs plans in a map that is off by the target's map error (a few centimetres), not
  by the odometry drift of the whole graph. The anchored room is written (``room_out``).
- **A failed pair** (homing lost, a stall, an inconsistent round trip): dropped with its reason;
  after a failure of motion the robot returns to the reference and homes to the reference image
  (the room's reference pose is re-anchored there for the rest of the graph). A pair whose first
  drive ran into something is tried once more from the other end: the drive's direction comes
  from the start target's estimated heading, so the other end's (different) error may pass
  where the first did not.
- **Held short**: a drive that stops before its end (the collision monitor holds the robot
  before furniture beside the target, a stall) still turns to the far target's heading and homes
  to it from where it stopped: the edge is measured from homed pose to homed pose either way, and
  navigation replays it the same way (``homed_short`` in the report). Only when that homing fails
  is the pair dropped. Measured in the lab: a target 0.35 m from a desk (``corner``) was reached
  0.10 m short of its odometry goal, held by the monitor, and the pair dropped.
- **Not connected at the end**: the roadmap is still written (``roadmap_out`` and the file) and
  the node fails, naming the components.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from itertools import combinations
from typing import Any

import numpy as np

from behaviours.ports import WRITES, InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.roadmap.display import Drawn, roadmap_drawings, roadmap_figures, roadmap_section
from behaviours.roadmap.homing import REQUIRED_ROOM, HomingSettings, home, home_after
from behaviours.roadmap.paths import PLAN_PORTS, reanchored, travel
from behaviours.roadmap.room import ROOM_IN
from behaviours.roadmap.routine import ROUTINE_PORTS, Failed, RoutineBehaviour, Step, robot_disc
from behaviours.roadmap.targets import TARGETS_IN, relative_images
from behaviours.roadmap.travel import REFERENCE_IN, return_to_reference
from behaviours.roadmap.values import TargetImages, TargetView
from behaviours.telemetry import Drawing, Figure
from maps.planning import segment_is_free
from maps.pose_graph import refine_targets
from maps.roadmap import EdgeMotion, InconsistentEstimates, Roadmap
from maps.room import RoomEstimate
from maps.store import check_not_redirected
from perception.geometry import Pose2D, wrap_angle

TURN_NOISE = 0.01  # sigma per radian turned (calibrated turns)
DRIFT = math.radians(0.6)  # heading sigma per square-root metre driven
DRIVE_NOISE = 0.02  # sigma per metre driven
HOMING_HEADING = math.radians(0.5)
HOMING_POSITION = 0.02  # m
END_CLEARANCE = 0.3  # m at each end of an edge not checked against the free grid


def measured_motion(start: Pose2D, end: Pose2D) -> EdgeMotion:
    """The edge motion from one homed odometry pose to another, with its covariance (module docstring)."""
    rel = end.relative_to(start)
    distance = math.hypot(rel.x, rel.y)
    angle1 = math.atan2(rel.y, rel.x) if distance > 1e-9 else 0.0
    angle2 = wrap_angle(rel.theta - angle1)
    variances = ((TURN_NOISE * abs(angle1) + HOMING_HEADING) ** 2 + DRIFT ** 2 * distance,
                 (DRIVE_NOISE * distance + HOMING_POSITION) ** 2,
                 (TURN_NOISE * abs(angle2) + HOMING_HEADING) ** 2 + DRIFT ** 2 * distance)
    return EdgeMotion(angle1, distance, angle2, np.diag(variances))


def straight_is_free(room: RoomEstimate, a: Pose2D, b: Pose2D, radius: float) -> bool:
    """Whether the robot may drive straight from a to b (reference frame; ends not checked)."""
    start, end = np.array([a.x, a.y]), np.array([b.x, b.y])
    length = float(np.hypot(*(end - start)))
    if length <= 2 * END_CLEARANCE:
        return True
    unit = (end - start) / length
    return segment_is_free(room.free, start + END_CLEARANCE * unit, end - END_CLEARANCE * unit, radius)


@dataclass
class GraphLog:
    """What happened to the pairs (for the report)."""

    tried: list[tuple[str, str]] = field(default_factory=list)
    dropped: list[dict[str, str]] = field(default_factory=list)
    not_straight: list[tuple[str, str]] = field(default_factory=list)
    homed_short: list[dict[str, str]] = field(default_factory=list)  # drives held short, then homed
    saved: str = ""


@register
class BuildGraph(RoutineBehaviour):
    """Drive every pair of targets there and back, homing at each end; fuse the two estimates into an edge.

    A failed pair returns the robot to the reference and is dropped. Writes the roadmap with its
    edges (``roadmap_out``) and saves it to ``file``; FAILURE when the graph is not connected.
    """

    ROADMAP = InputPort("roadmap", Roadmap, Ref("/map/roadmap"), doc="the targets found (reference frame)")
    FILE = InputPort("file", str, "", literal_only=True, file=WRITES,
                        doc="where to save the roadmap ('' : do not save)")
    ROADMAP_OUT = OutputPort("roadmap_out", Roadmap, "/map/roadmap", doc="the roadmap with its edges")
    ROOM_OUT = OutputPort("room_out", RoomEstimate, "/map/room", doc="the room, anchored where the robot last homed")
    PORTS = (ROADMAP, TARGETS_IN, REFERENCE_IN, FILE, *REQUIRED_ROOM, *PLAN_PORTS, *ROUTINE_PORTS,
             ROADMAP_OUT, ROOM_OUT)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.drawn = Drawn()
        self.log = GraphLog()
        self.graph: Roadmap | None = None
        self.room: RoomEstimate | None = None
        self.at: tuple[str, Pose2D] | None = None  # the target the robot is homed at, and its odometry pose
        self.priors: dict[str, EdgeMotion] = {}  # each target's own measurement from the reference

    def routine(self) -> Step[None]:
        roadmap = self.get_input(self.ROADMAP, None)
        targets = self.get_input(TARGETS_IN, None)
        self.room = self.get_input(ROOM_IN, None)
        if roadmap is None or targets is None or self.room is None:
            raise Failed("no roadmap" if roadmap is None else "no target images" if targets is None
                         else "no room estimate")
        self.graph, self.log, self.at = roadmap, GraphLog(), None
        self.priors = {t.name: measured_motion(Pose2D(), t.pose) for t in roadmap.targets}
        pairs, unknown = self._pairs(roadmap)
        while pairs:
            a, b = self._next(pairs)
            pairs.remove((a, b) if (a, b) in pairs else (b, a))
            yield from self._try(a, b, targets)
        while (joining := self._joining(unknown)) is not None:  # still apart: try what the map cannot vouch for
            unknown.remove(joining)
            yield from self._try(*joining, targets)
        self._finish()

    def _try(self, a: str, b: str, targets: TargetImages, *, again: bool = True) -> Step[None]:
        """Measure one pair; when the drive a -> b ran into something, once more from b's side."""
        self.log.tried.append((a, b))
        blocked = yield from self._pair(a, b, targets)
        assert self.graph is not None
        self.set_output(self.ROADMAP_OUT, self.graph)
        if blocked and again:
            yield from self._try(b, a, targets, again=False)

    def _pairs(self, roadmap: Roadmap) -> tuple[list[tuple[str, str]], list[tuple[str, str]]]:
        """Pairs not measured yet: those whose straight segment the room estimate knows as free, the others."""
        assert self.room is not None
        radius = robot_disc(self)
        free, unknown = [], []
        for a, b in combinations(sorted(roadmap.names), 2):
            if roadmap.motion(a, b) is not None:
                continue  # measured already
            if straight_is_free(self.room, roadmap.target(a).pose, roadmap.target(b).pose, radius):
                free.append((a, b))
            else:
                unknown.append((a, b))
        self.log.not_straight = list(unknown)
        return free, unknown

    def _joining(self, unknown: list[tuple[str, str]]) -> tuple[str, str] | None:
        """The shortest untried pair that would join two components of the graph, or None."""
        assert self.graph is not None
        component = {name: k for k, part in enumerate(self.graph.components()) for name in part}
        joining = [(a, b) for a, b in unknown if component[a] != component[b]]
        if not joining:
            return None
        graph = self.graph
        return min(joining, key=lambda p: graph.target(p[0]).pose.distance_to(graph.target(p[1]).pose))

    def _next(self, pairs: list[tuple[str, str]]) -> tuple[str, str]:
        """The untried pair to do next, oriented from its end nearest to the robot (module docstring)."""
        assert self.graph is not None
        here = self.graph.target(self.at[0]).pose if self.at else Pose2D()
        best: tuple[float, tuple[str, str]] | None = None
        for a, b in pairs:
            for first, second in ((a, b), (b, a)):
                gap = 0.0 if self.at and self.at[0] == first else here.distance_to(self.graph.target(first).pose)
                if best is None or gap < best[0]:
                    best = (gap, (first, second))
        assert best is not None
        return best[1]

    def _pair(self, a: str, b: str, targets: TargetImages) -> Step[bool]:
        """Measure a -> b and back; True when the first drive a -> b stalled (worth trying from b)."""
        settings = HomingSettings.of(self)
        assert self.graph is not None
        graph, leg = self.graph, "reaching"
        try:
            start = yield from self._reach(a, targets.get(a), settings)
            leg = "out"
            goal = start.compose(graph.target(b).pose.relative_to(graph.target(a).pose))
            there = yield from self._edge(goal, a, b, targets.get(b), settings)
            leg = "back"
            back = yield from self._edge(start, b, a, targets.get(a), settings)  # retrace the line just driven
        except Failed as exc:
            self.log.dropped.append({"from": a, "to": b, "reason": str(exc)})
            self.at = None
            yield from self._to_reference(settings)
            return leg == "out" and "stalled" in str(exc)
        try:
            self.graph = self.graph.with_round_trip(a, b, measured_motion(start, there), measured_motion(there, back))
        except InconsistentEstimates as exc:
            self.log.dropped.append({"from": a, "to": b, "reason": str(exc)})
            return False
        self.graph = refine_targets(self.graph, self.priors)
        return False

    def _reach(self, name: str, view: TargetView, settings: HomingSettings) -> Step[Pose2D]:
        """The homed odometry pose at target ``name``, travelling there first unless the robot is at it."""
        if self.at is not None and self.at[0] == name:
            return self.at[1]
        assert self.room is not None and self.graph is not None
        yield from travel(self, self.room, self.graph.target(name).pose, turn=True)
        result = yield from home(self, view, settings)
        self._homed(name, result.pose)
        return result.pose

    def _edge(self, goal: Pose2D, a: str, b: str, view: TargetView, settings: HomingSettings) -> Step[Pose2D]:
        """Drive straight from the homed pose at a to ``goal`` (odometry), home to b: the homed pose at b.
        A drive held short (module docstring, "Held short") turns to b's heading and homes from there."""
        what = f"edge {a} -> {b}"
        held = yield from self.attempted(self.drive_to(goal.x, goal.y, what))
        yield from self.turn_to(goal.theta, what)
        result = yield from home_after(self, view, settings, held)
        if held:
            self.log.homed_short.append({"from": a, "to": b, "reason": held})
        self._homed(b, result.pose)
        return result.pose

    def _homed(self, name: str, pose: Pose2D) -> None:
        """The robot is homed at target ``name`` (odometry ``pose``): anchor the room there (module docstring)."""
        assert self.graph is not None and self.room is not None
        self.at = (name, pose)
        self._anchor(pose.compose(self.graph.target(name).pose.inverse()))

    def _anchor(self, reference_pose: Pose2D) -> None:
        assert self.room is not None
        self.room = reanchored(self.room, reference_pose)
        self.set_output(self.ROOM_OUT, self.room)

    def _to_reference(self, settings: HomingSettings) -> Step[None]:
        """After a failed pair: back to the reference (a travel that runs into something, once more)."""
        assert self.room is not None
        reference = self.get_input(REFERENCE_IN, None)
        if reference is None:
            raise Failed("an edge failed and there is no reference image to return to")
        result = yield from return_to_reference(self, self.room, reference, settings, retries=1)
        self._anchor(result.pose)

    def _finish(self) -> None:
        assert self.graph is not None
        self.set_output(self.ROADMAP_OUT, self.graph)
        path = self.get_input(self.FILE)
        if path:
            try:
                check_not_redirected(path)  # checked at load to lie in the output folder: no link since
                relative_images(self.graph, path).save(path)
            except (OSError, ValueError) as exc:
                raise Failed(f"cannot save the roadmap to {path}: {exc}") from None
            self.log.saved = str(path)
        if not self.graph.is_connected():
            parts = " | ".join(", ".join(sorted(c)) for c in self.graph.components())
            raise Failed(f"the graph is not connected: {parts}")
        self.feedback_message = f"{len(self.graph.edges)} edges, connected"

    def figures(self) -> Iterator[Figure]:
        if self.graph is None:
            return
        yield from roadmap_figures(roadmap_section(self.graph))
        yield from roadmap_figures({"pairs_tried": len(self.log.tried), "dropped": self.log.dropped,
                                    "not_straight": [list(p) for p in self.log.not_straight],
                                    "homed_short": self.log.homed_short, "saved": self.log.saved})

    def drawings(self) -> Iterator[Drawing]:
        if self.graph is not None and self.drawn.changed("roadmap", self.graph):
            yield from roadmap_drawings(self.graph)
