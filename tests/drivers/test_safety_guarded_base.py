"""The guarded base: every drive() passes the monitor; stop() and the rest go straight through."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drivers.fake import FakeBase
from drivers.pioneer_body import BODIES
from drivers.safety.guarded_base import GuardedBase
from drivers.safety.settings import SafetySettings, monitor_config
from perception.collision_monitor import CollisionMonitor
from perception.geometry import Pose2D
from perception.ranges import RangeScan, RangeSensor


class Ranges:
    """A range source that returns what the test set."""

    def __init__(self, scan: RangeScan | None) -> None:
        self.scan = scan

    def read(self) -> RangeScan | None:
        return self.scan

    def close(self) -> None:
        pass


def guarded(scan: RangeScan | None, *, ranges: bool = True, now: float = 0.0) -> tuple[GuardedBase, FakeBase]:
    base = FakeBase()
    monitor = CollisionMonitor(monitor_config(None, BODIES["p3dx"].footprint))
    return GuardedBase(base, monitor, Ranges(scan) if ranges else None, lambda: now), base


WALL_AHEAD = RangeScan((RangeSensor(0.2, 0.0, 0.0),), np.array([0.08]), 0.0)  # 0.07 m past the front


def test_a_command_into_the_stop_zone_reaches_the_base_as_a_stop():
    guard, base = guarded(WALL_AHEAD)
    guard.drive(0.3, 0.0)
    guard.drive(-0.2, 0.0)
    assert base.commands == [(0.0, 0.0), (-0.2, 0.0)]
    assert guard.state.state == "clear" and guard.log.safety_stops == 1
    assert guard.log.events[0].action == "stop"


def test_without_a_range_source_commands_pass_and_the_log_says_so():
    guard, base = guarded(None, ranges=False)
    guard.drive(0.3, 0.1)
    assert base.commands == [(0.3, 0.1)] and guard.log.summary()["sources"] == "none"
    assert guard.state.reason == "no range sensors"


def test_a_source_without_a_scan_makes_the_robot_crawl():
    guard, base = guarded(None)
    guard.drive(0.4, 0.0)
    assert base.commands == [(0.1, 0.0)] and guard.state.action == "crawl"


def test_stop_and_the_drivers_extras_go_straight_through():
    guard, base = guarded(WALL_AHEAD)
    base.is_stalled = True
    guard.stop()
    assert base.commands == [(0.0, 0.0)] and guard.stalled() and guard.odometry() is base.pose
    assert guard.closed is False  # FakeBase's own attribute, read through the guard
    guard.close()
    assert base.closed


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


FRONT = RangeSensor(0.2, 0.0, 0.0)  # a transducer at the front, looking ahead
REAR = RangeSensor(-0.2, 0.0, math.pi)  # one looking back, hearing nothing


def ring(front: float, stamp: float) -> RangeScan:
    return RangeScan((FRONT, REAR), np.array([front, np.inf]), stamp)


def remembering(memory: float) -> tuple[GuardedBase, FakeBase, Ranges, Clock]:
    base, ranges, clock = FakeBase(), Ranges(None), Clock()
    monitor = CollisionMonitor(monitor_config(SafetySettings(memory=memory), BODIES["p3dx"].footprint))
    return GuardedBase(base, monitor, ranges, clock), base, ranges, clock


def test_an_echo_turned_into_the_blind_gap_beside_the_robot_still_stops_an_arc_into_it():
    for memory, expected in ((1.0, (0.0, 0.0)), (0.0, (0.2, -0.8))):
        guard, base, ranges, clock = remembering(memory)
        # t = 0: an echo 0.1 m ahead of the front transducer, at (0.3, 0) (odometry = base frame)
        ranges.scan = ring(0.1, 0.0)
        guard.drive(0.0, 0.0)
        # t = 0.5 s: turned +60 deg on the spot; the echo now lies at (0.15, -0.26), 90 deg right of
        # the front transducer, outside every cone, 0.047 m beside the P3-DX's box (half-width
        # 0.2125 m): in the stop zone, and an arc to the right (0.25 m radius) runs the front right
        # corner into it
        clock.now, base.pose = 0.5, Pose2D(0.0, 0.0, math.radians(60.0))
        ranges.scan = ring(np.inf, 0.5)
        guard.drive(0.2, -0.8)
        assert base.commands[-1] == expected  # memory 0: the newest scan alone, nothing there


def test_where_a_transducer_looks_now_its_reading_rules_not_the_memory():
    guard, base, ranges, clock = remembering(1.0)
    # t = 0: an echo 0.6 m ahead of the centre; t = 0.5 s, 0.3 m on: the front transducer looks
    # there and hears nothing (someone walked on), so the remembered echo does not count
    ranges.scan = ring(0.4, 0.0)
    guard.drive(0.3, 0.0)
    clock.now, base.pose = 0.5, Pose2D(0.3, 0.0, 0.0)
    ranges.scan = ring(np.inf, 0.5)
    guard.drive(0.3, 0.0)
    assert base.commands[-1] == (0.3, 0.0)


def test_an_echo_older_than_the_memory_is_forgotten():
    guard, base, ranges, clock = remembering(1.0)
    ranges.scan = ring(0.1, 0.0)
    guard.drive(0.0, 0.0)
    clock.now, base.pose = 1.5, Pose2D(0.0, 0.0, math.radians(60.0))  # as above, but 1.5 s later
    ranges.scan = ring(np.inf, 1.5)
    guard.drive(0.2, -0.8)
    assert base.commands[-1] == (0.2, -0.8)


def test_an_echo_closing_by_itself_is_judged_where_it_is_now_and_the_approach_allows_for_it():
    # the base stands; the transducer 0.2 m ahead of its centre reads 1.5 m, then 1.2 m 0.32 s later:
    # 0.9375 m/s of closing (perception.closing). At 0.52 s, no new firing: the echo is 0.9375 x 0.2 s
    # nearer, 1.0125 m from the transducer, 1.0025 m from the P3-DX's front (0.21 m); eq. 3' gives
    # v' = 1.0025 m / 1 s - 0.9375 m/s = 0.065 m/s. Judged where the ring heard it, 0.3 m/s would pass
    ahead = (RangeSensor(0.2, 0.0, 0.0),)
    scans = [RangeScan(ahead, np.array([1.5]), 0.0, fired=np.array([0.0])),
             RangeScan(ahead, np.array([1.2]), 0.32, fired=np.array([0.32])),
             RangeScan(ahead, np.array([1.2]), 0.52, fired=np.array([0.32]))]
    for closing, expected in ((True, 0.065), (False, 0.3)):
        base, ranges = FakeBase(), Ranges(None)
        config = monitor_config(SafetySettings(closing=closing), BODIES["p3dx"].footprint)
        guard = GuardedBase(base, CollisionMonitor(config), ranges, lambda r=ranges: r.scan.stamp)
        for scan, v in zip(scans, (0.0, 0.0, 0.3), strict=True):
            ranges.scan = scan
            guard.drive(v, 0.0)
        assert base.commands[-1][0] == pytest.approx(expected, abs=1e-3), closing
        assert ("closing at 0.94 m/s by itself" in guard.state.reason) == closing
