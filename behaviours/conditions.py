"""Condition leaves on blackboard values."""

from __future__ import annotations

from typing import Any

from py_trees.common import Access, Status

from behaviours.base import BearingsBehaviour
from behaviours.comparison import compare
from behaviours.ports import COMPARISONS, Param
from behaviours.registry import register


@register
class CheckBlackboard(BearingsBehaviour):
    """SUCCESS when ``key op value`` holds on the blackboard, FAILURE otherwise (or when unset)."""

    KIND = "condition"
    PARAMS = (
        Param("key", "key", doc="absolute key, optionally with an attribute: /robot/odometry.x", refs=False),
        Param("op", "str", "==", doc="comparison", choices=COMPARISONS, refs=False),
        Param("value", "any", doc="the value to compare with", refs=False),
    )

    def __init__(self, name: str | None = None, **params: Any) -> None:
        super().__init__(name=name, **params)
        self.bb.register_key(key=self.params["key"].split(".", 1)[0], access=Access.READ)

    def update(self) -> Status:
        key, op, value = self.params["key"], self.params["op"], self.params["value"]
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
    READS = ("/robot/stalled",)

    def update(self) -> Status:
        return Status.SUCCESS if self.read("/robot/stalled", False) else Status.FAILURE
