"""Timeout, RateController and Guard (behaviours/decorators.py) on the manual clock."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from behaviours.base import NotSetUp
from behaviours.decorators import GUARD_PORTS, Guard, RateController, Timeout
from behaviours.testing import BehaviourHarness
from perception.geometry import Pose2D
from tests.behaviours.scripted import Scripted


def test_timeout_uses_the_tree_clock_and_halts_the_child():
    child = Scripted(Status.RUNNING)
    harness = BehaviourHarness(Timeout(name="t", child=child, duration=5.0))
    assert harness.tick() == Status.RUNNING
    harness.clock.advance(4.9)
    assert harness.tick() == Status.RUNNING
    harness.clock.advance(0.1)
    assert harness.tick() == Status.FAILURE
    assert child.ticks == 2 and child.halts == 1  # not ticked once the time was up
    assert "timed out after 5 s" in harness.behaviour.feedback_message


def test_timeout_restarts_after_completion():
    child = Scripted(Status.SUCCESS)
    harness = BehaviourHarness(Timeout(name="t", child=child, duration=1.0))
    assert harness.tick() == Status.SUCCESS
    harness.clock.advance(10.0)
    assert harness.tick() == Status.SUCCESS  # a fresh deadline for a fresh run


def test_timeout_passes_the_childs_failure_up_before_the_deadline():
    harness = BehaviourHarness(Timeout(name="t", child=Scripted(Status.RUNNING, Status.FAILURE), duration=1.0))
    assert harness.tick() == Status.RUNNING
    harness.clock.advance(0.5)
    assert harness.tick() == Status.FAILURE and harness.behaviour.feedback_message == ""


def test_timeout_without_a_clock_is_a_clear_error():
    timeout = Timeout(name="t", child=Scripted(Status.RUNNING), duration=1.0)
    with pytest.raises(NotSetUp, match="no clock"):
        timeout.tick_once()


def test_rate_controller_limits_child_ticks():
    child = Scripted(Status.RUNNING)
    harness = BehaviourHarness(RateController(name="r", child=child, hz=2.0))
    for _ in range(20):  # 2 s at 10 Hz
        assert harness.tick() == Status.RUNNING
        harness.clock.advance(0.1)
    assert child.ticks == 4


def test_rate_controller_passes_completion_up():
    harness = BehaviourHarness(RateController(name="r", child=Scripted(Status.RUNNING, Status.SUCCESS), hz=10.0))
    assert harness.tick() == Status.RUNNING
    harness.clock.advance(0.1)
    assert harness.tick() == Status.SUCCESS


def test_guard_ticks_child_only_while_condition_holds():
    child = Scripted(Status.RUNNING)
    harness = BehaviourHarness(Guard(name="g", child=child, key="/robot/stalled", op="==", value=False),
                               blackboard={"/robot/stalled": False})
    assert harness.tick() == Status.RUNNING
    harness.write("/robot/stalled", True)
    assert harness.tick() == Status.FAILURE
    assert child.ticks == 1 and child.halts == 1


def test_guard_on_an_attribute_and_an_unset_key():
    child = Scripted(Status.RUNNING)
    harness = BehaviourHarness(Guard(name="g", child=child, key="/robot/odometry.x", op="<", value=1.0))
    assert harness.tick() == Status.FAILURE and child.ticks == 0  # unset: the condition does not hold
    harness.write("/robot/odometry", Pose2D(0.5, 0.0, 0.0))
    assert harness.tick() == Status.RUNNING and child.ticks == 1
    harness.write("/robot/odometry", Pose2D(1.5, 0.0, 0.0))
    assert harness.tick() == Status.FAILURE


def test_the_guard_ports_are_the_condition_key_op_value_with_equality_by_default():
    assert [port.name for port in GUARD_PORTS] == ["key", "op", "value"]
    assert [port.name for port in Guard.PORTS] == ["key", "op", "value"] and GUARD_PORTS[1].default == "=="
    assert Timeout.PORTS == (Timeout.DURATION,) and RateController.PORTS == (RateController.HZ,)
