"""Free arcs and the choice among them, against values worked out by hand.

The footprint in most cases is a 0.4 m square about the centre of rotation, grown by the 0.1 m
clearance to a 0.6 m square (its front edge at x = 0.3), so the sweeps can be solved on paper.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.avoidance.arcs import (
    ArcSettings,
    DetourLine,
    Surroundings,
    arc_point,
    choose,
    curvatures,
    free_distance,
    margin,
    needed_distance,
    wished_curvature,
)
from perception.geometry import Pose2D
from perception.polygons import rectangle

SQUARE = rectangle(0.2, 0.2, 0.2)
# three arcs (radius 0.5 right, straight, radius 0.5 left) at 0.2 m/s, needing 0.2^2 / 0.5 + 0.2 * 0.5 = 0.18 m
THREE = ArcSettings(SQUARE, clearance=0.1, horizon=0.5, decel=0.25, speed=0.2, min_radius=0.5, arcs=3)


def around(*points: tuple[float, float], settings: ArcSettings = THREE) -> Surroundings:
    return Surroundings.of(np.array(points, dtype=float).reshape(-1, 2), settings)


def test_the_needed_distance_is_the_braking_distance_plus_the_horizons_travel():
    # eq. 1: 0.3^2 / (2 * 0.25) + 0.3 * 0.5 = 0.18 + 0.15
    assert needed_distance(0.3, ArcSettings(SQUARE)) == pytest.approx(0.33)
    assert needed_distance(0.2, THREE) == pytest.approx(0.18)
    assert needed_distance(-0.2, THREE) == 0.0  # backing away means nothing ahead
    # a node ramping down as sqrt(2 a d) before its goal asks for d plus the horizon's travel
    d = 0.1
    assert needed_distance(math.sqrt(2 * 0.25 * d), ArcSettings(SQUARE, horizon=0.0)) == pytest.approx(d)


def test_the_free_distance_along_a_straight_arc_is_the_gap_to_the_grown_front_edge():
    # a point 1 m ahead: the grown square's front edge (x = 0.3) meets it after 0.7 m
    assert around((1.0, 0.0)).free(0.2, 0.0) == pytest.approx(0.7)
    assert around((1.0, 0.35)).free(0.2, 0.0) == math.inf  # beside the grown square's path
    assert free_distance(SQUARE, np.zeros((0, 2)), 0.2, 0.0) == math.inf


def test_the_margin_shrinks_to_half_the_nearest_gap():
    assert margin(SQUARE, np.array([[1.0, 0.0]]), 0.1) == 0.1
    assert margin(SQUARE, np.array([[0.28, 0.0]]), 0.1) == pytest.approx(0.04)  # 0.08 from the front edge
    assert margin(SQUARE, np.zeros((0, 2)), 0.1) == 0.1


def test_a_point_within_the_clearance_blocks_every_arc_whose_sweep_reaches_it():
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


def test_the_wished_curvature_is_the_commands_clipped_to_the_fan():
    assert wished_curvature(0.2, 0.2, THREE) == pytest.approx(1.0)
    assert wished_curvature(0.2, 1.0, THREE) == 2.0  # radius 0.2 is sharper than the fan's 0.5
    assert wished_curvature(0.0, -0.5, THREE) == -2.0  # a turn on the spot asks for the sharpest arc
    assert list(curvatures(THREE)) == [-2.0, 0.0, 2.0]


def test_a_point_ahead_on_the_right_sends_the_robot_left():
    # (0.4, -0.28): straight ahead the grown square meets it after 0.1 m (< 0.18: blocked). Turning right
    # about (0, -0.5) the point (0.215 from its 0.2 m edge... radius 0.4565 about the centre, at 28.81 deg)
    # comes round to the front edge x = 0.3 at 48.92 deg: 0.3509 rad at radius 0.5, 0.175 m: blocked too.
    # Turning left about (0, 0.5) the point is 0.8766 m from the centre, farther than the grown square's
    # far corner (0.854 m): never met.
    choice = choose(around((0.4, -0.28)), 0.0, THREE)
    right, straight, left = choice.arcs
    assert right.free == pytest.approx(0.1755, abs=5e-4)
    assert straight.free == pytest.approx(0.1)
    assert left.free == math.inf
    assert choice.chosen == 2 and choice.side == 1 and choice.reach == pytest.approx(0.18)


def test_a_detour_keeps_the_side_it_took():
    # (0.8, 0): straight ahead free for 0.5 m, short of a 0.58 m need (horizon 2.5 s); both turns pass
    # it (0.943 m from their centres, beyond the far corners at 0.854 m): equally close to the wish
    far = ArcSettings(SQUARE, clearance=0.1, horizon=2.5, speed=0.2, min_radius=0.5, arcs=3)
    points = around((0.8, 0.0), settings=far)
    assert [a.free for a in choose(points, 0.0, far).arcs] == [math.inf, pytest.approx(0.5), math.inf]
    assert choose(points, 0.0, far, side=1).chosen == 2
    assert choose(points, 0.0, far, side=-1).chosen == 0
    # the other side is taken when the detour's side has nothing free: (0.4, 0.4) is 0.4123 m from the
    # left turn's centre (0, 0.5), at -14.04 deg; its circle meets the grown front edge x = 0.3 at
    # (0.3, -0.2828), -43.31 deg: 0.5109 rad at radius 0.5, 0.2555 m, short of 0.58
    left_blocked = choose(around((0.8, 0.0), (0.4, 0.4), settings=far), 0.0, far, side=1)
    assert left_blocked.arcs[2].free == pytest.approx(0.2555, abs=5e-4) and left_blocked.chosen == 0
    assert choose(around((0.8, 0.0), (0.4, -0.4), settings=far), 0.0, far, side=-1).chosen == 2


def test_a_detour_stays_within_max_stray_of_its_line():
    # the robot 1.4 m left of the line it started on, heading along it; 0.58 m along the left arc
    # (radius 0.5) it would be 0.302 m further left: 1.70 m > 1.5; the right arc comes back
    far = ArcSettings(SQUARE, clearance=0.1, horizon=2.5, speed=0.2, min_radius=0.5, arcs=3, max_stray=1.5)
    line = DetourLine(0.0, 0.0, 0.0)
    choice = choose(around((0.8, 0.0), settings=far), 0.0, far, side=1, pose=Pose2D(0.0, 1.4, 0.0), line=line)
    assert [a.strays for a in choice.arcs] == [False, False, True]
    assert choice.chosen == 0 and not choice.only_straying
    # with the right arc blocked too, only the bound holds the robot
    held = choose(around((0.8, 0.0), (0.4, -0.4), settings=far), 0.0, far, pose=Pose2D(0.0, 1.6, 0.0), line=line)
    assert held.chosen is None and held.only_straying


def test_the_choice_is_mirror_symmetric():
    fan = ArcSettings(SQUARE, clearance=0.1, horizon=1.0, speed=0.2, min_radius=0.4, arcs=11)
    points = np.array([[0.7, -0.1], [0.75, 0.05], [0.5, -0.4]])
    choice = choose(Surroundings.of(points, fan), 0.3, fan)
    mirrored = choose(Surroundings.of(points * [1.0, -1.0], fan), -0.3, fan)
    assert choice.chosen is not None and mirrored.chosen == len(choice.arcs) - 1 - choice.chosen
