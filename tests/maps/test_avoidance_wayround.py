"""The way round planned on the echoes kept (maps.avoidance.wayround), against layouts worked by hand.

The footprint is the default disc of 0.2613 m (enclosing radius), the clearance 0.10 m: a cell
can be stood on where it is more than 0.3613 m from every echo. Cells are 5 cm, centred at
0.025 + 0.05 k; the robot at the origin stands in the cell centred (0.025, 0.025).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from behaviours.footprint import DEFAULT_FOOTPRINT
from maps.avoidance.sweep import AvoidSettings, DetourLine
from maps.avoidance.wayround import WayRound, carrot, plan
from perception.geometry import Pose2D

SETTINGS = AvoidSettings(DEFAULT_FOOTPRINT, clearance=0.10)
NEED = 0.2613 + 0.10
HERE = Pose2D(0.0, 0.0, 0.0)


def wall(x0: float, y0: float, x1: float, y1: float, step: float = 0.02) -> np.ndarray:
    n = int(math.ceil(math.hypot(x1 - x0, y1 - y0) / step)) + 1
    return np.column_stack((np.linspace(x0, x1, n), np.linspace(y0, y1, n)))


def least_distance(path: np.ndarray, points: np.ndarray) -> float:
    return float(np.min(np.hypot(path[:, None, 0] - points[None, :, 0], path[:, None, 1] - points[None, :, 1])))


def test_on_an_open_floor_the_way_is_the_straight_metre_ahead():
    way = plan(np.zeros((0, 2)), HERE, 0.0, SETTINGS, origin=(0.0, 0.0))
    assert way is not None
    # the first cell centre 1 m or more ahead: x = 1.025, on the robot's row (y = 0.025)
    assert way.end == pytest.approx((1.025, 0.025))
    # from the robot (0, 0) to the next cell (0.075, 0.025), then 19 steps of 0.05 m
    assert way.length == pytest.approx(math.hypot(0.075, 0.025) + 19 * 0.05, abs=1e-9)


def test_a_wall_across_the_way_is_passed_beyond_its_end_with_the_room_the_robot_needs():
    points = wall(0.6, -1.0, 0.6, 0.8)  # across the way, open beyond y = 0.8
    way = plan(points, HERE, 0.0, SETTINGS, origin=(0.0, 0.0))
    assert way is not None
    assert way.end[0] >= 1.0  # a metre along the heading from where it was held
    assert least_distance(way.path[6:], points) > NEED  # beyond the cells near the robot: the whole room
    assert way.path[:, 1].max() > 0.8 + NEED  # round the wall's end, not through it


def test_no_way_round_within_the_stray_bound_is_none():
    points = wall(0.6, -1.0, 0.6, 0.8)
    line = DetourLine(0.0, 0.0, 0.0)
    # the way round the end needs the robot 0.8 + 0.36 = 1.16 m off the line: not within 2 x 0.55 m ...
    strict = AvoidSettings(DEFAULT_FOOTPRINT, clearance=0.10, max_stray=0.55)
    assert plan(points, HERE, 0.0, strict, origin=(0.0, 0.0), line=line) is None
    assert plan(points, HERE, 0.0, strict, origin=(0.0, 0.0), line=line, stray=2.2) is not None  # ... within 1.21
    loose = AvoidSettings(DEFAULT_FOOTPRINT, clearance=0.10, max_stray=0.6)  # within 2 x 0.6 m
    assert plan(points, HERE, 0.0, loose, origin=(0.0, 0.0), line=line) is not None


def test_a_robot_nearer_something_than_its_room_can_still_leave():
    # an echo 0.22 m to the left, in the cell centred (0.025, 0.225): the robot's cell has 0.2 - 0.035 =
    # 0.165 m of room, its neighbours to the right 0.25 - 0.035 = 0.215 m and hypot(0.05, 0.25) - 0.035 =
    # 0.22 m, less than the 0.2613 m enclosing radius; the cells near it with as much room as the robot
    # has where it stands are open, and lead away
    way = plan(np.array([[0.0, 0.22]]), HERE, 0.0, SETTINGS, origin=(0.0, 0.0))
    assert way is not None and way.end[0] >= 1.0


def test_a_wall_across_the_whole_grid_leaves_no_way():
    assert plan(wall(0.6, -3.5, 0.6, 3.5), HERE, 0.0, SETTINGS, origin=(0.0, 0.0)) is None


def test_out_of_a_pocket_the_way_starts_backwards():
    # a U open behind the robot: ahead at x = 0.45, sides at y = +-0.6 from x = -0.5 to 0.45
    points = np.vstack((wall(0.45, -0.6, 0.45, 0.6), wall(-0.5, 0.6, 0.45, 0.6), wall(-0.5, -0.6, 0.45, -0.6)))
    way = plan(points, HERE, 0.0, SETTINGS, origin=(0.0, 0.0))
    assert way is not None
    assert way.end[0] >= 1.0
    # out of the mouth first (x <= -0.5 - NEED, clear of the sides' ends), then round a side (|y| >= 0.6 + NEED)
    out = int(np.argmax(way.path[:, 0] < -0.5 - NEED + 0.05))
    assert out > 0 and np.all(np.diff(way.path[: out + 1, 0]) <= 1e-9)
    assert np.abs(way.path[:, 1]).max() >= 0.6 + NEED - 0.05
    assert least_distance(way.path[6:], points) > NEED


def test_progress_counts_from_where_the_robot_was_held_along_the_heading_then():
    # planned again 0.5 m on: the end is still a metre from the origin along the heading (90 degrees)
    way = plan(np.zeros((0, 2)), Pose2D(0.0, 0.5, 0.0), math.pi / 2.0, SETTINGS, origin=(0.0, 0.0))
    assert way is not None and way.end[1] >= 1.0 and way.end[1] < 1.05
    assert way.length == pytest.approx(0.55, abs=0.06)


def test_the_carrot_is_the_point_a_lookahead_on_and_the_end_when_nearer():
    way = WayRound(np.array([[0.0, 0.0], [0.2, 0.0], [0.4, 0.0], [0.6, 0.0], [0.8, 0.0]]), 0.8)
    point, left = carrot(way, Pose2D(0.2, 0.1, 0.0), 0.5)
    # the nearest point is (0.2, 0); on from it, (0.6, 0) is hypot(0.4, 0.1) = 0.412 m from the robot,
    # (0.8, 0) hypot(0.6, 0.1) = 0.608 m: the first 0.5 m or more away is (0.8, 0)
    assert point == pytest.approx((0.8, 0.0)) and left == pytest.approx(math.hypot(0.6, 0.1))
    point, left = carrot(way, Pose2D(0.7, 0.0, 0.0), 0.5)
    assert point == pytest.approx((0.8, 0.0)) and left == pytest.approx(0.1)
