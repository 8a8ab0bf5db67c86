"""A child node for testing control nodes: it returns the statuses it is given and counts ticks and halts."""

from __future__ import annotations

import py_trees
from py_trees.common import Status


class Scripted(py_trees.behaviour.Behaviour):
    """Returns the statuses it is given, one per tick (the last one repeats); counts ticks and halts."""

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
