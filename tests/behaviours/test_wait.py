"""Wait (behaviours/wait.py): tree time on the manual clock, no command."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from behaviours.base import NotSetUp
from behaviours.testing import BehaviourHarness
from behaviours.wait import Wait


def test_wait_runs_for_its_duration_of_tree_time_and_does_not_drive():
    harness = BehaviourHarness(Wait(duration=0.3))
    statuses, messages = [], []
    for _ in range(4):
        statuses.append(harness.tick())
        messages.append(harness.behaviour.feedback_message)
        assert harness.read("/robot/command") is None
        harness.clock.advance(0.1)
    assert statuses == [Status.RUNNING] * 3 + [Status.SUCCESS]
    assert messages[:3] == ["0.3 s left", "0.2 s left", "0.1 s left"]


def test_wait_starts_over_when_run_again_and_zero_succeeds_at_once():
    harness = BehaviourHarness(Wait(duration=1.0))
    harness.clock.advance(5.0)
    assert harness.tick() == Status.RUNNING  # the wait starts when the node starts, not at time zero
    harness.clock.advance(1.0)
    assert harness.tick() == Status.SUCCESS
    assert harness.tick() == Status.RUNNING  # a fresh wait
    assert BehaviourHarness(Wait(duration=0.0)).tick() == Status.SUCCESS


def test_wait_without_a_clock_is_a_clear_error():
    with pytest.raises(NotSetUp, match="no clock"):
        Wait(duration=1.0).tick_once()
