"""delta_t (eq. 1 as written): values worked out by hand, zero for the same view, rotation-invariant,
growing with displacement, bounded for a wild landmark."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.similarity import (
    DEFAULT_SCALE,
    angle_form_threshold_angle,
    angle_of_cost,
    bearing_angles,
    cosine_distances,
    cost_of_angle,
    default_threshold,
    delta_t,
    eq1_costs,
    scaled,
)
from perception.synthetic import make_scene


def turned(degrees: float) -> np.ndarray:
    """The bearing straight ahead turned by ``degrees`` about z."""
    a = math.radians(degrees)
    return np.array([[math.cos(a), math.sin(a), 0.0]])


def test_eq1_costs_worked_out_by_hand():
    # b = 1 - cos 2 deg = 1 - 0.99939083 = 6.09173e-4, 2 b^2 = 7.421836e-7
    assert pytest.approx(6.09173e-4, rel=1e-5) == DEFAULT_SCALE
    # 3 deg: x = 1 - cos 3 deg = 1.3704652e-3, x / b = 2.249714, (x / b)^2 = 5.061213,
    # sqrt(6.061213) - 1 = 1.461953, times 2 b^2: 1.085038e-6 (the default threshold)
    assert cost_of_angle(math.radians(3.0)) == pytest.approx(1.085038e-6, rel=1e-5)
    assert default_threshold() == pytest.approx(1.085038e-6, rel=1e-5)
    # 1 deg: x = 1.523048e-4, x / b = 0.250019, sqrt(1.0625095) - 1 = 0.030781, times 2 b^2: 2.28452e-8,
    # close to theta^4 / 4 = 0.01745329^4 / 4 = 2.3199e-8 (quartic near 0)
    assert cost_of_angle(math.radians(1.0)) == pytest.approx(2.28452e-8, rel=1e-4)
    # 180 deg: x = 2, x / b = 3283.14, sqrt(1 + 3283.14^2) - 1 = 3282.14, times 2 b^2: 2.43594e-3 (about 4 b)
    assert cost_of_angle(math.pi) == pytest.approx(2.43594e-3, rel=1e-4)
    # the mean over two landmarks, one unmoved and one turned 3 deg: 1.085038e-6 / 2
    ref = np.vstack((turned(0.0), turned(0.0)))
    assert delta_t(ref, np.vstack((turned(0.0), turned(3.0)))) == pytest.approx(5.42519e-7, rel=1e-5)


def test_the_angle_form_weighs_a_small_change_900_times_more():
    # the earlier form at 3 deg: delta = 2 deg = 0.0349066 rad, theta / delta = 1.5,
    # delta^2 (sqrt(1 + 2.25) - 1) = 1.218470e-3 * 0.802776 = 9.78158e-4: 901.5 times eq. 1's 1.085038e-6
    # its 1e-3 rad^2: 0.0349066 * sqrt((1 + 1e-3 / 1.218470e-3)^2 - 1) = 0.0349066 * 1.521483 = 0.0531097 rad
    assert math.degrees(angle_form_threshold_angle(1e-3)) == pytest.approx(3.04300, rel=1e-4)


def test_the_cost_of_an_angle_is_inverted_and_fractions_are_of_the_angle():
    for degrees in (0.1, 1.0, 3.0, 20.0, 179.0):
        assert math.degrees(angle_of_cost(cost_of_angle(math.radians(degrees)))) == pytest.approx(degrees, rel=1e-6)
    assert angle_of_cost(1.0) == math.pi  # no change costs that much
    # 0.45 of the 3 deg threshold is 1.35 deg: x = 2.775698e-4, x / b = 0.455650, sqrt(1.207617) - 1 = 0.098916,
    # times 2 b^2: 7.3414e-8 (0.0677 of the threshold: a quarter of the cost would be 0.7 of the angle)
    assert scaled(default_threshold(), 0.45) == pytest.approx(7.3414e-8, rel=1e-4)


def test_cosine_distances_are_exact_near_zero():
    tiny = 1e-9  # 1 - cos(1e-9) = 5e-19, lost to rounding as 1 - l^T l'
    assert cosine_distances(turned(0.0), turned(math.degrees(tiny)))[0] == pytest.approx(5e-19, rel=1e-6)
    assert eq1_costs(np.array([0.0]))[0] == 0.0


def test_same_view_is_zero_and_turning_on_the_spot_is_compensated():
    scene = make_scene(0, yaw_deg=40.0, position=(0.0, 0.0, 0.0))
    assert delta_t(scene.ref, scene.ref) == 0.0
    # uncompensated, every bearing moves by up to 40 deg: hundreds of 3 deg thresholds
    assert delta_t(scene.ref, scene.cur) > 100 * default_threshold()
    assert delta_t(scene.ref, scene.cur, rotation=scene.rotation) == pytest.approx(0.0, abs=1e-20)


def test_grows_monotonically_with_distance_from_the_viewframe():
    values = [
        delta_t(s.ref, s.cur, rotation=s.rotation)
        for s in (make_scene(1, n_far=50, yaw_deg=0.0, position=(d, 0.0, 0.0)) for d in (0.05, 0.2, 0.5, 1.0))
    ]
    assert all(a < b for a, b in zip(values, values[1:], strict=False))


def test_a_wild_landmark_costs_at_most_about_4b():
    ref = np.tile([1.0, 0.0, 0.0], (10, 1))
    small = np.tile(turned(1.0), (10, 1))
    one_wild = small.copy()
    one_wild[0] = [-1.0, 0.0, 0.0]  # pi away
    added = delta_t(ref, one_wild) - delta_t(ref, small)
    assert 0 < added <= 4 * DEFAULT_SCALE / 10


def test_nothing_tracked_is_infinitely_dissimilar():
    assert delta_t(np.zeros((0, 3)), np.zeros((0, 3))) == float("inf")


def test_bearing_angles_are_accurate_near_zero_and_pi():
    a = np.array([[1.0, 0, 0], [1.0, 0, 0]])
    b = np.array([[np.cos(1e-9), np.sin(1e-9), 0], [-1.0, 0, 0]])
    assert bearing_angles(a, b) == pytest.approx([1e-9, np.pi], rel=1e-6)
