"""The collision monitor's zones and actions on hand-set scans with a hand-set clock.

Footprint: a Pioneer 3-DX's box (ARIA: 0.210 m to the front, 0.301 m to the rear, 0.425 m wide);
stop zone 0.10 m around it, slow-down zone 0.35 m (ratio 0.5), approach with 1 s before collision.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from perception.collision_monitor import CollisionMonitor, MonitorConfig, Zone
from perception.polygons import grow, rectangle
from perception.ranges import Bumper, RangeScan, RangeSensor

FOOTPRINT = rectangle(0.210, 0.301, 0.2125)
STOP = Zone("stop", grow(FOOTPRINT, 0.10), "stop")
SLOW = Zone("slowdown", grow(FOOTPRINT, 0.35), "slowdown", 0.5)
CONFIG = MonitorConfig(FOOTPRINT, (STOP, SLOW), time_before_collision=1.0, source_timeout=1.0, crawl_speed=0.1,
                       crawl_turn_rate=math.radians(20.0))
CENTRE = RangeSensor(0.0, 0.0, 0.0, max_range=10.0, min_range=0.0)  # reads points relative to the centre


def scan_of(*points: tuple[float, float], stamp: float = 0.0, bumpers=(), pressed=()) -> RangeScan:
    """A scan whose only content is ``points`` (as extra points) and a silent sensor."""
    return RangeScan((CENTRE,), np.array([math.inf]), stamp, tuple(bumpers), np.array(pressed, dtype=bool),
                     extra=np.array(points, dtype=float).reshape(-1, 2))


def check(v, w, scan, config=CONFIG, now=0.0):
    return CollisionMonitor(config).check(v, w, scan, now)


def test_approach_scales_the_speed_to_the_gap_over_time_before_collision():
    approach_only = MonitorConfig(FOOTPRINT, (), time_before_collision=1.0)
    # a point 0.5 m ahead of the centre is 0.29 m ahead of the front: at 0.3 m/s, 0.967 s to contact;
    # the command is scaled by 0.967 / 1 s: v = 0.29 m/s (the gap over time_before_collision)
    verdict = check(0.3, 0.0, scan_of((0.5, 0.0)), approach_only)
    assert verdict.v == pytest.approx(0.29) and verdict.w == 0.0
    assert (verdict.state.state, verdict.state.action) == ("slowed", "approach")
    assert verdict.state.nearest_m == pytest.approx(0.29)
    # 0.36 m ahead: gap 0.15 m, v = 0.15 m/s; a slower command that keeps 1 s passes unchanged
    assert check(0.3, 0.0, scan_of((0.36, 0.0)), approach_only).v == pytest.approx(0.15)
    assert check(0.1, 0.0, scan_of((0.36, 0.0)), approach_only).v == pytest.approx(0.1)


def test_a_point_in_the_stop_zone_on_the_path_stops_the_command():
    verdict = check(0.2, 0.1, scan_of((0.28, 0.0)))  # 0.07 m in front of the footprint
    assert (verdict.v, verdict.w) == (0.0, 0.0)
    assert (verdict.state.state, verdict.state.action, verdict.state.zone) == ("stopped", "stop", "stop")
    assert "0.07 m" in verdict.state.reason


def test_backing_away_and_turning_clear_of_it_stay_allowed():
    wall_ahead = scan_of((0.28, 0.0), (0.28, 0.15), (0.28, -0.15))
    backing = check(-0.2, 0.0, wall_ahead)
    assert (backing.v, backing.w, backing.state.state) == (-0.2, 0.0, "clear")
    # turning in place the corners sweep circles of radius up to hypot(0.301, 0.2125) = 0.368 m (the rear
    # ones): (0.30, 0.25), in the stop zone but 0.39 m from the centre, is clear of the sweep
    turning = check(0.0, 0.5, scan_of((0.30, 0.25)))
    assert (turning.v, turning.w, turning.state.state) == (0.0, 0.5, "clear")
    # a point near a corner is in the sweep: the turn stops, either way round
    for w in (0.5, -0.5):
        assert check(0.0, w, scan_of((0.25, 0.1))).state.action == "stop"


def test_a_point_beside_the_path_does_not_slow_the_robot():
    corridor = scan_of((0.0, 0.3), (0.3, 0.3), (-0.3, -0.3))  # walls 0.09 m from each side
    assert check(0.3, 0.0, corridor).state.state == "clear"


def test_the_slowdown_zone_keeps_its_ratio_and_the_most_restrictive_action_wins():
    # 0.29 m ahead of the front: inside the slow-down zone (0.35), outside the stop zone (0.10)
    slowed = check(0.2, 0.0, scan_of((0.5, 0.0)))  # approach alone would keep 0.2 (1.45 s to contact)
    assert slowed.v == pytest.approx(0.1) and slowed.state.action == "slowdown"
    # at 0.5 m/s approach asks for 0.29 / 0.5 = 0.58 and the zone for 0.5: the zone wins
    assert check(0.5, 0.0, scan_of((0.5, 0.0))).v == pytest.approx(0.25)
    # at 0.8 m/s approach asks for 0.29 / 0.8 = 0.3625 < 0.5: approach wins
    faster = check(0.8, 0.0, scan_of((0.5, 0.0)))
    assert faster.v == pytest.approx(0.29) and faster.state.action == "approach"


def test_a_pressed_bumper_stops_motion_towards_it_only():
    bumpers = (Bumper(0.25, 0.0, +1), Bumper(-0.25, 0.0, -1))
    front = scan_of(bumpers=bumpers, pressed=(True, False))
    stopped = check(0.2, 0.3, front)
    assert (stopped.v, stopped.w, stopped.state.action, stopped.state.zone) == (0.0, 0.0, "bumper", "front bumper")
    assert stopped.state.bumped
    assert (check(-0.2, 0.0, front).v, check(0.0, 0.5, front).w) == (-0.2, 0.5)


def test_no_data_limits_the_command_to_a_crawl_and_says_why():
    old = scan_of((3.0, 0.0), stamp=0.0)
    crawl = check(0.3, 0.0, old, now=1.5)
    assert crawl.v == pytest.approx(0.1) and crawl.state.action == "crawl"
    assert "1.50 s old (limit 1 s)" in crawl.state.reason
    # the ratio that keeps both under their limits: v 0.1 / 0.3 and w 0.349 / 0.5 -> 1/3 for both
    both = check(0.3, 0.5, old, now=1.5)
    assert (both.v, both.w) == pytest.approx((0.1, 0.5 / 3))
    assert check(0.0, 1.0, None).w == pytest.approx(math.radians(20.0))
    silent = RangeScan((CENTRE, CENTRE), np.array([math.nan, math.nan]), 0.0)
    assert "none of the 2 range sensors" in check(0.3, 0.0, silent).state.reason
    assert check(0.05, 0.0, None).state.state == "clear"  # already a crawl


def test_a_zero_command_is_clear_and_still_measures_the_nearest_point():
    verdict = check(0.0, 0.0, scan_of((0.26, 0.0)))
    assert verdict.state.state == "clear" and verdict.state.nearest_m == pytest.approx(0.05)


RANGES = st.one_of(st.floats(0.0, 6.0), st.just(math.inf), st.just(math.nan))
SPEEDS = st.floats(-1.5, 1.5, allow_nan=False)


@settings(max_examples=300, deadline=None)
@given(ranges=st.lists(RANGES, min_size=16, max_size=16), v=SPEEDS, w=SPEEDS, age=st.floats(0.0, 2.0),
       pressed=st.lists(st.booleans(), min_size=2, max_size=2))
def test_never_amplified_never_reversed_and_the_arc_is_kept(ranges, v, w, age, pressed):
    ring = tuple(RangeSensor(0.2 * math.cos(a), 0.2 * math.sin(a), a) for a in np.linspace(0, 2 * math.pi, 16,
                                                                                          endpoint=False))
    scan = RangeScan(ring, np.array(ranges), 0.0, (Bumper(0.25, 0, 1), Bumper(-0.25, 0, -1)), np.array(pressed))
    verdict = check(v, w, scan, now=age)
    assert abs(verdict.v) <= abs(v) and abs(verdict.w) <= abs(w)
    assert verdict.v * v >= 0.0 and verdict.w * w >= 0.0
    assert 0.0 <= verdict.state.ratio <= 1.0
    assert (verdict.v, verdict.w) == pytest.approx((v * verdict.state.ratio, w * verdict.state.ratio))


@settings(max_examples=200, deadline=None)
@given(points=st.lists(st.tuples(st.floats(0.22, 4.0), st.floats(-2.0, 2.0)), min_size=1, max_size=20),
       v=st.floats(-1.0, -0.01))
def test_backing_straight_away_from_anything_ahead_is_never_limited(points, v):
    verdict = check(v, 0.0, scan_of(*points))
    assert (verdict.v, verdict.w, verdict.state.state) == (v, 0.0, "clear")


def test_remembered_echoes_are_judged_like_the_scans_own_while_the_scan_is_fresh():
    silent = scan_of()
    monitor = CollisionMonitor(CONFIG)
    remembered = np.array([[0.28, 0.0]])  # 0.07 m in front of the footprint, seen a moment ago
    verdict = monitor.check(0.2, 0.0, silent, 0.0, remembered)
    assert (verdict.v, verdict.state.action) == (0.0, "stop") and verdict.state.nearest_m == pytest.approx(0.07)
    assert monitor.check(0.2, 0.0, silent, 0.0).v == 0.2  # the scan alone: nothing
    stale = monitor.check(0.2, 0.0, silent, 5.0, remembered)  # no fresh data: the crawl decides, not old echoes
    assert stale.state.action == "crawl" and stale.v == pytest.approx(0.1)


def test_approach_allows_for_a_point_closing_by_itself():
    approach_only = MonitorConfig(FOOTPRINT, (), time_before_collision=1.0)
    # a point 0.81 m ahead of the centre is 0.60 m ahead of the front: standing still, at 0.3 m/s
    # contact is 2 s away, and the command passes; walking at the robot at 0.5 m/s it is 0.75 s
    # away, and eq. 3' gives v' = 0.60 m / 1 s - 0.5 m/s = 0.10 m/s (ratio 1/3)
    scan = scan_of((0.81, 0.0))
    assert CollisionMonitor(approach_only).check(0.3, 0.0, scan, 0.0, closing=np.array([0.0])).v == 0.3
    verdict = CollisionMonitor(approach_only).check(0.3, 0.0, scan, 0.0, closing=np.array([0.5]))
    assert verdict.v == pytest.approx(0.10)
    assert verdict.state.action == "approach" and "closing at 0.50 m/s by itself" in verdict.state.reason
    # closing at 0.7 m/s, faster than the gap over the time kept: stopped
    assert CollisionMonitor(approach_only).check(0.3, 0.0, scan, 0.0, closing=np.array([0.7])).v == 0.0
    # turning on the spot towards it is the turn's own business (no speed to scale by u / |v|)
    assert CollisionMonitor(approach_only).check(0.0, 0.5, scan, 0.0, closing=np.array([0.7])).w == 0.5
