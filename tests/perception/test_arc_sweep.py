"""The time until a footprint following a command's arc touches a point, against hand-worked values."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from perception.arc_sweep import contact_times
from perception.polygons import rectangle

SQUARE = rectangle(0.5, 0.5, 0.5)  # 1 m square about the centre of rotation


def test_straight_ahead_the_gap_over_the_speed():
    # a point 1.0 ahead, 0.2 left: the front edge (x = 0.5) meets it after 0.5 m, at 0.25 m/s: 2 s
    assert contact_times(SQUARE, np.array([[1.0, 0.2]]), 0.25, 0.0) == pytest.approx([2.0])
    # backing away from it, or a point beside the path: never
    assert contact_times(SQUARE, np.array([[1.0, 0.2]]), -0.25, 0.0) == [math.inf]
    assert contact_times(SQUARE, np.array([[1.0, 0.7]]), 0.25, 0.0) == [math.inf]


def test_turning_in_place_the_corner_sweeps_the_point():
    # a point 0.6 m ahead: turning counter-clockwise it comes round clockwise (seen from the base)
    # and meets the side x = 0.5 where cos(phi) = 0.5 / 0.6: phi = acos(5/6) = 0.585686 rad, at 1 rad/s
    assert contact_times(SQUARE, np.array([[0.6, 0.0]]), 0.0, 1.0) == pytest.approx([0.585686], abs=1e-6)
    assert contact_times(SQUARE, np.array([[0.6, 0.0]]), 0.0, -2.0) == pytest.approx([0.292843], abs=1e-6)
    # farther than the corners (0.707 m): the sweep is clear
    assert contact_times(SQUARE, np.array([[0.75, 0.0]]), 0.0, 1.0) == [math.inf]


def test_on_an_arc_the_point_turns_about_the_centre_of_rotation():
    # v = w = 0.5: radius 1, centre (0, 1); the point (1, 1) is 1 m from it and turns clockwise
    # about it until it meets the side x = 0.1 of a 0.2 m square: at pi/2 - asin(0.1) = 1.470629 rad,
    # 2.941258 s at 0.5 rad/s
    small = rectangle(0.1, 0.1, 0.1)
    assert contact_times(small, np.array([[1.0, 1.0]]), 0.5, 0.5) == pytest.approx([2.941258], abs=1e-6)


def test_a_point_inside_counts_when_the_command_goes_its_way():
    inside = np.array([[0.4, 0.0], [-0.4, 0.0]])
    assert contact_times(SQUARE, inside, 0.2, 0.0).tolist() == [0.0, math.inf]
    assert contact_times(SQUARE, inside, -0.2, 0.0).tolist() == [math.inf, 0.0]
    assert contact_times(SQUARE, inside, 0.0, 1.0).tolist() == [math.inf, math.inf]


def test_no_motion_no_contact():
    assert contact_times(SQUARE, np.array([[0.6, 0.0]]), 0.0, 0.0) == [math.inf]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a turn too slow to sweep is no motion, not a division by zero
        assert contact_times(SQUARE, np.array([[0.6, 0.0], [0.5, 0.0]]), 0.0, 1e-12).tolist() == [math.inf] * 2
