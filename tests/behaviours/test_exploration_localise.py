"""LocalisePose alone: hand-set odometry and landmark bearings, the corrected pose read back."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.exploration.localise import LocalisePose
from behaviours.telemetry import report_sections
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
    section = report_sections(harness.behaviour)["localisation"]
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


def test_the_report_and_the_drawings_of_the_corrected_pose():
    node = LocalisePose()
    assert report_sections(node) == {"localisation": {"landmarks": 0, "corrections": 0}}
    assert list(node.drawings()) == []
    harness = BehaviourHarness(node, blackboard={"/robot/odometry": Pose2D()})
    for i in range(30):  # 1.45 m straight towards landmark 1 at (4, 0), the others off to the sides
        pose = Pose2D(0.05 * i, 0.0, 0.0)
        harness.write("/robot/odometry", pose)
        harness.write("/perception/frames", {"landmarks": seen_from(pose, 0.1 * i)})
        harness.tick()
        harness.clock.advance(0.1)
    section = report_sections(node)["localisation"]
    assert list(section) == ["landmarks", "corrections", "position_sigma_m", "heading_sigma_deg",
                             "max_position_sigma_m", "max_heading_sigma_deg", "correction_m", "final_pose"]
    assert section["final_pose"] == pytest.approx({"x": 1.45, "y": 0.0, "theta": 0.0}, abs=0.01)
    pose_drawing, landmarks = node.drawings()
    assert pose_drawing.entity == "odometry_frame/localisation/pose"
    assert pose_drawing.positions[0] == pytest.approx([1.45, 0.0], abs=0.01)
    # only landmarks whose range is known (within 0.5 m) are drawn: not the one straight ahead
    assert landmarks.entity == "odometry_frame/localisation/landmarks" and landmarks.labels == ("2", "3", "4")
    assert landmarks.positions == pytest.approx(LANDMARKS[1:], abs=0.05)
