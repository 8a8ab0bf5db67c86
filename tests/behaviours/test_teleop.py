"""KeyboardTeleop with a fake key source, the key parser, DriveWaypoints on an ideal base."""

from __future__ import annotations

import math
import os

import pytest
from py_trees.common import Status

from behaviours.teleop import KeyboardTeleop
from behaviours.testing import BehaviourHarness
from behaviours.waypoints import DriveWaypoints, waypoint_pairs
from drivers.fake import FakeKeys
from drivers.interfaces import STOP
from drivers.keyboard import TerminalKeys, parse_keys
from perception.geometry import Pose2D
from tests.behaviours.test_motion import integrate


def teleop(batches: list[list[str]], **ports) -> tuple[BehaviourHarness, FakeKeys]:
    keys = FakeKeys(batches)
    node = KeyboardTeleop(**ports)
    harness = BehaviourHarness(node)
    node.setup(clock=harness.clock, keys=keys)  # the key source is handed in at setup
    return harness, keys


def test_arrow_keys_and_wasd_drive_and_space_stops():
    harness, _ = teleop([["up"], ["a"], ["space"], ["s"], ["right"]], speed=0.2, turn_rate=30.0)
    expected = [(0.2, 0.0), (0.0, math.radians(30)), (0.0, 0.0), (-0.2, 0.0), (0.0, -math.radians(30))]
    for v, w in expected:
        assert harness.tick() == Status.RUNNING
        command = harness.read("/robot/command")
        assert (command.v, command.w) == pytest.approx((v, w))
        harness.clock.advance(0.1)


def test_the_robot_stops_when_keys_stop_arriving_for_the_timeout():
    harness, _ = teleop([["w"]], key_timeout=0.5)
    moving = []
    for _ in range(8):
        harness.tick()
        moving.append(harness.read("/robot/command").v > 0)
        harness.clock.advance(0.1)
    assert moving == [True] * 6 + [False] * 2  # 0.0 .. 0.5 s after the key, then stopped


def test_q_or_enter_ends_the_drive():
    for key in ("q", "enter"):
        harness, _ = teleop([["up"], [key]])
        harness.tick()
        assert harness.tick() == Status.SUCCESS and harness.read("/robot/command") == STOP


def test_without_a_terminal_the_node_fails_and_never_blocks():
    read, write = os.pipe()  # not a terminal
    try:
        with pytest.raises(OSError, match="not a terminal"):
            TerminalKeys(read)
    finally:
        os.close(read)
        os.close(write)


def test_parse_keys_names_arrows_and_specials():
    assert parse_keys("\x1b[A\x1b[Dw \nQ\x1bOB") == ["up", "left", "w", "space", "enter", "q", "down"]


def test_drive_waypoints_passes_every_point_and_stops_at_the_last():
    harness = BehaviourHarness(DriveWaypoints(waypoints=[1.0, 0.0, 1.0, 1.0, 0.0, 1.0]),
                               blackboard={"/robot/odometry": Pose2D()})
    visited = []

    def step(h: BehaviourHarness) -> None:
        integrate(h)
        visited.append(h.read("/robot/odometry"))

    assert harness.tick_until(between=step) == Status.SUCCESS
    for x, y in waypoint_pairs([1.0, 0.0, 1.0, 1.0, 0.0, 1.0]):
        assert min(math.hypot(p.x - x, p.y - y) for p in visited) < 0.06
    assert harness.read("/robot/command") == STOP
    with pytest.raises(ValueError, match="pairs"):
        waypoint_pairs([1.0, 2.0, 3.0])


def test_equals_chooses_a_branch_at_load_time():
    from behaviours.choice import Equals

    assert BehaviourHarness(Equals(value="keyboard", equals="keyboard")).tick() == Status.SUCCESS
    chosen = BehaviourHarness(Equals(value="waypoints", equals="keyboard"))
    assert chosen.tick() == Status.FAILURE and "'waypoints' is not 'keyboard'" in chosen.behaviour.feedback_message
