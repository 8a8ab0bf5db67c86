"""Interest edges (eq. 2): r and phi by hand, the states at their thresholds, re-evaluation, image neighbours."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration.interest import (
    Interest,
    classify_interest,
    closer_points,
    edge_geometry,
    image_edges,
    reevaluate_interest,
)
from tests.maps.exploration_maps import grid_map


def test_eq2_r_and_phi_by_hand():
    eye = np.zeros(3)
    a, b = np.array([[3.0, 4.0, 0.0]]), np.array([[6.0, 8.0, 0.0]])  # 5 m and 10 m away
    r, phi, a_closer = edge_geometry(a, b, eye, heading=0.0)
    assert r == pytest.approx([0.5]) and phi == pytest.approx([math.atan2(4, 3)]) and a_closer.tolist() == [True]
    r, phi, a_closer = edge_geometry(b, a, eye, heading=math.radians(30))
    assert r == pytest.approx([0.5]) and phi == pytest.approx([math.atan2(4, 3) - math.radians(30)])
    assert a_closer.tolist() == [False]


def test_eq2_interest_states_at_the_thresholds():
    r = np.array([0.5, 0.5, 0.5000001, 0.2, 0.94, 0.95, 0.99])
    phi = np.array([math.pi / 6, math.pi / 6 + 1e-6, 0.0, 0.0, 0.0, 0.0, 1.0])
    assert classify_interest(r, phi).tolist() == [
        Interest.WATCH_NOW,
        Interest.WATCH_LATER,  # a big depth jump off to the side: later
        Interest.WATCH_LATER,
        Interest.WATCH_NOW,
        Interest.WATCH_LATER,
        Interest.NEVER,
        Interest.NEVER,
    ]


def test_reevaluation_follows_the_robot_but_never_stays_never():
    points = np.array(
        [[2.0, 0.0, 1.0], [5.0, 0.0, 1.0], [2.0, 3.0, 1.0], [2.05, 3.0, 1.0], [30.0, 0.0, 1.0], [60.0, 0.0, 1.0]]
    )
    edges = np.array([[0, 1], [2, 3], [4, 5]])
    states = np.array([Interest.WATCH_NOW, Interest.NEVER, Interest.WATCH_NOW], dtype=np.uint8)
    m = grid_map(np.zeros((2, 2)), points=points, edges=edges, interest=states)
    turned = reevaluate_interest(m, np.array([0.0, 0.0, 1.0]), heading=math.pi / 2)
    # edge 0: r = 0.4 but 90 degrees off the heading; edge 2: 30 m away, beyond max_range: not touched
    assert turned.interest.tolist() == [Interest.WATCH_LATER, Interest.NEVER, Interest.WATCH_NOW]
    beside = reevaluate_interest(m, np.array([1.95, 3.0, 1.0]), heading=0.0)  # r = 0.05 / 0.1 = 0.5 ahead
    assert beside.interest[1] == Interest.NEVER
    away = reevaluate_interest(m, np.array([-100.0, 0.0, 1.0]), heading=0.0, max_range=200.0)
    assert away.interest[0] == Interest.NEVER  # r = 102 / 105 > 0.95
    assert reevaluate_interest(away, np.array([0.0, 0.0, 1.0]), 0.0).interest[0] == Interest.NEVER


def test_closer_points_of_all_edges_or_of_some():
    points = np.array([[2.0, 0.0, 1.0], [5.0, 0.0, 1.0], [0.0, 4.0, 1.0], [0.0, 3.0, 1.0]])
    states = np.full(2, Interest.WATCH_NOW, dtype=np.uint8)
    m = grid_map(np.zeros((2, 2)), points=points, edges=np.array([[0, 1], [2, 3]]), interest=states)
    eye = np.array([0.0, 0.0, 1.0])
    assert closer_points(m, eye).tolist() == [[2.0, 0.0, 1.0], [0.0, 3.0, 1.0]]
    assert closer_points(m, eye, np.array([1])).tolist() == [[0.0, 3.0, 1.0]]
    assert closer_points(m, np.array([0.0, 10.0, 1.0])).tolist() == [[2.0, 0.0, 1.0], [0.0, 4.0, 1.0]]


def test_image_neighbours_are_pixels_at_most_max_px_apart():
    uv = np.array([[320.0, 240.0], [325.0, 240.0], [500.0, 240.0], [320.0, 244.0]])
    assert image_edges(uv, 5.0).tolist() == [[0, 1], [0, 3]]
    assert image_edges(uv, 4.9).tolist() == [[0, 3]] and image_edges(uv[:1], 100.0).shape == (0, 2)
