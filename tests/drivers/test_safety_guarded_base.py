"""The guarded base: every drive() passes the monitor; stop() and the rest go straight through."""

from __future__ import annotations

import numpy as np

from drivers.fake import FakeBase
from drivers.pioneer_body import BODIES
from drivers.safety.guarded_base import GuardedBase
from drivers.safety.settings import monitor_config
from perception.collision_monitor import CollisionMonitor
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
