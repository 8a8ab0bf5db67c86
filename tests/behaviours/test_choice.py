"""Equals (behaviours/choice.py): a mission's load-time choice between branches."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from behaviours.choice import Equals
from behaviours.testing import BehaviourHarness


def test_equals_chooses_a_branch_at_load_time():
    assert BehaviourHarness(Equals(value="keyboard", equals="keyboard")).tick() == Status.SUCCESS
    chosen = BehaviourHarness(Equals(value="waypoints", equals="keyboard"))
    assert chosen.tick() == Status.FAILURE and "'waypoints' is not 'keyboard'" in chosen.behaviour.feedback_message


def test_equals_compares_text_exactly_and_takes_no_reference():
    assert BehaviourHarness(Equals(value="Keyboard", equals="keyboard")).tick() == Status.FAILURE
    with pytest.raises(ValueError, match="takes a literal value"):
        Equals(value="{/mission/drive}", equals="keyboard")
