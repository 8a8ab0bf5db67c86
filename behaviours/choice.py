"""A mission's load-time choice between branches: ``Equals`` compares two literals.

Missions choose a branch by an input (``teach_route``: ``drive`` = waypoints or keyboard) with
``Selector`` children ``Sequence: [Equals: {value: "${drive}", equals: keyboard}, ...]``. The
input is substituted when the mission loads, so the choice needs no blackboard key (a
``/mission/<input>`` key read at run time does not survive the BehaviorTree.CPP export, which
substitutes inputs too).
"""

from __future__ import annotations

from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.ports import InputPort
from behaviours.registry import register


@register
class Equals(BearingsBehaviour):
    """SUCCESS when ``value`` equals ``equals`` (two literals, e.g. an input and a choice), else FAILURE."""

    KIND = "condition"
    VALUE = InputPort("value", str, literal_only=True, doc="the value chosen (usually a ${input})")
    EQUALS = InputPort("equals", str, literal_only=True, doc="the value this branch is for")
    PORTS = (VALUE, EQUALS)

    def update(self) -> Status:
        value, equals = self.get_input(self.VALUE), self.get_input(self.EQUALS)
        self.feedback_message = "" if value == equals else f"{value!r} is not {equals!r}"
        return Status.SUCCESS if value == equals else Status.FAILURE
