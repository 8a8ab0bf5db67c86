"""The ``roadmap`` report section and the rerun views of the roadmap nodes.

Report (``report_sections()`` of the nodes, merged by the runner under ``roadmap``):
``turn_scale`` (CalibrateTurns), ``room`` (RoomEstimationDodecagon), ``targets`` and
``edges``/``connected`` (from the roadmap on the blackboard: RecordTarget, BuildGraph),
``search`` (CoverageScoring), ``reference_drift_m (NODE)`` (ReturnToReference), ``navigation``
(NavigateToTarget). Angles in degrees, lengths in metres, poses in the reference frame.

rerun (``log_rerun(rec)``, after every recorded tick; logged again only when the value
changed), all in the reference frame under ``roadmap/``: ``room`` (free floor polygon, the
obstacle points, the dodecagon corners), ``coverage`` (each valid position coloured by the
fraction of its headings covered), ``targets`` (position, heading, name), ``graph`` (edges),
``plan`` (the last planned path), ``robot`` (the odometry pose seen through the room estimate).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from maps.coverage import CoverageGrid
from maps.planning import PlanResult
from maps.roadmap import Roadmap
from maps.room import RoomEstimate
from perception.geometry import Pose2D


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


class RoadmapDisplay:
    """Logs roadmap values to rerun, each only when it changed (by identity)."""

    def __init__(self) -> None:
        self._last: dict[str, int] = {}

    def _changed(self, what: str, value: Any) -> bool:
        if value is None or self._last.get(what) == id(value):
            return False
        self._last[what] = id(value)
        return True

    def log_room(self, rec: Any, room: RoomEstimate | None) -> None:
        if room is None or not self._changed("room", room.polygon):  # re-anchoring keeps the map: not again
            return
        loop = np.vstack([room.polygon, room.polygon[:1]])
        rec.log("roadmap/room/free", rec.LineStrips2D([loop], colors=[[40, 160, 40]], radii=0.02))
        if len(room.obstacle_points):
            rec.log("roadmap/room/obstacles", rec.Points2D(room.obstacle_points, radii=0.015, colors=[[120, 120, 120]]))
        if room.corners:
            rec.log("roadmap/room/corners", rec.Points2D([[c.x, c.y] for c in room.corners], radii=0.03))
        rec.log("roadmap/room/reference", rec.Arrows2D(origins=[[0.0, 0.0]], vectors=[[0.4, 0.0]],
                                                     labels=["reference"], colors=[[200, 60, 200]]))

    def log_coverage(self, rec: Any, coverage: CoverageGrid | None) -> None:
        if coverage is None or not self._changed("coverage", coverage):
            return
        ix, iy = np.nonzero(coverage.valid)
        fraction = coverage.covered[ix, iy].mean(axis=1)
        xy = np.column_stack((coverage.origin[0] + ix * coverage.cell, coverage.origin[1] + iy * coverage.cell))
        colours = np.column_stack((255 * (1 - fraction), 80 + 175 * fraction, 60 + 0 * fraction)).astype(np.uint8)
        rec.log("roadmap/coverage", rec.Points2D(xy, radii=coverage.cell * 0.45, colors=colours))

    def log_roadmap(self, rec: Any, roadmap: Roadmap | None) -> None:
        if roadmap is None or not self._changed("roadmap", roadmap):
            return
        if roadmap.targets:
            xy = [[t.pose.x, t.pose.y] for t in roadmap.targets]
            heading = [[0.3 * math.cos(t.pose.theta), 0.3 * math.sin(t.pose.theta)] for t in roadmap.targets]
            rec.log("roadmap/targets", rec.Arrows2D(origins=xy, vectors=heading, labels=list(roadmap.names),
                                                    colors=[[230, 140, 0]]))
        strips = [[[roadmap.target(e.source).pose.x, roadmap.target(e.source).pose.y],
                   [roadmap.target(e.target).pose.x, roadmap.target(e.target).pose.y]] for e in roadmap.edges]
        rec.log("roadmap/graph", rec.LineStrips2D(strips, colors=[[30, 90, 220]], radii=0.015))

    def log_plan(self, rec: Any, plan: PlanResult | None) -> None:
        if plan is None or not plan.ok or not self._changed("plan", plan):
            return
        rec.log("roadmap/plan", rec.LineStrips2D([[[w.x, w.y] for w in plan.waypoints]], colors=[[250, 60, 60]],
                                                 radii=0.01))

    def log_robot(self, rec: Any, room: RoomEstimate | None, odometry: Pose2D | None) -> None:
        if room is None or odometry is None:
            return
        pose = room.to_reference(odometry)
        rec.log("roadmap/robot", rec.Arrows2D(origins=[[pose.x, pose.y]], vectors=[[0.3 * math.cos(pose.theta),
                                                                                     0.3 * math.sin(pose.theta)]],
                                              colors=[[0, 0, 0]]))
