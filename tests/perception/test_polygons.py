"""Polygons of the footprint and the zones: orientation, inside, distance, growing, checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.polygons import as_polygon, contains, disc, distance, grow, is_convex, rectangle, signed_area


def test_a_clockwise_outline_is_turned_counter_clockwise():
    clockwise = [[1.0, 1.0], [1.0, -1.0], [-1.0, -1.0], [-1.0, 1.0]]
    poly = as_polygon(clockwise)
    assert signed_area(poly) == pytest.approx(4.0)


@pytest.mark.parametrize(("vertices", "message"), [
    ([[0.0, 0.0], [1.0, 0.0]], "at least 3"),
    ([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]], "no area"),
    ([[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]], "cross"),  # a bow tie
    ([[0.0, 0.0], [math.inf, 0.0], [0.0, 1.0]], "finite"),
])
def test_bad_outlines_are_refused_with_a_reason(vertices, message):
    with pytest.raises(ValueError, match=message):
        as_polygon(vertices)


def test_inside_and_distance_to_a_box():
    box = rectangle(0.2, 0.3, 0.25)  # x from -0.3 to 0.2, y +-0.25
    points = np.array([[0.0, 0.0], [0.5, 0.0], [0.0, -0.45], [0.5, 0.65]])
    assert contains(box, points).tolist() == [True, False, False, False]
    # inside: 0; 0.3 beyond the front; 0.2 beside; a corner at (0.3, 0.4) away: 0.5
    assert distance(box, points) == pytest.approx([0.0, 0.3, 0.2, 0.5])


def test_a_grown_box_is_the_box_with_every_side_moved_out():
    grown = grow(rectangle(0.2, 0.3, 0.25), 0.1)
    assert sorted(map(tuple, np.round(grown, 9))) == sorted(map(tuple, rectangle(0.3, 0.4, 0.35)))


def test_the_disc_polygon_contains_its_circle_and_touches_it():
    poly = disc(0.26, sides=16)
    angles = np.linspace(0.0, 2.0 * math.pi, 90, endpoint=False)
    circle = 0.2599 * np.column_stack((np.cos(angles), np.sin(angles)))
    assert contains(poly, circle).all() and is_convex(poly)
    assert distance(poly, np.array([[0.36, 0.0]])).min() == pytest.approx(0.1, abs=0.011)


def test_convexity():
    assert is_convex(rectangle(1.0, 1.0, 1.0))
    notched = as_polygon([[0, 0], [2, 0], [2, 2], [1, 1], [0, 2]])
    assert not is_convex(notched)
