"""CheckBlackboard and IsStalled (behaviours/conditions.py) on a hand-set blackboard."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from behaviours.conditions import CheckBlackboard, IsStalled
from behaviours.decorators import GUARD_PORTS
from behaviours.testing import BehaviourHarness
from perception.geometry import Pose2D


@pytest.mark.parametrize(("op", "value", "expected"), [
    ("==", 3, Status.SUCCESS), ("!=", 3, Status.FAILURE), ("<", 4, Status.SUCCESS), ("<=", 3, Status.SUCCESS),
    (">", 3, Status.FAILURE), (">=", 4, Status.FAILURE),
])
def test_check_blackboard_compares_the_key_with_the_value(op, value, expected):
    node = CheckBlackboard(key="/map/count", op=op, value=value)
    harness = BehaviourHarness(node, blackboard={"/map/count": 3})
    assert harness.tick() == expected
    assert node.feedback_message == f"/map/count = 3 {op} {value!r}: {expected == Status.SUCCESS}"


def test_check_blackboard_reads_an_attribute_and_fails_while_the_key_is_unset():
    node = CheckBlackboard(key="/robot/odometry.x", op=">=", value=1.5)
    harness = BehaviourHarness(node)
    assert harness.tick() == Status.FAILURE and node.feedback_message == "/robot/odometry.x is not set"
    harness.write("/robot/odometry", Pose2D(2.0, 0.0, 0.0))
    assert harness.tick() == Status.SUCCESS


def test_check_blackboard_fails_when_the_values_cannot_be_ordered():
    harness = BehaviourHarness(CheckBlackboard(key="/map/name", op="<", value=1), blackboard={"/map/name": "lab"})
    assert harness.tick() == Status.FAILURE


def test_check_blackboard_declares_the_guard_condition():
    assert CheckBlackboard.PORTS == GUARD_PORTS and CheckBlackboard.KIND == "condition"


def test_is_stalled_follows_the_stall_flag_and_fails_without_one():
    harness = BehaviourHarness(IsStalled())
    assert harness.tick() == Status.FAILURE  # no flag yet: not stalled
    harness.write("/robot/stalled", True)
    assert harness.tick() == Status.SUCCESS
    harness.write("/robot/stalled", False)
    assert harness.tick() == Status.FAILURE


def test_is_stalled_reads_a_remapped_flag():
    harness = BehaviourHarness(IsStalled(stalled="{/robot/left_wheel_stalled}"),
                               blackboard={"/robot/left_wheel_stalled": True, "/robot/stalled": False})
    assert harness.tick() == Status.SUCCESS
