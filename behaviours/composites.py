"""Composites py_trees does not have: Nav2's ``RecoveryNode``."""

from __future__ import annotations

from collections.abc import Iterator

import py_trees
from py_trees.common import Status

from behaviours.ports import InputPort
from behaviours.registry import Declared, register


@register
class RecoveryNode(Declared, py_trees.composites.Composite):
    """Nav2 recovery: tick the task; on failure tick the recovery and retry the task.

    Nav2 semantics: SUCCESS when the first child succeeds; when it fails and fewer than
    ``number_of_retries`` recoveries have run, tick the recovery: its SUCCESS starts the first
    child afresh, its FAILURE fails the node. FAILURE once the retries are used up.
    """

    KIND = "composite"
    NUMBER_OF_RETRIES = InputPort("number_of_retries", int, 1, minimum=0, literal_only=True, doc="recoveries to try")
    PORTS = (NUMBER_OF_RETRIES,)
    CHILDREN = (2, 2)

    def __init__(
        self, name: str, children: list[py_trees.behaviour.Behaviour], number_of_retries: int = 1
    ) -> None:
        if len(children) != 2:
            raise ValueError("RecoveryNode takes exactly two children: the task and its recovery")
        super().__init__(name=name, children=children)
        self.number_of_retries = number_of_retries
        self.retries = 0
        self._in_recovery = False

    def initialise(self) -> None:
        self.retries = 0
        self._in_recovery = False

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        if self.status != Status.RUNNING:
            self.initialise()
        task, recovery = self.children
        while True:
            if not self._in_recovery:
                self.current_child = task
                yield from task.tick()
                if task.status == Status.RUNNING:
                    self.status = Status.RUNNING
                    break
                if task.status == Status.SUCCESS:
                    self.stop(Status.SUCCESS)
                    break
                if self.retries >= self.number_of_retries:
                    self.feedback_message = f"failed after {self.retries} recoveries"
                    self.stop(Status.FAILURE)
                    break
                self._in_recovery = True
            self.current_child = recovery
            yield from recovery.tick()
            if recovery.status == Status.RUNNING:
                self.status = Status.RUNNING
                break
            if recovery.status == Status.FAILURE:
                self.feedback_message = "recovery failed"
                self.stop(Status.FAILURE)
                break
            self.retries += 1
            self._in_recovery = False
            task.stop(Status.INVALID)  # start the task afresh in the same tick
        yield self

    def stop(self, new_status: Status = Status.INVALID) -> None:
        for child in self.children:
            if child.status == Status.RUNNING:
                child.stop(Status.INVALID)
        self._in_recovery = False
        super().stop(new_status)
