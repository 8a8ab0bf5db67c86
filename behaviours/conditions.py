"""Condition leaves on blackboard values."""

from __future__ import annotations

from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.comparison import compare
from behaviours.decorators import GUARD_KEY, GUARD_OP, GUARD_PORTS, GUARD_VALUE
from behaviours.ports import InputPort, Ref
from behaviours.registry import register


@register
class CheckBlackboard(BearingsBehaviour):
    """SUCCESS when ``key op value`` holds on the blackboard, FAILURE otherwise (or when unset)."""

    KIND = "condition"
    PORTS = GUARD_PORTS

    def update(self) -> Status:
        key, op, value = self.get_input(GUARD_KEY), self.get_input(GUARD_OP), self.get_input(GUARD_VALUE)
        try:
            current = self.bb.get(key)
        except KeyError:
            self.feedback_message = f"{key} is not set"
            return Status.FAILURE
        holds = compare(current, op, value)
        self.feedback_message = f"{key} = {current!r} {op} {value!r}: {holds}"
        return Status.SUCCESS if holds else Status.FAILURE


@register
class IsStalled(BearingsBehaviour):
    """SUCCESS while the base reports a stalled wheel (a collision), FAILURE otherwise."""

    KIND = "condition"
    STALLED = InputPort("stalled", bool, Ref("/robot/stalled"), doc="the base's stall flag")
    PORTS = (STALLED,)

    def update(self) -> Status:
        return Status.SUCCESS if self.get_input(self.STALLED, False) else Status.FAILURE
