"""Planning with OMPL: around an obstacle with true clearance, determinism, and clear refusals."""

from __future__ import annotations

import math
import time

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from maps.planning import Leg, legs_through, plan_path
from maps.room import FreeGrid
from perception.geometry import Pose2D

CELL = 0.05
ROOM = (4.0, 3.0)
RADIUS = 0.25


def _grid(*boxes: tuple[float, float, float, float]) -> FreeGrid:
    """The 4 x 3 m room at 5 cm; a cell is blocked when its square touches a box (x0, y0, x1, y1)."""
    nx, ny = round(ROOM[0] / CELL), round(ROOM[1] / CELL)
    grid = FreeGrid(np.ones((nx, ny), bool), CELL, (CELL / 2, CELL / 2))
    centres = grid.centres()
    free = grid.free.copy()
    h = CELL / 2
    for x0, y0, x1, y1 in boxes:
        free &= ~((centres[..., 0] + h > x0) & (centres[..., 0] - h < x1)
                  & (centres[..., 1] + h > y0) & (centres[..., 1] - h < y1))
    return FreeGrid(free, CELL, grid.origin)


def _true_clearance(points: np.ndarray, boxes) -> np.ndarray:
    """Exact distance of points to the room's walls and to the boxes."""
    walls = np.minimum.reduce([points[:, 0], ROOM[0] - points[:, 0], points[:, 1], ROOM[1] - points[:, 1]])
    clearance = walls
    for x0, y0, x1, y1 in boxes:
        gap_x = np.maximum.reduce([x0 - points[:, 0], points[:, 0] - x1, np.zeros(len(points))])
        gap_y = np.maximum.reduce([y0 - points[:, 1], points[:, 1] - y1, np.zeros(len(points))])
        clearance = np.minimum(clearance, np.hypot(gap_x, gap_y))
    return clearance


def _dense(waypoints: tuple[Pose2D, ...]) -> np.ndarray:
    pts = np.array([[w.x, w.y] for w in waypoints])
    pieces = [a + np.linspace(0, 1, 500)[:, None] * (b - a) for a, b in zip(pts[:-1], pts[1:], strict=True)]
    return np.concatenate(pieces)


def _drive(start: Pose2D, legs: tuple[Leg, ...], final_turn: float) -> Pose2D:
    pose = start
    for leg in legs:
        pose = pose.compose(Pose2D(0.0, 0.0, leg.turn)).compose(Pose2D(leg.distance, 0.0, 0.0))
    return pose.compose(Pose2D(0.0, 0.0, final_turn))


WALL = (1.9, 0.0, 2.1, 2.2)  # from the bottom wall up to 0.8 m below the top wall


def test_path_around_an_obstacle_keeps_the_robot_radius(record_property):
    grid = _grid(WALL)
    start, goal = Pose2D(0.6, 0.6, 0.0), Pose2D(3.4, 0.6, math.pi / 2)
    began = time.perf_counter()
    result = plan_path(grid, start, goal, robot_radius=RADIUS)
    took = time.perf_counter() - began
    assert result.ok and result.reason == ""
    assert result.waypoints[0] == start and result.waypoints[-1] == goal
    assert _true_clearance(_dense(result.waypoints), [WALL]).min() >= RADIUS
    assert result.length > 2 * math.hypot(1.4, 2.2 - 0.6)  # it must go over the wall's end
    assert result.length < 7.0  # simplified: not a random walk
    end = _drive(start, result.legs, result.final_turn)
    assert end.distance_to(goal) < 1e-9 and abs(math.remainder(end.theta - goal.theta, 2 * math.pi)) < 1e-9
    for before, after in zip(result.waypoints[1:-2], result.waypoints[2:-1], strict=True):
        assert abs(before.theta - math.atan2(after.y - before.y, after.x - before.x)) < 1e-9
    record_property("plan_around_wall_ms", round(took * 1e3, 2))
    print(f"\nplan around a wall (4 x 3 m at 5 cm): {took * 1e3:.1f} ms, {len(result.waypoints)} waypoints, "
          f"{result.length:.2f} m")


def test_planning_is_deterministic():
    grid = _grid(WALL, (2.8, 1.0, 3.2, 3.0))
    start, goal = Pose2D(0.6, 0.6, 0.0), Pose2D(3.5, 2.5, 0.0)
    first = plan_path(grid, start, goal, robot_radius=RADIUS, seed=7)
    again = plan_path(grid, start, goal, robot_radius=RADIUS, seed=7)
    assert first.ok and first.waypoints == again.waypoints
    assert _true_clearance(_dense(first.waypoints), [WALL, (2.8, 1.0, 3.2, 3.0)]).min() >= RADIUS


def test_a_clear_straight_line_needs_no_search():
    result = plan_path(_grid(), Pose2D(0.5, 0.5, 1.0), Pose2D(3.0, 2.0, -1.0), robot_radius=RADIUS)
    assert result.ok and len(result.waypoints) == 2 and len(result.legs) == 1
    assert result.length == math.hypot(2.5, 1.5)


def test_no_path_is_a_clear_answer_at_once():
    closed = (1.9, 0.0, 2.1, 3.0)
    result = plan_path(_grid(closed), Pose2D(0.6, 0.6, 0.0), Pose2D(3.4, 0.6, 0.0), robot_radius=RADIUS)
    assert not result.ok and "separate free regions" in result.reason and result.waypoints == ()
    narrow = (1.9, 0.0, 2.1, 2.6)  # a 0.4 m gap: too narrow for a 0.5 m wide robot
    assert "separate" in plan_path(_grid(narrow), Pose2D(0.6, 0.6, 0.0), Pose2D(3.4, 0.6, 0.0),
                                   robot_radius=RADIUS).reason
    assert plan_path(_grid(narrow), Pose2D(0.6, 0.6, 0.0), Pose2D(3.4, 0.6, 0.0), robot_radius=0.1).ok


def test_running_out_of_time_is_reported():
    result = plan_path(_grid(WALL), Pose2D(0.6, 0.6, 0.0), Pose2D(3.4, 0.6, 0.0), robot_radius=RADIUS, time_limit=0.0)
    assert not result.ok and result.reason == "no path found within 0 s"


def test_start_or_goal_where_the_robot_cannot_stand():
    grid = _grid(WALL)
    assert "cannot stand at the start" in plan_path(grid, Pose2D(2.0, 1.0), Pose2D(3.4, 0.6),
                                                    robot_radius=RADIUS).reason
    assert "cannot stand at the goal" in plan_path(grid, Pose2D(0.6, 0.6), Pose2D(3.9, 0.6),
                                                   robot_radius=RADIUS).reason
    assert "cannot stand at the goal" in plan_path(grid, Pose2D(0.6, 0.6), Pose2D(9.0, 0.6),
                                                   robot_radius=RADIUS).reason


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-5, 5), st.floats(-5, 5)), min_size=2, max_size=6),
       st.floats(-math.pi, math.pi), st.floats(-math.pi, math.pi))
def test_legs_drive_through_the_polyline(points, start_theta, goal_theta):
    pts = np.array(points)
    legs, final_turn = legs_through(pts, start_theta, goal_theta)
    end = _drive(Pose2D(*pts[0], start_theta), legs, final_turn)
    assert end.distance_to(Pose2D(*pts[-1])) < 1e-9
    assert abs(math.remainder(end.theta - goal_theta, 2 * math.pi)) < 1e-9
    assert all(abs(leg.turn) <= math.pi for leg in legs)
