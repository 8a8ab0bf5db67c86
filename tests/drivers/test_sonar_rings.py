"""The Pioneer rings: ARIA's SonarUnit tables in metres and radians, and the bumper segments."""

from __future__ import annotations

import math

import pytest

from drivers.sonar_rings import bumper_ring, sonar_ring


def test_the_p3dx_ring_is_arias_table_in_metres_and_radians():
    ring = sonar_ring("p3dx", max_range=4.0)
    assert len(ring) == 16
    # SonarUnit 3 166 27 10 and SonarUnit 12 -255 27 170 of params/p3dx.p
    assert (ring[3].x, ring[3].y, ring[3].heading) == pytest.approx((0.166, 0.027, math.radians(10)))
    assert (ring[12].x, ring[12].y, ring[12].heading) == pytest.approx((-0.255, 0.027, math.radians(170)))
    assert all(s.max_range == 4.0 and s.fov == pytest.approx(math.radians(30)) for s in ring)
    # the front ring (0-7) looks forward or sideways, the rear ring (8-15) backward or sideways
    assert all(math.cos(s.heading) >= -1e-12 for s in ring[:8]) and all(math.cos(s.heading) <= 1e-12 for s in ring[8:])


def test_the_p3at_ring_sits_further_forward():
    dx, at = sonar_ring("p3dx"), sonar_ring("p3at")
    assert at[3].x == pytest.approx(0.245) and at[3].x > dx[3].x
    assert [s.heading for s in at] == [s.heading for s in dx]


def test_an_unknown_model_is_refused():
    with pytest.raises(ValueError, match="no sonar ring for 'p4'"):
        sonar_ring("p4")


def test_five_front_and_five_rear_bumpers_on_the_disc():
    bumpers = bumper_ring(0.26)
    assert [b.facing for b in bumpers] == [1] * 5 + [-1] * 5
    assert all(math.hypot(b.x, b.y) == pytest.approx(0.26) for b in bumpers)
    assert (bumpers[2].x, bumpers[2].y) == pytest.approx((0.26, 0.0))  # straight ahead
    assert (bumpers[7].x, bumpers[7].y) == pytest.approx((-0.26, 0.0))  # straight behind
