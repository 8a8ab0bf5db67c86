"""delta_t (eq. 1): zero for the same view, rotation-invariant, growing with displacement, robust."""

from __future__ import annotations

import numpy as np
import pytest

from perception.similarity import bearing_angles, delta_t
from perception.synthetic import make_scene


def test_same_view_is_zero_and_turning_on_the_spot_is_compensated():
    scene = make_scene(0, yaw_deg=40.0, position=(0.0, 0.0, 0.0))
    assert delta_t(scene.ref, scene.ref) == 0.0
    # uncompensated, the 40 deg turn costs about delta * angle = 0.035 * 0.6 rad^2
    assert delta_t(scene.ref, scene.cur) > 0.015
    assert delta_t(scene.ref, scene.cur, rotation=scene.rotation) == pytest.approx(0.0, abs=1e-20)


def test_grows_monotonically_with_distance_from_the_viewframe():
    values = [
        delta_t(s.ref, s.cur, rotation=s.rotation)
        for s in (make_scene(1, n_far=50, yaw_deg=0.0, position=(d, 0.0, 0.0)) for d in (0.05, 0.2, 0.5, 1.0))
    ]
    assert all(a < b for a, b in zip(values, values[1:], strict=False))


def test_pseudo_huber_is_linear_for_large_angles_so_outliers_weigh_little():
    ref = np.tile([1.0, 0.0, 0.0], (10, 1))
    small = np.tile([np.cos(0.01), np.sin(0.01), 0.0], (10, 1))
    one_wild = small.copy()
    one_wild[0] = [-1.0, 0.0, 0.0]  # pi away
    quadratic_cost = (np.pi**2) / 2 / 10  # what a least-squares cost would add
    added = delta_t(ref, one_wild) - delta_t(ref, small)
    assert 0 < added < quadratic_cost / 10


def test_nothing_tracked_is_infinitely_dissimilar():
    assert delta_t(np.zeros((0, 3)), np.zeros((0, 3))) == float("inf")


def test_bearing_angles_are_accurate_near_zero_and_pi():
    a = np.array([[1.0, 0, 0], [1.0, 0, 0]])
    b = np.array([[np.cos(1e-9), np.sin(1e-9), 0], [-1.0, 0, 0]])
    assert bearing_angles(a, b) == pytest.approx([1e-9, np.pi], rel=1e-6)
