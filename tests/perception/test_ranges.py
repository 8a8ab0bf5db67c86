"""Range readings: echoes placed along each sensor's axis in the base frame, bumpers by the side they face."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.ranges import Bumper, RangeScan, RangeSensor


def test_echoes_lie_on_each_sensors_axis_and_silent_sensors_give_no_point():
    front = RangeSensor(x=0.1, y=0.0, heading=0.0)
    left = RangeSensor(x=0.0, y=0.1, heading=math.pi / 2)
    rear = RangeSensor(x=-0.2, y=0.0, heading=math.pi)
    scan = RangeScan((front, left, rear), np.array([1.0, 0.5, np.inf]), stamp=2.0)
    # front: 0.1 + 1.0 along +x; left: 0.1 + 0.5 along +y; rear: no echo
    assert scan.points() == pytest.approx(np.array([[1.1, 0.0], [0.0, 0.6]]))


def test_points_from_other_sources_are_added():
    sensor = RangeSensor(x=0.0, y=0.0, heading=0.0)
    scan = RangeScan((sensor,), np.array([np.nan]), stamp=0.0, extra=np.array([[2.0, -1.0]]))
    assert scan.points() == pytest.approx(np.array([[2.0, -1.0]]))


def test_bumpers_by_the_side_they_face():
    bumpers = (Bumper(0.25, 0.1, +1), Bumper(0.25, -0.1, +1), Bumper(-0.25, 0.0, -1))
    scan = RangeScan((), np.zeros(0), stamp=0.0, bumpers=bumpers, pressed=np.array([False, True, False]))
    assert scan.bumped(+1) and not scan.bumped(-1)


def test_a_reading_for_every_sensor_and_bumper():
    with pytest.raises(ValueError, match="2 ranges for 1 sensors"):
        RangeScan((RangeSensor(0.0, 0.0, 0.0),), np.zeros(2), stamp=0.0)


def test_a_sensor_with_a_reading_covers_its_cone_and_the_rest_is_blind():
    front = RangeSensor(0.2, 0.0, 0.0, fov=math.radians(30.0), max_range=5.0)
    side = RangeSensor(0.0, 0.2, math.pi / 2, fov=math.radians(30.0), max_range=5.0)
    points = np.array([
        [1.2, 0.0],    # 1.0 m along the front axis -> covered
        [0.7, 0.2],    # 21.8 deg off the front axis (outside its 15 deg half-cone), not in the side cone -> blind
        [0.0, 0.6],    # 0.4 m along the side axis, the side transducer not read yet (nan) -> blind
        [6.0, 0.0],    # beyond the front's 5 m -> blind
    ])
    scan = RangeScan((front, side), np.array([0.5, np.nan]), 0.0)
    assert scan.covers(points).tolist() == [True, False, False, False]
    read = RangeScan((front, side), np.array([np.inf, 2.0]), 0.0)
    assert read.covers(points).tolist() == [True, False, True, False]
