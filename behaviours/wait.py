"""Waiting on the tree's clock."""

from __future__ import annotations

from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.ports import InputPort
from behaviours.registry import register


@register
class Wait(BearingsBehaviour):
    """RUNNING for ``duration`` seconds of tree time, then SUCCESS (the robot is not driven)."""

    DURATION = InputPort("duration", float, unit="s", doc="how long to wait", minimum=0.0)
    PORTS = (DURATION,)

    def initialise(self) -> None:
        self._until = self.now() + self.get_input(self.DURATION)

    def update(self) -> Status:
        remaining = self._until - self.now()
        if remaining > 1e-9:
            self.feedback_message = f"{remaining:.1f} s left"
            return Status.RUNNING
        return Status.SUCCESS
