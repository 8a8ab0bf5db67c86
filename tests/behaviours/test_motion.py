"""Motion behaviours in isolation: hand-set odometry, manual clock, commands read back."""

from __future__ import annotations

import math

import pytest
from py_trees.common import Status

from behaviours.motion import Drive, DriveTo, Rotate, Stop
from behaviours.testing import BehaviourHarness
from behaviours.wait import Wait
from drivers.interfaces import STOP, VelocityCommand
from perception.collision_monitor import SafetyState
from perception.geometry import Pose2D


def integrate(harness: BehaviourHarness, dt: float = 0.1) -> None:
    """An ideal base: move the odometry by the command for dt."""
    pose = harness.read("/robot/odometry")
    cmd = harness.read("/robot/command") or STOP
    theta = pose.theta + cmd.w * dt
    harness.write("/robot/odometry", Pose2D(pose.x + cmd.v * dt * math.cos(pose.theta),
                                            pose.y + cmd.v * dt * math.sin(pose.theta), theta))


def test_drive_reaches_distance_and_stops():
    harness = BehaviourHarness(Drive(distance=1.0, speed=0.5), blackboard={"/robot/odometry": Pose2D()})
    assert harness.tick() == Status.RUNNING
    assert harness.read("/robot/command").v == pytest.approx(0.5)
    status = harness.tick_until(between=integrate)
    assert status == Status.SUCCESS
    assert harness.read("/robot/odometry").x == pytest.approx(1.0, abs=0.01)
    assert harness.read("/robot/command") == STOP


def test_drive_backwards_and_holds_heading():
    harness = BehaviourHarness(Drive(distance=-0.5), blackboard={"/robot/odometry": Pose2D(theta=0.0)})
    harness.tick()
    assert harness.read("/robot/command").v < 0
    harness.write("/robot/odometry", Pose2D(x=-0.1, theta=0.1))
    harness.tick()
    assert harness.read("/robot/command").w < 0  # steers back to the starting heading


def test_drive_waits_for_odometry_then_fails_when_stalled():
    harness = BehaviourHarness(Drive(distance=1.0))
    assert harness.tick() == Status.RUNNING
    assert harness.read("/robot/command") is None
    harness.write("/robot/odometry", Pose2D())
    assert harness.tick() == Status.RUNNING
    harness.write("/robot/stalled", True)
    assert harness.tick() == Status.FAILURE
    assert harness.behaviour.feedback_message == "stalled"
    assert harness.read("/robot/command") == STOP


def test_a_drive_the_collision_monitor_keeps_stopping_fails_after_the_held_timeout_with_its_reason():
    stop = SafetyState("stopped", "stop", "front", "obstacle 0.08 m from the footprint in the stop zone 'front'")
    harness = BehaviourHarness(Drive(distance=5.0, held_timeout=10.0),
                               blackboard={"/robot/odometry": Pose2D(), "/robot/safety": stop})
    assert harness.tick() == Status.RUNNING  # held since now
    harness.clock.advance(9.9)
    assert harness.tick() == Status.RUNNING and harness.read("/robot/command").v > 0.0  # it asks on
    harness.write("/robot/safety", SafetyState())  # the way cleared for a tick: the clock starts again
    harness.clock.advance(0.1)
    assert harness.tick() == Status.RUNNING
    harness.write("/robot/safety", stop)
    harness.tick()
    harness.clock.advance(10.0)
    assert harness.tick() == Status.FAILURE and harness.read("/robot/command") == STOP
    assert harness.behaviour.feedback_message == (
        "held by the collision monitor for 10 s: obstacle 0.08 m from the footprint in the stop zone 'front'")
    never = BehaviourHarness(Drive(distance=5.0, held_timeout=0.0),
                             blackboard={"/robot/odometry": Pose2D(), "/robot/safety": stop})
    never.tick()
    never.clock.advance(1000.0)
    assert never.tick() == Status.RUNNING  # 0: held for ever, as before


def test_drive_slows_down_before_the_goal():
    harness = BehaviourHarness(Drive(distance=5.0, speed=1.0), blackboard={"/robot/odometry": Pose2D()})
    harness.tick()
    far = harness.read("/robot/command").v
    harness.write("/robot/odometry", Pose2D(x=4.95))
    harness.tick()
    near = harness.read("/robot/command").v
    assert far == pytest.approx(1.0) and near < math.sqrt(2 * 0.3 * 0.05) + 1e-9


@pytest.mark.parametrize("angle", [90.0, -45.0, 270.0])
def test_rotate_turns_by_the_angle_across_the_wrap(angle):
    start = Pose2D(theta=math.radians(170.0))
    harness = BehaviourHarness(Rotate(angle=angle, speed=90.0), blackboard={"/robot/odometry": start})
    assert harness.tick_until(between=integrate) == Status.SUCCESS
    turned = math.degrees(harness.read("/robot/odometry").theta - start.theta)
    assert turned == pytest.approx(angle, abs=1.0)


def test_drive_to_turns_first_then_arrives():
    harness = BehaviourHarness(DriveTo(x=0.0, y=1.0), blackboard={"/robot/odometry": Pose2D()})
    harness.tick()
    first = harness.read("/robot/command")
    assert first.v == 0.0 and first.w > 0  # goal is 90 deg to the left: turn in place
    assert harness.tick_until(between=integrate) == Status.SUCCESS
    assert harness.read("/robot/odometry").distance_to(Pose2D(0.0, 1.0)) <= 0.05


def test_a_drive_says_how_far_it_means_to_go_on_its_command():
    """``reach``: the distance left to the goal, what the avoidance judges a wish against."""
    drive = BehaviourHarness(Drive(distance=-0.8), blackboard={"/robot/odometry": Pose2D()})
    drive.tick()
    assert drive.read("/robot/command").reach == pytest.approx(0.8)
    to = BehaviourHarness(DriveTo(x=0.3, y=0.4), blackboard={"/robot/odometry": Pose2D()})
    to.tick()
    assert to.read("/robot/command").reach == pytest.approx(0.5)
    turn = BehaviourHarness(Rotate(angle=90.0), blackboard={"/robot/odometry": Pose2D()})
    turn.tick()
    assert turn.read("/robot/command").reach == math.inf  # no goal along an arc
    assert VelocityCommand(0.3, 0.0, 0.5) == VelocityCommand(0.3, 0.0)  # not part of the velocity


def test_drive_to_reads_its_goal_from_the_blackboard():
    harness = BehaviourHarness(DriveTo(x="{/mission/gx}", y=0.0),
                               blackboard={"/robot/odometry": Pose2D(), "/mission/gx": 0.4})
    assert harness.tick_until(between=integrate) == Status.SUCCESS
    assert harness.read("/robot/odometry").x == pytest.approx(0.4, abs=0.05)


def test_halting_a_motion_leaves_a_stop_command():
    harness = BehaviourHarness(Drive(distance=5.0), blackboard={"/robot/odometry": Pose2D()})
    harness.tick()
    assert harness.read("/robot/command") != STOP
    harness.halt()
    assert harness.read("/robot/command") == STOP


def test_stop_and_wait():
    harness = BehaviourHarness(Stop())
    assert harness.tick() == Status.SUCCESS
    assert harness.read("/robot/command") == VelocityCommand(0.0, 0.0)
    wait = BehaviourHarness(Wait(duration=2.0))
    assert wait.tick() == Status.RUNNING
    wait.clock.advance(1.9)
    assert wait.tick() == Status.RUNNING
    wait.clock.advance(0.1)
    assert wait.tick() == Status.SUCCESS


def test_parameters_are_checked_when_built_by_hand():
    with pytest.raises(TypeError, match="missing required input 'distance'"):
        Drive()
    with pytest.raises(ValueError, match=r"Drive.speed must be <= 1.2"):
        Drive(distance=1.0, speed=3.0)
    with pytest.raises(TypeError, match="unknown port"):
        Drive(distance=1.0, sped=0.1)
    with pytest.raises(ValueError, match="outside the blackboard namespaces"):
        Drive(distance=1.0, command="{/elsewhere/command}")


def test_remapped_ports_read_and_write_other_keys():
    drive = Drive(distance=1.0, odometry="{/mission/pose}", command="{/mission/velocity}")
    harness = BehaviourHarness(drive, blackboard={"/mission/pose": Pose2D()})
    assert harness.tick() == Status.RUNNING
    assert harness.read("/mission/velocity").v > 0
    assert harness.read("/robot/command") is None  # the default key is left alone


def test_a_wrongly_typed_output_is_a_bug_caught_at_once():
    drive = Drive(distance=1.0)
    with pytest.raises(TypeError, match="declared VelocityCommand"):
        drive.set_output("command", (0.1, 0.0))
