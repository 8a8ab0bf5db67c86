"""LocalisePose alone: hand-set odometry and landmark bearings, the corrected pose read back."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.localise import LocalisePose
from behaviours.testing import BehaviourHarness
from perception.frame import LandmarkBearings
from perception.geometry import Pose2D, wrap_angle

LANDMARKS = np.array([[4.0, 0.0], [0.0, 5.0], [-3.0, -3.0], [3.0, 3.0]])


def seen_from(true: Pose2D, stamp: float) -> LandmarkBearings:
    a = np.arctan2(LANDMARKS[:, 1] - true.y, LANDMARKS[:, 0] - true.x) - true.theta
    b = np.column_stack((np.cos(a), np.sin(a), np.zeros(len(a))))
    return LandmarkBearings(np.arange(1, len(a) + 1), b, stamp, "landmarks")


def test_waits_for_odometry_and_starts_where_it_is():
    harness = BehaviourHarness(LocalisePose())
    assert harness.tick() == Status.SUCCESS and harness.read("/robot/pose") is None
    harness.write("/robot/odometry", Pose2D(1.0, 2.0, 0.5))
    harness.tick()
    assert harness.read("/robot/pose") == Pose2D(1.0, 2.0, 0.5)


def test_without_the_sensor_the_pose_is_odometry():
    harness = BehaviourHarness(LocalisePose(), blackboard={"/robot/odometry": Pose2D()})
    harness.tick()
    harness.write("/robot/odometry", Pose2D(0.5, 0.1, 0.2))
    harness.tick()
    pose = harness.read("/robot/pose")
    assert (pose.x, pose.y, pose.theta) == pytest.approx((0.5, 0.1, 0.2))


def test_a_turn_that_odometry_undercounts_is_corrected():
    """Odometry counts 90 % of a turn on the spot (a mis-calibrated axle); the landmarks do not lie."""
    harness = BehaviourHarness(LocalisePose(), blackboard={"/robot/odometry": Pose2D()})
    true = 0.0
    for i in range(40):
        harness.write("/perception/frames", {"landmarks": seen_from(Pose2D(0.0, 0.0, true), 0.1 * i)})
        harness.tick()
        true += math.radians(4.0)
        harness.write("/robot/odometry", Pose2D(0.0, 0.0, wrap_angle(0.9 * true)))
        harness.clock.advance(0.1)
    harness.write("/perception/frames", {"landmarks": seen_from(Pose2D(0.0, 0.0, true), 4.0)})
    harness.tick()
    error = math.degrees(abs(wrap_angle(harness.read("/robot/pose").theta - true)))
    assert error < 2.0 < math.degrees(abs(wrap_angle(0.9 * true - true)))  # odometry: 16 degrees off
    section = harness.behaviour.report_sections()["localisation"]
    assert section["landmarks"] == 4 and section["corrections"] == 41


def test_a_frame_is_used_once():
    harness = BehaviourHarness(LocalisePose(), blackboard={"/robot/odometry": Pose2D()})
    frame = seen_from(Pose2D(), 0.0)
    harness.write("/perception/frames", {"landmarks": frame})
    harness.tick()
    harness.tick()
    assert harness.behaviour.corrections == 1


def test_the_mount_is_checked():
    with pytest.raises(ValueError, match="mount"):
        LocalisePose(mount=[0.0, 0.0])
