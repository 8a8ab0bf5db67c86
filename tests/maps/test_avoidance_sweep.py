"""What is free around the base, against values worked out by hand.

The footprint is a 0.4 m square about the centre of rotation, grown by the 0.1 m clearance to a
0.6 m square (its front edge at x = 0.3), so the sweeps can be solved on paper.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.avoidance.sweep import (
    AvoidSettings,
    DetourLine,
    Surroundings,
    arc_point,
    free_distance,
    margin,
    needed_distance,
)
from perception.polygons import rectangle

SQUARE = rectangle(0.2, 0.2, 0.2)
SETTINGS = AvoidSettings(SQUARE, clearance=0.1, horizon=0.5, decel=0.25, speed=0.2)


def around(*points: tuple[float, float]) -> Surroundings:
    return Surroundings.of(np.array(points, dtype=float).reshape(-1, 2), SETTINGS)


def test_the_needed_distance_is_the_braking_distance_plus_the_horizons_travel():
    # eq. 1: 0.3^2 / (2 * 0.25) + 0.3 * 0.5 = 0.18 + 0.15
    assert needed_distance(0.3, SETTINGS) == pytest.approx(0.33)
    assert needed_distance(0.2, SETTINGS) == pytest.approx(0.18)
    assert needed_distance(-0.2, SETTINGS) == 0.0  # backing away means nothing ahead
    # a node ramping down as sqrt(2 a d) before its goal asks for d plus the horizon's travel
    d = 0.1
    assert needed_distance(math.sqrt(2 * 0.25 * d), AvoidSettings(SQUARE, horizon=0.0)) == pytest.approx(d)


def test_the_free_distance_along_a_straight_arc_is_the_gap_to_the_grown_front_edge():
    # a point 1 m ahead: the grown square's front edge (x = 0.3) meets it after 0.7 m
    assert around((1.0, 0.0)).free(0.2, 0.0) == pytest.approx(0.7)
    assert around((1.0, 0.35)).free(0.2, 0.0) == math.inf  # beside the grown square's path
    assert free_distance(SQUARE, np.zeros((0, 2)), 0.2, 0.0) == math.inf


def test_the_margin_shrinks_to_half_the_nearest_gap():
    assert margin(SQUARE, np.array([[1.0, 0.0]]), 0.1) == 0.1
    assert margin(SQUARE, np.array([[0.28, 0.0]]), 0.1) == pytest.approx(0.04)  # 0.08 from the front edge
    assert margin(SQUARE, np.zeros((0, 2)), 0.1) == 0.1


def test_a_point_within_the_clearance_blocks_every_motion_whose_sweep_reaches_it():
    # 0.05 m beside the square's left side: the straight arc passes it, and so does an arc of radius 0.5
    # either way (the point is 0.269 m from the left turn's centre (0, 0.5), nearer than the square's
    # 0.3; 0.757 m from the right turn's, farther than its far corners' 0.728). Radius 0.3 to the left
    # brings the left side into it: the point (0.1118 m from the centre (0, 0.3), at -26.57 deg) turns
    # clockwise to where its circle crosses the side (0.05, -0.1), -63.43 deg: 0.6435 rad at radius 0.3,
    # 0.193 m of travel, within the monitor's 1 m sweep.
    near = around((0.1, 0.25))
    assert not near.grazes(0.2, 0.0) and near.open(0.2, 0.0, 0.18)
    assert not near.grazes(0.2, 0.4) and not near.grazes(0.2, -0.4)
    assert free_distance(SQUARE, np.array([[0.1, 0.25]]), 0.2, 0.2 / 0.3) == pytest.approx(0.19305, abs=5e-5)
    assert near.grazes(0.2, 0.2 / 0.3) and not near.open(0.2, 0.2 / 0.3, 0.0)
    # facing 90 deg left it lies 0.1 m straight ahead of the square's front: grazed at once
    assert near.free_towards(np.array([math.pi / 2]))[0] == 0.0


def test_the_free_distance_in_a_direction_once_turned_to_face_it():
    # (0, 1) is 1 m to the left: facing it, 0.7 m to the grown front edge; (0.8, 0.8) is 1.131 m away at
    # 45 deg: 0.831 m. Facing left, (1, 0) is beside the path.
    points = around((0.0, 1.0))
    assert points.free_towards(np.array([0.0, math.pi / 2]))[1] == pytest.approx(0.7)
    assert around((0.8, 0.8)).free_towards(np.array([math.pi / 4]))[0] == pytest.approx(math.hypot(0.8, 0.8) - 0.3)
    assert around((1.0, 0.0)).free_towards(np.array([0.0, math.pi / 2])) == pytest.approx([0.7, math.inf])


def test_turning_on_the_spot_sweeps_the_corners_into_a_near_point():
    # (0.25, 0) is 0.25 m from the centre, inside the corners' 0.283 m: turning either way the front
    # edge x = 0.2 meets it where the circle crosses it, y = +-0.15, after atan2(0.15, 0.2) = 36.87 deg
    point = around((0.25, 0.0))
    assert point.turn_limits == pytest.approx((0.6435, 0.6435), abs=1e-4)
    assert point.turns(0.6) and point.turns(-0.6) and not point.turns(0.7) and not point.turns(-0.7)
    assert around((0.3, 0.0)).turns(math.pi)  # beyond the corners: a full turn is free


def test_an_arc_point_after_s_metres():
    # eq. 2: curvature 2 (radius 0.5), s = pi / 4: a quarter turn, (0.5, 0.5)
    assert arc_point(2.0, math.pi / 4) == pytest.approx((0.5, 0.5))
    assert arc_point(-2.0, math.pi / 4) == pytest.approx((0.5, -0.5))
    assert arc_point(0.0, 0.7) == (0.7, 0.0)


def test_the_detour_lines_offset_is_signed_left_positive():
    # eq. 3: a line east from the origin; a line north from (1, 1), on which x = 0 lies 1 m to the left
    assert DetourLine(0.0, 0.0, 0.0).offset(3.0, 0.4) == pytest.approx(0.4)
    assert DetourLine(1.0, 1.0, math.pi / 2).offset(0.0, 5.0) == pytest.approx(1.0)
    assert DetourLine(1.0, 1.0, math.pi / 2).offset(2.0, -3.0) == pytest.approx(-1.0)


def test_up_to_a_goal_the_footprint_must_not_touch_and_keeps_the_clearance_but_for_the_last_margin():
    # a point ahead, 0.25 m from the front edge: the bare square meets it after 0.25 m, grown after 0.15 m
    ahead = around((0.45, 0.0))
    assert not ahead.open(0.3, 0.0, needed_distance(0.3, SETTINGS))  # 0.15 m free, eq. 1 needs 0.33
    assert ahead.open(0.3, 0.0, 0.33, goal=0.2) and ahead.open(0.3, 0.0, 0.33, goal=0.24)
    assert not ahead.open(0.3, 0.0, 0.33, goal=0.26)  # a goal beyond the touch
    # a point beside the way, 0.02 m outside the square's side: the bare square passes it, grown it meets
    # it after 0.30 m (0.302 with round corners); a goal 0.35 m on is within the margin of that, 0.45 m is not
    beside = around((0.6, 0.22))
    assert beside.margin == pytest.approx(0.1)
    assert beside.open(0.3, 0.0, 0.33, goal=0.35)
    assert not beside.open(0.3, 0.0, 0.33, goal=0.45)


def test_a_point_within_the_clearance_beyond_the_goal_does_not_block_it():
    # 0.08 m ahead of the square's front edge: within the clearance, the margin is half of it, 0.04 m
    near = around((0.28, 0.0))
    assert near.margin == pytest.approx(0.04) and not near.open(0.02, 0.0, 0.01)  # grazed within the sweep
    assert near.open(0.02, 0.0, 0.01, goal=0.05)  # the motion ends 0.03 m short of it
    assert near.open(0.02, 0.0, 0.01, goal=0.06)  # 0.02 m short, eq. 1's 0.011 m within the goal less the margin
    assert not near.open(0.02, 0.0, 0.01, goal=0.1)  # ... or touches it first
