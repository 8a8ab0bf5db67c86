"""The Pioneer's body from ARIA's parameter files: footprint, sonar ring, bumper positions."""

from __future__ import annotations

import math

import pytest

from drivers.pioneer_body import BODIES


def test_every_model_has_a_ring_of_sixteen_facing_out():
    for body in BODIES.values():
        sensors = body.sensors()
        assert len(sensors) == 16
        for sensor in sensors:  # each transducer looks away from the centre (within 60 degrees)
            outward = math.atan2(sensor.y, sensor.x)
            assert abs(math.remainder(sensor.heading - outward, 2 * math.pi)) < math.radians(60)


def test_the_p3dx_ring_and_box_are_arias():
    body = BODIES["p3dx"]
    front_left = body.sensors()[3]  # SonarUnit 3 166 27 10
    assert (front_left.x, front_left.y, front_left.heading) == pytest.approx((0.166, 0.027, math.radians(10)))
    assert body.footprint[:, 0].max() == pytest.approx(0.210) and body.footprint[:, 0].min() == pytest.approx(-0.301)
    assert body.footprint[:, 1].max() == pytest.approx(0.2125)


def test_bumpers_sit_where_aria_places_their_hits():
    # ArBumpers: bumper i of 5 at -(i + 1/2) 27 + 67.5 degrees on RobotRadius: 54, 27, 0, -27, -54 (front)
    bumpers = BODIES["p3dx"].bumpers()
    front, rear = bumpers[:5], bumpers[5:]
    angles = [round(math.degrees(math.atan2(b.y, b.x)), 6) for b in front]
    assert angles == [54.0, 27.0, 0.0, -27.0, -54.0]
    assert all(b.facing == 1 for b in front) and all(b.facing == -1 for b in rear)
    assert math.hypot(front[2].x, front[2].y) == pytest.approx(0.25)
    assert (rear[2].x, rear[2].y) == pytest.approx((-0.25, 0.0))


def test_the_p3at_ring_sits_further_forward_with_the_same_headings():
    dx, at = BODIES["p3dx"].sensors(), BODIES["p3at"].sensors(max_range=4.0)
    assert at[3].x == pytest.approx(0.245) and at[3].x > dx[3].x  # SonarUnit 3 245 27 10 of params/p3at.p
    assert [s.heading for s in at] == [s.heading for s in dx]
    assert all(s.max_range == 4.0 for s in at)


def test_the_simulator_puts_the_bumpers_on_its_own_disc():
    bumpers = BODIES["p3dx"].bumpers(0.26)
    assert all(math.hypot(b.x, b.y) == pytest.approx(0.26) for b in bumpers)
    assert (bumpers[2].x, bumpers[2].y) == pytest.approx((0.26, 0.0))
