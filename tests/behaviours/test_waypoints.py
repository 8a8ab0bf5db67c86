"""DriveWaypoints (behaviours/waypoints.py) on an ideal base, and the flat waypoint list."""

from __future__ import annotations

import math

import pytest
from py_trees.common import Status

from behaviours.testing import BehaviourHarness
from behaviours.waypoints import DriveWaypoints, waypoint_pairs
from drivers.interfaces import STOP
from perception.geometry import Pose2D
from tests.behaviours.test_motion import integrate


def drive(waypoints: list[float], **ports) -> tuple[Status, list[Pose2D], list[float]]:
    """Drive to the end on an ideal base: the final status, every pose and every forward speed."""
    harness = BehaviourHarness(DriveWaypoints(waypoints=waypoints, **ports), blackboard={"/robot/odometry": Pose2D()})
    poses, speeds = [], []

    def step(h: BehaviourHarness) -> None:
        speeds.append(h.read("/robot/command").v)
        integrate(h)
        poses.append(h.read("/robot/odometry"))

    status = harness.tick_until(between=step)
    assert harness.read("/robot/command") == STOP
    return status, poses, speeds


def test_drive_waypoints_passes_every_point_and_stops_at_the_last():
    status, visited, _ = drive([1.0, 0.0, 1.0, 1.0, 0.0, 1.0])
    assert status == Status.SUCCESS
    for x, y in waypoint_pairs([1.0, 0.0, 1.0, 1.0, 0.0, 1.0]):
        assert min(math.hypot(p.x - x, p.y - y) for p in visited) < 0.06
    assert math.hypot(visited[-1].x, visited[-1].y - 1.0) <= 0.05


def test_a_waypoint_straight_on_is_passed_at_full_speed_and_a_bend_is_slowed_for():
    _, poses, speeds = drive([0.5, 0.0, 1.0, 0.0, 1.0, 0.5], speed=0.3)
    passing = min(range(len(poses)), key=lambda i: abs(poses[i].x - 0.5))
    assert speeds[passing] == pytest.approx(0.3)  # (0.5, 0): the route goes on straight, full speed
    turning = next(i for i, p in enumerate(poses) if p.theta > 0.05)  # turns on the spot at (1, 0)
    assert speeds[turning] == 0.0 and speeds[turning - 1] < 0.2  # slowed down before the 90 deg bend
    assert poses[turning].x == pytest.approx(1.0, abs=0.05)


def test_waypoints_come_in_pairs():
    assert waypoint_pairs([1.0, 2.0, 3.0, 4.0]) == [(1.0, 2.0), (3.0, 4.0)]
    with pytest.raises(ValueError, match="pairs"):
        waypoint_pairs([1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="no waypoints"):
        DriveWaypoints(waypoints=[])


def test_each_command_says_how_far_the_robot_goes_before_it_stops():
    # (1, 0) then (2, 0) straight on, then a right-angle bend to (2, 1): from the start the robot
    # stops first at (2, 0), 2 m away; past the bend it stops at the end
    harness = BehaviourHarness(DriveWaypoints(waypoints=[1.0, 0.0, 2.0, 0.0, 2.0, 1.0]),
                               blackboard={"/robot/odometry": Pose2D()})
    harness.tick()
    assert harness.read("/robot/command").reach == pytest.approx(2.0)
    harness.write("/robot/odometry", Pose2D(1.0, 0.0, 0.0))  # at (1, 0): on to the bend
    harness.tick()
    assert harness.read("/robot/command").reach == pytest.approx(1.0)
    harness.write("/robot/odometry", Pose2D(2.0, 0.0, math.pi / 2))  # at the bend, turned
    harness.tick()
    assert harness.read("/robot/command").reach == pytest.approx(1.0)
