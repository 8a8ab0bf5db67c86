"""The data-gathering nodes (behaviours/sense.py): driver readings onto the blackboard, on fake drivers."""

from __future__ import annotations

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.base import NotSetUp
from behaviours.keys import SENSED_KEYS
from behaviours.registry import NodeType
from behaviours.sense import SENSE_NODES, GrabFrames, ReadOdometry, ReadPanTilt, ReadRanges
from behaviours.testing import BehaviourHarness
from drivers.fake import fake_robot
from drivers.interfaces import PanTiltState
from perception.frame import Frame
from perception.geometry import Pose2D
from perception.ranges import Bumper, RangeScan, RangeSensor


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


class QueuedRanges:
    """A range source returning the scans a test queued, then None."""

    def __init__(self, *scans: RangeScan | None) -> None:
        self.scans = list(scans)

    def read(self) -> RangeScan | None:
        return self.scans.pop(0) if self.scans else None

    def close(self) -> None:
        pass


def scan(stamp: float, front: float) -> RangeScan:
    return RangeScan((RangeSensor(0.2, 0.0, 0.0),), np.array([front]), stamp, (Bumper(0.25, 0.0, +1),),
                     np.array([front < 0.05]))


def test_read_ranges_copies_the_newest_scan_and_keeps_the_last_when_none_comes():
    robot = fake_robot()
    robot.ranges = QueuedRanges(None, scan(0.1, 1.5), scan(0.2, 0.01))
    harness = BehaviourHarness(ReadRanges(), robot=robot)
    assert harness.tick() == Status.SUCCESS and harness.read("/robot/ranges") is None  # nothing read yet
    harness.tick()
    assert harness.read("/robot/ranges").ranges.tolist() == [1.5]
    harness.tick()
    latest = harness.read("/robot/ranges")
    assert latest.stamp == 0.2 and latest.bumped(+1)
    harness.tick()  # the source has nothing new: the last scan stays, its stamp tells its age
    assert harness.read("/robot/ranges").stamp == 0.2


def test_read_ranges_does_nothing_on_a_robot_without_range_sensors():
    harness = BehaviourHarness(ReadRanges(), robot=fake_robot())
    assert harness.tick() == Status.SUCCESS and harness.read("/robot/ranges") is None


def test_the_sensed_keys_the_framework_reads_are_written_by_the_sensing_branch():
    written = {port.key: port.type for node in SENSE_NODES for port in NodeType.of(node).outputs}
    assert all(written.get(spec.path) is spec.type for spec in SENSED_KEYS)


@pytest.mark.parametrize("node", SENSE_NODES)
def test_a_sensor_without_a_robot_is_a_clear_error(node):
    harness = BehaviourHarness(node())
    with pytest.raises(NotSetUp, match="no robot"):
        harness.tick()
