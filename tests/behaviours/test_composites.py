"""Nav2's RecoveryNode (behaviours/composites.py): task, recovery, retries."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from behaviours.composites import RecoveryNode
from behaviours.testing import BehaviourHarness
from tests.behaviours.scripted import Scripted


def test_recovery_node_retries_after_recovery():
    task = Scripted(Status.FAILURE, Status.FAILURE, Status.SUCCESS, name="task")
    recovery = Scripted(Status.SUCCESS, name="recovery")
    harness = BehaviourHarness(RecoveryNode(name="rec", children=[task, recovery], number_of_retries=3))
    assert harness.tick() == Status.SUCCESS  # fail, recover, fail, recover, succeed: all in one tick
    assert (task.ticks, recovery.ticks) == (3, 2)


def test_recovery_node_gives_up_after_the_retries():
    task, recovery = Scripted(Status.FAILURE, name="task"), Scripted(Status.SUCCESS, name="recovery")
    harness = BehaviourHarness(RecoveryNode(name="rec", children=[task, recovery], number_of_retries=2))
    assert harness.tick() == Status.FAILURE
    assert (task.ticks, recovery.ticks) == (3, 2)
    assert harness.behaviour.feedback_message == "failed after 2 recoveries"


def test_recovery_node_fails_when_recovery_fails_and_waits_while_running():
    task = Scripted(Status.FAILURE, name="task")
    recovery = Scripted(Status.RUNNING, Status.FAILURE, name="recovery")
    harness = BehaviourHarness(RecoveryNode(name="rec", children=[task, recovery], number_of_retries=5))
    assert harness.tick() == Status.RUNNING
    assert harness.tick() == Status.FAILURE
    assert task.ticks == 1  # the task is not retried while its recovery runs
    assert harness.behaviour.feedback_message == "recovery failed"


def test_recovery_node_without_retries_fails_with_its_task_and_never_recovers():
    task, recovery = Scripted(Status.FAILURE, name="task"), Scripted(Status.SUCCESS, name="recovery")
    harness = BehaviourHarness(RecoveryNode(name="rec", children=[task, recovery], number_of_retries=0))
    assert harness.tick() == Status.FAILURE and recovery.ticks == 0


def test_a_halted_recovery_node_halts_its_running_child_and_counts_retries_afresh():
    task = Scripted(Status.FAILURE, Status.RUNNING, name="task")
    recovery = Scripted(Status.SUCCESS, name="recovery")
    harness = BehaviourHarness(RecoveryNode(name="rec", children=[task, recovery], number_of_retries=1))
    assert harness.tick() == Status.RUNNING and harness.behaviour.retries == 1  # failed, recovered, running
    restarts = task.halts  # the task is reset before each retry
    harness.halt()
    assert task.halts == restarts + 1 and task.status == Status.INVALID
    task.statuses = [Status.FAILURE]
    assert harness.tick() == Status.FAILURE
    assert recovery.ticks == 2  # the fresh run had its own retry before giving up


def test_recovery_node_takes_exactly_two_children():
    with pytest.raises(ValueError, match="exactly two children"):
        RecoveryNode(name="rec", children=[Scripted(Status.SUCCESS)])
