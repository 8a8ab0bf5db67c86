"""RoutineBehaviour: a coroutine per tick, motion through the motion nodes, images at rest."""

from __future__ import annotations

import math

import numpy as np
import py_trees
import pytest
from py_trees.common import Status

from behaviours.ports import OutputPort
from behaviours.roadmap.routine import CAMERA_OFFSET, ROUTINE_PORTS, Failed, RoutineBehaviour, Step
from behaviours.testing import BehaviourHarness
from drivers.interfaces import STOP, PanTiltState
from perception.camera import PinholeCamera
from perception.collision_monitor import SafetyState
from perception.frame import Frame
from perception.geometry import Pose2D
from tests.behaviours.test_motion import integrate

CAMERA = PinholeCamera(64, 48, 50.0, 50.0, 31.5, 23.5)


class Errand(RoutineBehaviour):
    """Turn left 90 deg, drive 0.5 m, take an image; fail on request (a test routine, not registered)."""

    def __init__(self, name: str | None = None, fail: bool = False, **ports) -> None:
        super().__init__(name=name, **ports)
        self.fail = fail
        self.image: tuple[Frame, Pose2D] | None = None

    def routine(self) -> Step[None]:
        yield from self.rotate(math.pi / 2)
        yield from self.drive(0.5)
        if self.fail:
            raise Failed("asked to fail")
        self.image = yield from self.capture()


def frame_at(stamp: float) -> Frame:
    return Frame(np.zeros((48, 64), np.uint8), CAMERA, stamp, "front")


def world(harness: BehaviourHarness) -> None:
    """An ideal base, and a camera that delivers a frame every tick (stamped with the next tick)."""
    integrate(harness)
    harness.write("/perception/frames", {"front": frame_at(harness.clock.now() + 0.1)})


def test_turns_drives_then_takes_an_image_at_rest():
    harness = BehaviourHarness(Errand(), blackboard={"/robot/odometry": Pose2D()})
    assert harness.tick() == Status.RUNNING
    assert harness.read("/robot/command").w > 0  # Rotate's command, on this node's command key
    assert harness.tick_until(between=world) == Status.SUCCESS
    pose = harness.read("/robot/odometry")
    assert pose.theta == pytest.approx(math.pi / 2, abs=0.01) and pose.y == pytest.approx(0.5, abs=0.02)
    frame, at = harness.behaviour.image
    assert at.y == pytest.approx(pose.y)
    assert frame.stamp >= harness.clock.now() - 0.5  # taken after the robot stopped, not before


def test_an_image_waits_for_rest_and_settle_time():
    node = Errand(settle=1.0)
    harness = BehaviourHarness(node, blackboard={"/robot/odometry": Pose2D()})
    harness.tick_until(lambda s: node.feedback_message.startswith("waiting for an image"), between=world)
    stopped = harness.clock.now()
    assert harness.tick_until(between=world) == Status.SUCCESS
    assert node.image[0].stamp >= stopped + 1.0 - 1e-6


def test_failed_routine_fails_with_its_reason_and_stops_the_robot():
    harness = BehaviourHarness(Errand(fail=True), blackboard={"/robot/odometry": Pose2D()})
    assert harness.tick_until(between=world) == Status.FAILURE
    assert harness.behaviour.feedback_message == "asked to fail"
    assert harness.read("/robot/command") == STOP


def test_halting_stops_the_motion_and_leaves_no_blackboard_clients_behind():
    before = len(py_trees.blackboard.Blackboard.clients)
    harness = BehaviourHarness(Errand(), blackboard={"/robot/odometry": Pose2D()})
    clients = len(py_trees.blackboard.Blackboard.clients)
    harness.tick()
    harness.tick()
    assert len(py_trees.blackboard.Blackboard.clients) == clients + 1  # the Rotate node's
    harness.halt()
    assert harness.read("/robot/command") == STOP
    assert len(py_trees.blackboard.Blackboard.clients) == clients
    assert clients > before


def test_a_motion_that_makes_no_progress_fails():
    harness = BehaviourHarness(Errand(), blackboard={"/robot/odometry": Pose2D()})
    assert harness.tick_until(max_ticks=500) == Status.FAILURE  # nothing moves the base
    assert "no progress" in harness.behaviour.feedback_message
    assert harness.clock.now() < 3.0 * 2.0 + 5.0 + 1.0  # 90 deg at 45 deg/s, three times over, plus 5 s


def test_a_stall_left_by_a_contact_is_backed_away_from_before_driving():
    harness = BehaviourHarness(Errand(), blackboard={"/robot/odometry": Pose2D(theta=math.pi / 2),
                                                     "/robot/stalled": True})
    node = harness.behaviour
    node._last_direction = 1.0
    harness.tick_until(lambda s: harness.read("/robot/command") is not None
                       and harness.read("/robot/command").v != 0.0, between=integrate)
    assert harness.read("/robot/command").v < 0  # backs up: the last drive went forwards into the contact


def test_the_head_is_levelled_before_an_image_and_not_commanded_without_one():
    node = Errand()
    harness = BehaviourHarness(node, blackboard={"/robot/odometry": Pose2D(), "/ptu/state": PanTiltState(0.5, 0.1)})
    harness.tick_until(lambda s: node.feedback_message.startswith("waiting") or harness.read("/ptu/command"),
                       between=world)
    command = harness.read("/ptu/command")
    assert (command.pan, command.tilt) == (0.0, 0.0)
    harness.write("/ptu/state", PanTiltState(0.0, 0.0))
    assert harness.tick_until(between=world) == Status.SUCCESS


def test_camera_offset_takes_two_numbers():
    with pytest.raises(ValueError, match="camera_offset takes"):
        Errand(camera_offset=[0.1, 0.0, 0.2])


def test_motion_uses_the_routines_own_ports_as_bound():
    node = Errand(turn_speed=90.0, odometry="{/robot/calibrated_odometry}", command="/robot/routine_command")
    harness = BehaviourHarness(node, blackboard={"/robot/calibrated_odometry": Pose2D()})
    assert harness.tick() == Status.RUNNING
    assert (harness.read("/robot/command") or STOP).w == 0.0  # the motion node writes the routine's command key
    assert harness.read("/robot/routine_command").w == pytest.approx(math.radians(90.0))  # turn_speed, at top rate


class Marker(RoutineBehaviour):
    """Writes one output on its second tick (a test routine, not registered)."""

    MARK = OutputPort("mark", float, "/map/mark", doc="a mark")
    PORTS = (*ROUTINE_PORTS, MARK)

    def routine(self) -> Step[None]:
        yield
        self.set_output(self.MARK, 1.5)


@pytest.mark.parametrize("key", ["/map/mark", "/map/elsewhere"])
def test_written_is_what_the_node_last_wrote_on_its_output_and_none_before(key):
    node = Marker(mark=key)
    harness = BehaviourHarness(node)
    assert harness.tick() == Status.RUNNING and node.written(Marker.MARK) is None
    assert harness.tick() == Status.SUCCESS and node.written(Marker.MARK) == 1.5
    assert harness.read(key) == 1.5
    harness.write(key, 2.5)  # another node wrote the same key since: that is what is there
    assert node.written(Marker.MARK) == 2.5


def test_pair_reads_a_position_port():
    node = Errand(camera_offset=[0.2, -0.05])
    assert node.camera_offset == (0.2, -0.05) and node.pair(CAMERA_OFFSET) == (0.2, -0.05)


def held_for(seconds: float):
    """Between ticks: :func:`world`, and the collision monitor stopping every command (the base does
    not move) for the first ``seconds`` (a person in the way who then walks on)."""
    def between(harness: BehaviourHarness) -> None:
        stopped = harness.clock.now() < seconds
        harness.write("/robot/safety", SafetyState("stopped", "stop", "stop", "a person") if stopped else SafetyState())
        if not stopped:
            world(harness)
    return between


def test_time_held_by_the_collision_monitor_is_not_lack_of_progress():
    """The quarter turn is given 3 x 2 s + 5 s = 11 s; held for 15 s by the monitor it still goes on
    once the way clears, and a hold of the motion node's held_timeout (20 s) fails, saying so."""
    harness = BehaviourHarness(Errand(), blackboard={"/robot/odometry": Pose2D()})
    assert harness.tick_until(between=held_for(15.0), max_ticks=1000) == Status.SUCCESS
    harness = BehaviourHarness(Errand(), blackboard={"/robot/odometry": Pose2D()})
    assert harness.tick_until(between=held_for(1000.0), max_ticks=1000) == Status.FAILURE
    assert "held by the collision monitor for 20 s" in harness.behaviour.feedback_message
    assert 20.0 <= harness.clock.now() < 21.0
