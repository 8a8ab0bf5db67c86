"""KeyboardTeleop (behaviours/teleop.py) with a fake keyboard handed in at setup, as the runner hands the terminal."""

from __future__ import annotations

import math

import pytest
from py_trees.common import Status

from behaviours.base import NotSetUp
from behaviours.teleop import KeyboardTeleop
from behaviours.testing import BehaviourHarness
from drivers.fake import FakeKeys
from drivers.interfaces import STOP


class Opener:
    """A keyboard opener that counts how often the keyboard was opened."""

    def __init__(self, keys: FakeKeys) -> None:
        self.keys, self.opened = keys, 0

    def __call__(self) -> FakeKeys:
        self.opened += 1
        return self.keys


def teleop(batches: list[list[str]], **ports) -> tuple[BehaviourHarness, Opener]:
    opener = Opener(FakeKeys(batches))
    node = KeyboardTeleop(**ports)
    harness = BehaviourHarness(node)
    node.setup(clock=harness.clock, keyboard=opener)  # as the runner does: setup(keyboard=...)
    return harness, opener


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


def test_q_or_enter_ends_the_drive_and_gives_the_keyboard_back():
    for key in ("q", "enter"):
        harness, opener = teleop([["up"], [key]])
        harness.tick()
        assert harness.tick() == Status.SUCCESS and harness.read("/robot/command") == STOP
        assert opener.opened == 1 and opener.keys.closed


def test_the_keyboard_is_opened_only_when_the_node_runs():
    harness, opener = teleop([["up"]])
    assert opener.opened == 0  # set up, not run: the terminal is not taken
    harness.tick()
    harness.tick()
    assert opener.opened == 1
    harness.halt()  # a higher-priority branch takes over: the keyboard is given back
    assert opener.keys.closed and harness.behaviour.keys is None


def test_without_a_terminal_the_node_fails_stopped():
    def no_terminal() -> FakeKeys:
        raise OSError("standard input is not a terminal: run the mission from a terminal to drive with keys")

    node = KeyboardTeleop()
    harness = BehaviourHarness(node)
    node.setup(keyboard=no_terminal)
    assert harness.tick() == Status.FAILURE and harness.read("/robot/command") == STOP
    assert "not a terminal" in node.feedback_message


def test_a_tree_set_up_without_a_keyboard_is_a_clear_error():
    harness = BehaviourHarness(KeyboardTeleop())
    with pytest.raises(NotSetUp, match="no keyboard"):
        harness.tick()
