"""What the roadmap nodes show: the ``roadmap`` report section and their drawings for the recording.

Report (the nodes' ``figures()``, section ``roadmap``): ``turn_scale`` (CalibrateTurns), ``room``
(RoomEstimationDodecagon), ``targets`` and ``edges``/``connected``/``components`` (from the
roadmap on the blackboard: RecordTarget, BuildGraph), ``search`` (CoverageScoring),
``reference_drift_m (NODE)`` (ReturnToReference), ``navigation`` (NavigateToTarget). Angles in
degrees, lengths in metres, poses in the reference frame.

Drawings (the nodes' ``drawings()``, all in the reference frame under ``roadmap/``): ``room``
(free floor polygon, the obstacle points, the dodecagon corners, the reference), ``coverage``
(each valid position coloured by the fraction of its headings covered), ``targets`` (position,
heading, each labelled with its name), ``graph`` (edges), ``plan`` (the last planned path),
``robot`` (the odometry pose seen through the room estimate). The functions here draw a value;
a node draws it again only when it changed (:class:`Drawn`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from behaviours.telemetry import Arrows, Colour, Drawing, Figure, Lines, Points
from maps.coverage import CoverageGrid
from maps.planning import PlanResult
from maps.roadmap import Roadmap
from maps.room import RoomEstimate
from perception.geometry import Pose2D

SECTION = "roadmap"
FREE_COLOUR: Colour = (40, 160, 40)
OBSTACLE_COLOUR: Colour = (120, 120, 120)
CORNER_COLOUR: Colour = (60, 60, 200)
REFERENCE_COLOUR: Colour = (200, 60, 200)
TARGET_COLOUR: Colour = (230, 140, 0)
GRAPH_COLOUR: Colour = (30, 90, 220)
PLAN_COLOUR: Colour = (250, 60, 60)
ROBOT_COLOUR: Colour = (0, 0, 0)
HEADING_LENGTH = 0.3  # m: the arrow of a target's or the robot's heading


# -- report ------------------------------------------------------------------------------------
def pose_dict(pose: Pose2D) -> dict[str, float]:
    return {"x": round(pose.x, 4), "y": round(pose.y, 4), "theta_deg": round(math.degrees(pose.theta), 3)}


def roadmap_section(roadmap: Roadmap) -> dict[str, Any]:
    """Targets with their poses (reference frame), edges and connectivity."""
    edges = [{"from": e.source, "to": e.target, "angle1_deg": round(math.degrees(e.motion.angle1), 3),
              "distance_m": round(e.motion.distance, 4), "angle2_deg": round(math.degrees(e.motion.angle2), 3),
              "cost": round(e.motion.cost, 5)} for e in roadmap.edges]
    return {
        "targets": {t.name: {**pose_dict(t.pose), "image": t.image} for t in roadmap.targets},
        "edges": edges,
        "connected": roadmap.is_connected(),
        "components": len(roadmap.components()),
    }


def room_section(room: RoomEstimate, points: list[int], features: list[int], stamp: float) -> dict[str, Any]:
    """The room estimate: free area, reference corner (its odometry pose and when it was taken)."""
    return {
        "free_area_m2": round(float(room.free.free.sum()) * room.free.cell ** 2, 3),
        "polygon_vertices": len(room.polygon),
        "reference_corner": room.reference_index,
        "reference_odometry": pose_dict(room.reference_pose),
        "reference_stamp": stamp,
        "stereo_points": points,
        "image_features": features,
    }


def roadmap_figures(values: dict[str, Any], within: str = "") -> list[Figure]:
    """The ``roadmap`` figures of a mapping of names to values, nested in ``within`` when given
    (``roadmap_figures(room_section(...), "room")``: ``room.free_area_m2``, ...)."""
    prefix = f"{within}." if within else ""
    return [Figure(SECTION, prefix + name, value) for name, value in values.items()]


# -- drawings ----------------------------------------------------------------------------------
class Drawn:
    """What a node has drawn (by identity): a value is drawn again only when it is another object."""

    def __init__(self) -> None:
        self._last: dict[str, object] = {}

    def changed(self, what: str, value: object) -> bool:
        """True (and remembered) when ``value`` is not None and not what was drawn as ``what`` last."""
        if value is None or self._last.get(what) is value:
            return False
        self._last[what] = value
        return True


def room_drawings(room: RoomEstimate) -> list[Drawing]:
    """The free floor polygon (closed), the obstacle points, the dodecagon corners and the reference."""
    loop = np.vstack([room.polygon, room.polygon[:1]])
    drawings: list[Drawing] = [Lines("roadmap/room/free", [loop], FREE_COLOUR, radius=0.02)]
    if len(room.obstacle_points):
        drawings.append(Points("roadmap/room/obstacles", room.obstacle_points, OBSTACLE_COLOUR, radius=0.015))
    if room.corners:
        drawings.append(Points("roadmap/room/corners", np.array([[c.x, c.y] for c in room.corners]), CORNER_COLOUR,
                               radius=0.03))
    drawings.append(Arrows("roadmap/room/reference", np.array([[0.4, 0.0]]), REFERENCE_COLOUR, np.array([[0.0, 0.0]]),
                           labels=("reference",)))
    return drawings


def coverage_drawings(coverage: CoverageGrid) -> list[Drawing]:
    """Each valid position, red (nothing covered) to green (every heading covered)."""
    ix, iy = np.nonzero(coverage.valid)
    fraction = coverage.covered[ix, iy].mean(axis=1)
    xy = np.column_stack(coverage.position(ix, iy))
    colours = np.column_stack((255 * (1 - fraction), 80 + 175 * fraction, 60 + 0 * fraction)).astype(np.uint8)
    rgb = [(int(r), int(g), int(b)) for r, g, b in colours]
    return [Points("roadmap/coverage", xy, rgb, radius=coverage.cell * 0.45)]


def roadmap_drawings(roadmap: Roadmap) -> list[Drawing]:
    """The targets (position, heading, name) and the edges of the graph."""
    drawings: list[Drawing] = []
    if roadmap.targets:
        xy = np.array([[t.pose.x, t.pose.y] for t in roadmap.targets])
        heading = np.array([heading_vector(t.pose) for t in roadmap.targets])
        drawings.append(Arrows("roadmap/targets", heading, TARGET_COLOUR, xy, labels=tuple(roadmap.names)))
    ends = [(roadmap.target(e.source).pose, roadmap.target(e.target).pose) for e in roadmap.edges]
    strips = [np.array([[a.x, a.y], [b.x, b.y]]) for a, b in ends]
    drawings.append(Lines("roadmap/graph", strips, GRAPH_COLOUR, radius=0.015))
    return drawings


def plan_drawings(plan: PlanResult) -> list[Drawing]:
    """The path a plan found (nothing for a failed plan)."""
    if not plan.ok:
        return []
    return [Lines("roadmap/plan", [np.array([[w.x, w.y] for w in plan.waypoints])], PLAN_COLOUR, radius=0.01)]


def robot_drawings(room: RoomEstimate, odometry: Pose2D) -> list[Drawing]:
    """The robot's odometry pose in the reference frame, through the room estimate."""
    pose = room.to_reference(odometry)
    return [Arrows("roadmap/robot", np.array([heading_vector(pose)]), ROBOT_COLOUR, np.array([[pose.x, pose.y]]))]


def heading_vector(pose: Pose2D) -> list[float]:
    return [HEADING_LENGTH * math.cos(pose.theta), HEADING_LENGTH * math.sin(pose.theta)]
