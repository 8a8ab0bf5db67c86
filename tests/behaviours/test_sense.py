"""The data-gathering nodes (behaviours/sense.py): driver readings onto the blackboard, on fake drivers."""

from __future__ import annotations

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.base import NotSetUp
from behaviours.sense import SENSE_NODES, GrabFrames, ReadOdometry, ReadPanTilt
from behaviours.testing import BehaviourHarness
from drivers.fake import fake_robot
from drivers.interfaces import PanTiltState
from perception.frame import Frame
from perception.geometry import Pose2D


def frame(name: str, stamp: float) -> Frame:
    return Frame(image=np.zeros((4, 4), np.uint8), camera=None, stamp=stamp, camera_name=name)


def test_read_odometry_copies_the_pose_and_the_stall_flag():
    robot = fake_robot()
    robot.base.pose = Pose2D(1.0, 2.0, 0.5)
    harness = BehaviourHarness(ReadOdometry(), robot=robot)
    assert harness.tick() == Status.SUCCESS
    assert harness.read("/robot/odometry") == Pose2D(1.0, 2.0, 0.5) and harness.read("/robot/stalled") is False
    robot.base.is_stalled = np.bool_(True)  # a driver may answer with numpy's bool
    harness.tick()
    assert harness.read("/robot/stalled") is True


def test_read_odometry_writes_a_remapped_key():
    harness = BehaviourHarness(ReadOdometry(odometry="{/robot/wheel_odometry}"), robot=fake_robot())
    harness.tick()
    assert harness.read("/robot/wheel_odometry") == Pose2D() and harness.read("/robot/odometry") is None


def test_read_pan_tilt_copies_the_state_and_does_nothing_without_a_unit():
    robot = fake_robot(ptu=True)
    robot.ptu.move(0.5, -0.1, 1.0)
    harness = BehaviourHarness(ReadPanTilt(), robot=robot)
    assert harness.tick() == Status.SUCCESS
    assert harness.read("/ptu/state") == PanTiltState(0.5, -0.1, False, 0.0)
    bare = BehaviourHarness(ReadPanTilt(), robot=fake_robot())
    assert bare.tick() == Status.SUCCESS and bare.read("/ptu/state") is None


def test_grab_frames_keeps_a_dropped_frame_and_names_the_first_camera_frame():
    robot = fake_robot(cameras=("front", "back"))
    robot.cameras["front"].frames = [frame("front", 1.0)]
    robot.cameras["back"].frames = [frame("back", 1.0), frame("back", 2.0)]
    harness = BehaviourHarness(GrabFrames(), robot=robot)
    assert harness.tick() == Status.SUCCESS
    assert {k: f.stamp for k, f in harness.read("/perception/frames").items()} == {"front": 1.0, "back": 1.0}
    assert harness.read("/perception/frame").camera_name == "front"
    harness.tick()  # front drops its frame: the last one stays, with its old stamp
    assert {k: f.stamp for k, f in harness.read("/perception/frames").items()} == {"front": 1.0, "back": 2.0}


def test_grab_frames_grabs_only_the_missions_cameras():
    robot = fake_robot(cameras=("front", "back"))
    robot.cameras["front"].frames = [frame("front", 1.0)]
    robot.cameras["back"].frames = [frame("back", 1.0)]
    harness = BehaviourHarness(GrabFrames(cameras=("back",)), robot=robot)
    harness.tick()
    assert list(harness.read("/perception/frames")) == ["back"]
    assert harness.read("/perception/frame").camera_name == "back"
    assert robot.cameras["front"].frames  # never grabbed


def test_grab_frames_without_cameras_writes_nothing():
    harness = BehaviourHarness(GrabFrames(), robot=fake_robot())
    assert harness.tick() == Status.SUCCESS and harness.read("/perception/frames") is None


def test_a_camera_the_robot_lacks_is_refused_at_setup():
    with pytest.raises(KeyError, match="no camera side"):
        BehaviourHarness(GrabFrames(cameras=("front", "side")), robot=fake_robot(cameras=("front",)))


@pytest.mark.parametrize("node", SENSE_NODES)
def test_a_sensor_without_a_robot_is_a_clear_error(node):
    harness = BehaviourHarness(node())
    with pytest.raises(NotSetUp, match="no robot"):
        harness.tick()
