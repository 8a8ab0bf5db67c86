"""What the roadmap nodes show: the report section's values and the drawings, in the reference frame."""

from __future__ import annotations

import math

import numpy as np
import pytest

from behaviours.roadmap.display import (
    Drawn,
    coverage_drawings,
    plan_drawings,
    roadmap_drawings,
    roadmap_figures,
    roadmap_section,
    robot_drawings,
    room_drawings,
    room_section,
)
from behaviours.telemetry import Arrows, Figure, Lines, Points, Sections
from maps.coverage import coverage_grid
from maps.planning import PlanResult, plan_path
from maps.roadmap import EdgeMotion, Roadmap
from maps.room import RoomEstimate
from perception.geometry import Pose2D

ROOM = RoomEstimate(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 2.0], [0.0, 2.0]]), np.array([1.5, 1.0]),
                    Pose2D(1.0, 0.0, math.pi / 2), 3, (Pose2D(1.5, 0.5), Pose2D(1.7, 0.6)),
                    np.array([[0.0, 1.0], [3.0, 1.0]]))


def roadmap() -> Roadmap:
    edge = EdgeMotion(0.1, 1.0, -0.1, np.diag([1e-3, 1e-3, 1e-3]))
    return Roadmap().with_target("a", Pose2D(1.0, 0.5, 0.2), "a.png").with_target("b", Pose2D(2.0, 1.5)).with_edge(
        "a", "b", edge)


def by_entity(drawings) -> dict[str, object]:
    return {d.entity: d for d in drawings}


def test_the_room_is_its_closed_polygon_obstacles_corners_and_the_reference():
    drawn = by_entity(room_drawings(ROOM))
    assert list(drawn) == ["roadmap/room/free", "roadmap/room/obstacles", "roadmap/room/corners",
                           "roadmap/room/reference"]
    free = drawn["roadmap/room/free"]
    assert isinstance(free, Lines) and free.colours == (40, 160, 40) and free.radius == 0.02
    (loop,) = free.strips
    assert len(loop) == 5 and np.array_equal(loop[0], loop[-1])  # closed
    obstacles = drawn["roadmap/room/obstacles"]
    assert isinstance(obstacles, Points) and obstacles.radius == 0.015 and obstacles.colours == (120, 120, 120)
    assert np.array_equal(drawn["roadmap/room/corners"].positions, [[1.5, 0.5], [1.7, 0.6]])
    reference = drawn["roadmap/room/reference"]
    assert isinstance(reference, Arrows) and np.array_equal(reference.vectors, [[0.4, 0.0]])
    assert reference.colours == (200, 60, 200) and reference.labels == ("reference",)


def test_a_room_without_obstacles_or_corners_is_its_polygon_and_the_reference():
    bare = RoomEstimate.from_polygon(ROOM.polygon)
    assert [d.entity for d in room_drawings(bare)] == ["roadmap/room/free", "roadmap/room/reference"]


def test_coverage_colours_each_valid_position_by_the_fraction_of_headings_covered():
    grid = coverage_grid(ROOM, ROOM.free, robot_radius=0.28).cover(1.5, 1.0)
    (points,) = coverage_drawings(grid)
    assert points.entity == "roadmap/coverage" and points.radius == pytest.approx(0.045)
    ix, iy = np.nonzero(grid.valid)
    assert len(points.positions) == grid.valid.sum() == len(points.colours)
    k = int(np.argmax(grid.covered[ix, iy].mean(axis=1)))  # the most covered position
    assert tuple(points.positions[k]) == pytest.approx(grid.position(int(ix[k]), int(iy[k])))
    fraction = grid.covered[ix[k], iy[k]].mean()
    assert points.colours[k] == (int(255 * (1 - fraction)), int(80 + 175 * fraction), 60)
    untouched = int(np.argmin(grid.covered[ix, iy].mean(axis=1)))
    assert points.colours[untouched] == (255, 80, 60)  # nothing covered: red


def test_the_roadmap_is_its_targets_with_headings_and_names_and_its_edges():
    drawn = by_entity(roadmap_drawings(roadmap()))
    targets = drawn["roadmap/targets"]
    assert isinstance(targets, Arrows) and targets.colours == (230, 140, 0)
    assert np.array_equal(targets.origins, [[1.0, 0.5], [2.0, 1.5]])
    assert targets.vectors[0] == pytest.approx([0.3 * math.cos(0.2), 0.3 * math.sin(0.2)])
    assert targets.labels == ("a", "b")
    graph = drawn["roadmap/graph"]
    assert isinstance(graph, Lines) and graph.colours == (30, 90, 220) and graph.radius == 0.015
    assert [s.tolist() for s in graph.strips] == [[[1.0, 0.5], [2.0, 1.5]]]
    assert list(by_entity(roadmap_drawings(Roadmap()))) == ["roadmap/graph"]  # empty: no targets, no edges


def test_a_plan_is_its_path_and_a_failed_plan_nothing():
    plan = plan_path(ROOM.free, Pose2D(0.7, 0.7), Pose2D(2.3, 1.3), robot_radius=0.28)
    (path,) = plan_drawings(plan)
    assert path.entity == "roadmap/plan" and path.colours == (250, 60, 60) and path.radius == 0.01
    assert path.strips[0].tolist() == [[w.x, w.y] for w in plan.waypoints]
    assert plan_drawings(PlanResult(False, "no path")) == []


def test_the_robot_is_shown_through_the_room_estimate():
    (robot,) = robot_drawings(ROOM, Pose2D(1.0, 2.0, math.pi / 2))  # 2 m ahead of the reference
    assert robot.entity == "roadmap/robot" and robot.colours == (0, 0, 0)
    assert np.allclose(robot.origins, [[2.0, 0.0]]) and np.allclose(robot.vectors, [[0.3, 0.0]])


def test_drawn_tells_a_new_value_from_the_one_drawn_by_identity():
    drawn, grid = Drawn(), coverage_grid(ROOM, ROOM.free, robot_radius=0.28)
    assert not drawn.changed("coverage", None)
    assert drawn.changed("coverage", grid) and not drawn.changed("coverage", grid)
    assert drawn.changed("plan", grid)  # another name: its own memory
    assert drawn.changed("coverage", grid.cover(1.5, 1.0))  # a new grid, equal or not


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


def test_roadmap_figures_nest_under_their_name():
    figures = roadmap_figures({"scans": 2, "covered_fraction": 0.5}, "search")
    assert figures == [Figure("roadmap", "search.scans", 2), Figure("roadmap", "search.covered_fraction", 0.5)]
    gathered = Sections()
    gathered.add(figures)
    gathered.add(roadmap_figures({"turn_scale": 1.02}))
    assert gathered.sections == {"roadmap": {"search": {"scans": 2, "covered_fraction": 0.5}, "turn_scale": 1.02}}
