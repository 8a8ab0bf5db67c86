"""How fast an echo closes on the robot by itself (eq. C1-C3), on hand-set readings and poses.

One transducer on the robot's centre line, 0.2 m ahead of its centre, looking straight ahead;
its firings are 0.32 s apart, as a Pioneer 3's ring fires each transducer.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.closing import ClosingEchoes
from perception.geometry import Pose2D
from perception.ranges import RangeScan, RangeSensor

AHEAD = RangeSensor(0.2, 0.0, 0.0, max_range=5.0, min_range=0.1)
HOME = Pose2D(0.0, 0.0, 0.0)


def reading(metres: float, fired: float, stamp: float | None = None) -> RangeScan:
    return RangeScan((AHEAD,), np.array([metres]), fired if stamp is None else stamp, fired=np.array([fired]))


def closing_after(first: float, second: float, *, pose: Pose2D = HOME, interval: float = 0.32) -> float:
    echoes = ClosingEchoes().added(reading(first, 0.0), HOME).added(reading(second, interval), pose)
    return float(echoes.speeds[0])


def test_a_reading_that_comes_nearer_with_the_robot_standing_closes_at_the_range_rate():
    # 1.0 m then 0.7 m, 0.32 s apart: r_still = 1.0 (eq. C1), u = 0.3 / 0.32 = 0.9375 m/s (eq. C2)
    assert closing_after(1.0, 0.7) == pytest.approx(0.9375)


def test_the_robots_own_travel_is_not_counted():
    # the robot drove 0.1 m straight at it: a standing thing would read 0.9 m; 0.7 m is 0.2 m nearer
    assert closing_after(1.0, 0.7, pose=Pose2D(0.1, 0.0, 0.0)) == pytest.approx(0.2 / 0.32)
    # a wall the robot drives at, read 0.1 m nearer: standing still
    assert closing_after(1.0, 0.9, pose=Pose2D(0.1, 0.0, 0.0)) == 0.0


def test_noise_a_receding_thing_a_new_thing_and_a_turned_cone_are_not_closing():
    assert closing_after(1.0, 0.95) == 0.0  # 0.156 m/s: below MIN_CLOSING (noise)
    assert closing_after(0.7, 1.0) == 0.0  # receding
    assert closing_after(3.0, 0.8) == 0.0  # 6.9 m/s: something else came into the cone
    assert closing_after(1.0, 0.7, pose=Pose2D(0.0, 0.0, math.radians(10.0))) == 0.0  # the cone looks elsewhere
    assert closing_after(1.0, 0.7, interval=0.8) == 0.0  # not successive firings
    assert closing_after(math.inf, 0.7) == 0.0  # no echo before


def test_a_closing_echo_is_judged_where_it_is_now_until_the_transducer_fires_again():
    echoes = ClosingEchoes().added(reading(1.0, 0.0), HOME).added(reading(0.7, 0.32), HOME)
    # read again at 0.52 s with no new firing: 0.2 s old, so 0.9375 x 0.2 = 0.1875 m nearer (eq. C3)
    later = reading(0.7, 0.32, stamp=0.52)
    echoes = echoes.added(later, HOME)
    assert echoes.speeds[0] == pytest.approx(0.9375)  # a repeated reading is no new firing
    judged, speeds = echoes.judged(later, 0.52)
    assert judged.ranges[0] == pytest.approx(0.5125)
    np.testing.assert_allclose(speeds, [0.9375])
    # never nearer than the transducer can read
    assert echoes.judged(reading(0.7, 0.32, stamp=2.0), 2.0)[0].ranges[0] == AHEAD.min_range


def test_a_standing_thing_is_judged_where_it_was_heard():
    echoes = ClosingEchoes().added(reading(1.0, 0.0), HOME).added(reading(1.0, 0.32), HOME)
    judged, speeds = echoes.judged(reading(1.0, 0.32, stamp=0.6), 0.6)
    assert judged.ranges[0] == 1.0 and speeds[0] == 0.0


def test_a_sensor_carried_away_from_where_it_looks_is_not_judged():
    # a rear transducer while the robot drives 0.1 m forwards, reading a wall at a grazing angle at the
    # same 1.0 m: the first echo's arc (+-15 deg) would now be 1.0969 m away at least, sqrt(1.01 + 0.2
    # cos 15 deg), so eq. C2 gives 0.30 m/s; but the sensor moved away from where it looks: speed 0
    behind = RangeSensor(-0.2, 0.0, math.pi, max_range=5.0, min_range=0.1)
    first = RangeScan((behind,), np.array([1.0]), 0.0, fired=np.array([0.0]))
    second = RangeScan((behind,), np.array([1.0]), 0.32, fired=np.array([0.32]))
    echoes = ClosingEchoes().added(first, HOME).added(second, Pose2D(0.1, 0.0, 0.0))
    assert echoes.speeds[0] == 0.0
    # standing, the same sensor hears a thing coming at it from behind: 1.0 then 0.8 m, 0.625 m/s
    second = RangeScan((behind,), np.array([0.8]), 0.32, fired=np.array([0.32]))
    assert ClosingEchoes().added(first, HOME).added(second, HOME).speeds[0] == pytest.approx(0.625)
