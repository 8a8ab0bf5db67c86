"""A homing's sidestep judged against hand-set range readings before they start (manual clock).

The disc of the routine's robot (0.28 m) and the clearance (0.10 m) make 0.38 m between the
base's centre and a point straight ahead where a move must end; the disc polygon's edges touch
its circle straight ahead and behind, so the figures below are exact."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.roadmap.homing import MIN_STEP, HomingSettings, Look, TargetHoming, _step_plan
from behaviours.roadmap.room_to_move import straight_reach
from behaviours.roadmap.routine import Failed
from behaviours.roadmap.vision import Comparison
from behaviours.testing import BehaviourHarness
from perception.geometry import Pose2D
from perception.planar import PlanarResult, PlanarStatus
from perception.ranges import RangeScan, RangeSensor

RADIUS = 0.28


def test_a_move_ends_the_clearance_short_of_a_point_in_its_way():
    ahead = np.array([[1.0, 0.0]])
    assert straight_reach(ahead, RADIUS, 0.0, 1.0) == pytest.approx(1.0 - 0.38)
    assert straight_reach(np.array([[-0.8, 0.0]]), RADIUS, math.pi, 0.5) == pytest.approx(0.8 - 0.38)  # backwards
    assert straight_reach(np.array([[0.0, 0.5]]), RADIUS, math.pi / 2, 0.25) == pytest.approx(0.5 - 0.38)  # left


def test_points_beside_the_way_beyond_the_sweep_or_none_hold_nothing():
    beside = np.array([[0.5, 0.30]])  # within the clearance of the disc passing it, never touched
    assert straight_reach(beside, RADIUS, 0.0, 1.0) == math.inf
    far = np.array([[2.0, 0.0]])  # touched after 1.72 m: beyond a 0.25 m move and the monitor's 1 m sweep
    assert straight_reach(far, RADIUS, 0.0, 0.25) == math.inf
    assert straight_reach(far, RADIUS, 0.0, 1.0) == pytest.approx(2.0 - 0.38)  # within 1 m + 1 m: it counts
    assert straight_reach(np.zeros((0, 2)), RADIUS, 0.0, 1.0) == math.inf


def test_a_point_already_within_the_clearance_ahead_leaves_no_room():
    assert straight_reach(np.array([[0.33, 0.0]]), RADIUS, 0.0, 0.25) == 0.0


def sensor_at(heading_deg: float) -> RangeSensor:
    """A transducer at the base's centre, looking ``heading_deg`` off the heading."""
    return RangeSensor(0.0, 0.0, math.radians(heading_deg))


def homing_with_ranges(readings: dict[float, float]) -> TargetHoming:
    """A homing node at the odometry origin, facing +x, that has read the ranges ``{heading deg: m}``
    for one second (the echoes it judges are those of its last second)."""
    node = TargetHoming(target="centre")
    sensors = tuple(sensor_at(h) for h in readings)
    harness = BehaviourHarness(node, blackboard={"/robot/odometry": Pose2D()})
    for _ in range(3):  # no target images: the routine fails at once, the echoes are remembered all the same
        harness.write("/robot/ranges", RangeScan(sensors, np.array(list(readings.values())), harness.clock.now()))
        assert harness.tick() == Status.FAILURE
        harness.clock.advance(0.1)
    return node


def target_ahead() -> Look:
    """A look at a target straight ahead: the sidesteps go left (side 1) or right (-1), forwards."""
    planar = PlanarResult(0.0, np.array([0.0, 1.0]), np.ones(40, dtype=bool), PlanarStatus.OK)
    return Look(Pose2D(), Pose2D(), Comparison(40, planar), 0.0)


SETTINGS = HomingSettings(step=0.25, done_distance=0.08, max_rounds=5, min_inliers=25)


def test_the_sidestep_takes_the_other_side_when_something_is_in_its_way():
    node = homing_with_ranges({90.0: 0.5, -90.0: 3.0})  # a desk 0.5 m to the left, the right open
    assert _step_plan(node, target_ahead(), SETTINGS, 1) == (-1, 0.25)
    assert _step_plan(node, target_ahead(), SETTINGS, -1) == (-1, 0.25)


def test_with_neither_side_free_the_side_with_more_room_is_taken_shortened():
    node = homing_with_ranges({90.0: 0.5, -90.0: 0.55})  # 0.12 m of room to the left, 0.17 m to the right
    side, length = _step_plan(node, target_ahead(), SETTINGS, 1)
    assert side == -1 and length == pytest.approx(0.55 - 0.38)


def test_without_room_on_either_side_homing_fails_rather_than_step():
    node = homing_with_ranges({90.0: 0.45, -90.0: 0.40})  # 0.07 and 0.02 m: less than MIN_STEP
    assert MIN_STEP > 0.07
    with pytest.raises(Failed, match="no room to step sideways"):
        _step_plan(node, target_ahead(), SETTINGS, 1)


def test_without_range_sensors_the_step_is_not_judged():
    node = TargetHoming(target="centre")
    BehaviourHarness(node, blackboard={"/robot/odometry": Pose2D()})
    assert node.sensed() is None
    assert _step_plan(node, target_ahead(), SETTINGS, 1) == (1, 0.25)
