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
    PORTS = (
        InputPort("value", str, literal_only=True, doc="the value chosen (usually a ${input})"),
        InputPort("equals", str, literal_only=True, doc="the value this branch is for"),
    )

    def update(self) -> Status:
        same = self.get_input("value") == self.get_input("equals")
        self.feedback_message = "" if same else f"{self.get_input('value')!r} is not {self.get_input('equals')!r}"
        return Status.SUCCESS if same else Status.FAILURE
