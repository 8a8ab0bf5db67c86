"""The control nodes of behaviours/control.py: py_trees' semantics under the mission language's names."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from behaviours.control import MEMORY, OneShot, Parallel, Repeat, Retry, Selector, Sequence
from behaviours.registry import Registry
from behaviours.testing import BehaviourHarness
from tests.behaviours.scripted import Scripted


def _build(type_name: str, **kwargs):
    """A built-in control node made the way the builder makes it: its class, by registered name."""
    return Registry.builtin().lookup(type_name).cls(**kwargs)


@pytest.mark.parametrize(
    ("name", "params", "child_status", "expected"),
    [("Inverter", {}, Status.SUCCESS, Status.FAILURE), ("Inverter", {}, Status.FAILURE, Status.SUCCESS),
     ("ForceSuccess", {}, Status.FAILURE, Status.SUCCESS), ("ForceFailure", {}, Status.SUCCESS, Status.FAILURE),
     ("Retry", {"num_attempts": 3}, Status.FAILURE, Status.RUNNING)],
)
def test_registered_decorators_map_to_py_trees_semantics(name, params, child_status, expected):
    node = _build(name, name=name, child=Scripted(child_status), **params)
    assert BehaviourHarness(node).tick() == expected


@pytest.mark.parametrize(("name", "expected"), [("Success", Status.SUCCESS), ("Failure", Status.FAILURE),
                                                ("Running", Status.RUNNING)])
def test_the_constant_leaves(name, expected):
    assert BehaviourHarness(_build(name, name=name)).tick() == expected


def test_retry_gives_up_after_its_attempts():
    child = Scripted(Status.FAILURE)
    harness = BehaviourHarness(_build("Retry", name="r", child=child, num_attempts=3))
    statuses = [harness.tick() for _ in range(3)]
    assert statuses == [Status.RUNNING, Status.RUNNING, Status.FAILURE] and child.ticks == 3


def test_repeat_counts_cycles():
    child = Scripted(Status.SUCCESS)
    harness = BehaviourHarness(_build("Repeat", name="r", child=child, num_cycles=3))
    assert [harness.tick() for _ in range(3)] == [Status.RUNNING, Status.RUNNING, Status.SUCCESS]


def test_repeat_fails_on_a_failure():
    harness = BehaviourHarness(Repeat(name="r", child=Scripted(Status.SUCCESS, Status.FAILURE), num_cycles=5))
    assert [harness.tick() for _ in range(2)] == [Status.RUNNING, Status.FAILURE]


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


def test_sequence_fails_at_the_first_failure():
    first, second = Scripted(Status.FAILURE, name="a"), Scripted(Status.SUCCESS, name="b")
    assert BehaviourHarness(Sequence(name="s", children=[first, second])).tick() == Status.FAILURE
    assert second.ticks == 0


def test_selector_falls_back_until_a_child_does_not_fail():
    first, second, third = (Scripted(Status.FAILURE, name="a"), Scripted(Status.SUCCESS, name="b"),
                            Scripted(Status.SUCCESS, name="c"))
    assert BehaviourHarness(Selector(name="f", children=[first, second, third])).tick() == Status.SUCCESS
    assert (first.ticks, second.ticks, third.ticks) == (1, 1, 0)
    assert Selector.BTCPP == "Fallback" and Selector.PORTS == Sequence.PORTS == (MEMORY,)


@pytest.mark.parametrize(("policy", "expected"), [("all", Status.RUNNING), ("one", Status.SUCCESS)])
def test_parallel_succeeds_when_all_or_one_child_did(policy, expected):
    done, busy = Scripted(Status.SUCCESS, name="done"), Scripted(Status.RUNNING, name="busy")
    node = Parallel(name="p", children=[done, busy], policy=policy)
    assert BehaviourHarness(node).tick() == expected and node.policy_name == policy


def test_parallel_fails_as_soon_as_one_child_fails():
    failing, busy = Scripted(Status.FAILURE, name="fails"), Scripted(Status.RUNNING, name="busy")
    assert BehaviourHarness(Parallel(name="p", children=[failing, busy])).tick() == Status.FAILURE


def test_parallel_synchronised_does_not_tick_a_child_that_succeeded_again():
    done, busy = Scripted(Status.SUCCESS, name="done"), Scripted(Status.RUNNING, Status.SUCCESS, name="busy")
    harness = BehaviourHarness(Parallel(name="p", children=[done, busy], synchronise=True))
    assert [harness.tick(), harness.tick()] == [Status.RUNNING, Status.SUCCESS] and done.ticks == 1
    again, slow = Scripted(Status.SUCCESS, name="again"), Scripted(Status.RUNNING, Status.SUCCESS, name="slow")
    loose = BehaviourHarness(Parallel(name="p", children=[again, slow], synchronise=False))
    assert [loose.tick(), loose.tick()] == [Status.RUNNING, Status.SUCCESS] and again.ticks == 2


@pytest.mark.parametrize("policy", ["on_success", "on_completion"])
def test_one_shot_latches_a_success(policy):
    child = Scripted(Status.SUCCESS)
    harness = BehaviourHarness(OneShot(name="o", child=child, policy=policy))
    assert [harness.tick(), harness.tick()] == [Status.SUCCESS, Status.SUCCESS] and child.ticks == 1


def test_one_shot_on_success_retries_a_failure_but_on_completion_keeps_it():
    retried = Scripted(Status.FAILURE, Status.SUCCESS)
    harness = BehaviourHarness(OneShot(name="o", child=retried, policy="on_success"))
    assert [harness.tick(), harness.tick()] == [Status.FAILURE, Status.SUCCESS] and retried.ticks == 2
    kept = Scripted(Status.FAILURE, Status.SUCCESS)
    latched = BehaviourHarness(OneShot(name="o", child=kept, policy="on_completion"))
    assert [latched.tick(), latched.tick()] == [Status.FAILURE, Status.FAILURE] and kept.ticks == 1


def test_retry_and_oneshot_are_named_as_in_behaviortree_cpp():
    assert (Retry.BTCPP, OneShot.BTCPP) == ("RetryUntilSuccessful", "RunOnce")
    assert [p.name for p in Parallel.PORTS] == ["policy", "synchronise"]
