"""Decorators and composites of the mission language, on the manual clock."""

from __future__ import annotations

import py_trees
import pytest
from py_trees.common import Status

from behaviours.base import NotSetUp
from behaviours.composites import RecoveryNode
from behaviours.decorators import Guard, RateController, Timeout
from behaviours.registry import Registry
from behaviours.testing import BehaviourHarness


class Scripted(py_trees.behaviour.Behaviour):
    """Returns the statuses it is given, one per tick (the last one repeats); counts ticks."""

    def __init__(self, *statuses: Status, name: str = "scripted") -> None:
        super().__init__(name=name)
        self.statuses = list(statuses)
        self.ticks = 0
        self.halts = 0

    def update(self) -> Status:
        self.ticks += 1
        return self.statuses.pop(0) if len(self.statuses) > 1 else self.statuses[0]

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID:
            self.halts += 1


def _build(type_name: str, **kwargs):
    """A built-in control node made the way the builder makes it: its class, by registered name."""
    return Registry.builtin().lookup(type_name).cls(**kwargs)


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


def test_guard_ticks_child_only_while_condition_holds():
    child = Scripted(Status.RUNNING)
    harness = BehaviourHarness(Guard(name="g", child=child, key="/robot/stalled", op="==", value=False),
                               blackboard={"/robot/stalled": False})
    assert harness.tick() == Status.RUNNING
    harness.write("/robot/stalled", True)
    assert harness.tick() == Status.FAILURE
    assert child.ticks == 1 and child.halts == 1


@pytest.mark.parametrize(
    ("name", "params", "child_status", "expected"),
    [("Inverter", {}, Status.SUCCESS, Status.FAILURE), ("ForceSuccess", {}, Status.FAILURE, Status.SUCCESS),
     ("ForceFailure", {}, Status.SUCCESS, Status.FAILURE), ("Retry", {"num_attempts": 3}, Status.FAILURE,
                                                              Status.RUNNING)],
)
def test_registered_decorators_map_to_py_trees_semantics(name, params, child_status, expected):
    node = _build(name, name=name, child=Scripted(child_status), **params)
    assert BehaviourHarness(node).tick() == expected


def test_retry_gives_up_after_its_attempts():
    child = Scripted(Status.FAILURE)
    harness = BehaviourHarness(_build("Retry", name="r", child=child, num_attempts=3))
    statuses = [harness.tick() for _ in range(3)]
    assert statuses == [Status.RUNNING, Status.RUNNING, Status.FAILURE] and child.ticks == 3


def test_repeat_counts_cycles():
    child = Scripted(Status.SUCCESS)
    harness = BehaviourHarness(_build("Repeat", name="r", child=child, num_cycles=3))
    assert [harness.tick() for _ in range(3)] == [Status.RUNNING, Status.RUNNING, Status.SUCCESS]


def test_sequence_memory_default_resumes_at_running_child():
    first, second = Scripted(Status.SUCCESS, name="a"), Scripted(Status.RUNNING, name="b")
    seq = _build("Sequence", name="s", children=[first, second], memory=True)
    harness = BehaviourHarness(seq)
    harness.tick()
    harness.tick()
    assert (first.ticks, second.ticks) == (1, 2)
    first2, second2 = Scripted(Status.SUCCESS, name="a"), Scripted(Status.RUNNING, name="b")
    reactive = BehaviourHarness(_build("Sequence", name="s", children=[first2, second2], memory=False))
    reactive.tick()
    reactive.tick()
    assert (first2.ticks, second2.ticks) == (2, 2)
