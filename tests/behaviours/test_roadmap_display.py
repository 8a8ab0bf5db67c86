"""The rerun views and report sections of the roadmap nodes, with a recorder that keeps what it is given."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from behaviours.roadmap.display import RoadmapDisplay, roadmap_section, room_section
from maps.coverage import coverage_grid
from maps.planning import plan_path
from maps.roadmap import EdgeMotion, Roadmap
from maps.room import RoomEstimate
from perception.geometry import Pose2D

ROOM = RoomEstimate(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 2.0], [0.0, 2.0]]), np.array([1.5, 1.0]),
                    Pose2D(1.0, 0.0, math.pi / 2), 3, (Pose2D(1.5, 0.5), Pose2D(1.7, 0.6)),
                    np.array([[0.0, 1.0], [3.0, 1.0]]))


class Recorder:
    """Stands in for the rerun module: archetypes are (name, arguments), ``log`` keeps (path, archetype)."""

    def __init__(self) -> None:
        self.logged: list[tuple[str, Any]] = []

    def __getattr__(self, archetype: str):
        return lambda *args, **kwargs: (archetype, args, kwargs)

    def log(self, path: str, value: Any) -> None:
        self.logged.append((path, value))

    def paths(self) -> list[str]:
        return [p for p, _ in self.logged]


def roadmap() -> Roadmap:
    edge = EdgeMotion(0.1, 1.0, -0.1, np.diag([1e-3, 1e-3, 1e-3]))
    return Roadmap().with_target("a", Pose2D(1.0, 0.5, 0.2), "a.png").with_target("b", Pose2D(2.0, 1.5)).with_edge(
        "a", "b", edge)


def test_each_view_is_logged_in_the_reference_frame_and_only_when_it_changed():
    rec, display = Recorder(), RoadmapDisplay()
    grid = coverage_grid(ROOM, ROOM.free, robot_radius=0.28).cover(1.5, 1.0)
    plan = plan_path(ROOM.free, Pose2D(0.7, 0.7), Pose2D(2.3, 1.3), robot_radius=0.28)
    graph = roadmap()
    for _ in range(2):  # the second time nothing changed: nothing logged again
        display.log_room(rec, ROOM)
        display.log_coverage(rec, grid)
        display.log_roadmap(rec, graph)
        display.log_plan(rec, plan)
    assert rec.paths()[:5] == ["roadmap/room/free", "roadmap/room/obstacles", "roadmap/room/corners",
                               "roadmap/room/reference", "roadmap/coverage"]
    assert rec.paths()[5:] == ["roadmap/targets", "roadmap/graph", "roadmap/plan"]
    polygon = dict(rec.logged)["roadmap/room/free"][1][0][0]
    assert np.array_equal(polygon[0], polygon[-1]) and len(polygon) == 5  # closed
    _, (positions,), kwargs = dict(rec.logged)["roadmap/coverage"]
    assert len(positions) == grid.valid.sum() and kwargs["colors"].shape == (len(positions), 3)
    targets = dict(rec.logged)["roadmap/targets"][2]
    assert targets["labels"] == ["a", "b"] and targets["origins"] == [[1.0, 0.5], [2.0, 1.5]]


def test_the_robot_is_shown_through_the_room_estimate():
    rec = Recorder()
    RoadmapDisplay().log_robot(rec, ROOM, Pose2D(1.0, 2.0, math.pi / 2))  # 2 m ahead of the reference
    _, _, kwargs = rec.logged[0][1]
    assert np.allclose(kwargs["origins"], [[2.0, 0.0]]) and np.allclose(kwargs["vectors"], [[0.3, 0.0]])


def test_report_sections_in_degrees_and_metres():
    section = roadmap_section(roadmap())
    assert section["targets"]["a"] == {"x": 1.0, "y": 0.5, "theta_deg": round(math.degrees(0.2), 3), "image": "a.png"}
    assert section["edges"] == [{"from": "a", "to": "b", "angle1_deg": round(math.degrees(0.1), 3), "distance_m": 1.0,
                                 "angle2_deg": round(math.degrees(-0.1), 3), "cost": section["edges"][0]["cost"]}]
    assert section["connected"] and section["components"] == 1
    room = room_section(ROOM, [10] * 12, [5] * 12, 42.0)
    assert room["reference_corner"] == 3 and room["reference_stamp"] == 42.0
    assert room["reference_odometry"] == {"x": 1.0, "y": 0.0, "theta_deg": 90.0}
    assert 0 < room["free_area_m2"] < 6.0
