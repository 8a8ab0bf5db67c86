"""Decorators that need the tree's clock or a blackboard guard.

py_trees' own ``Timeout`` reads ``time.monotonic()``; ours reads the clock handed to the tree at
setup, so timeouts last simulated seconds in the simulator and unit tests can step time by hand.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import py_trees
from py_trees.common import Status

from behaviours.base import NotSetUp
from behaviours.clock import Clock
from behaviours.comparison import compare


class _ClockedDecorator(py_trees.decorators.Decorator):
    """A decorator that receives the tree's clock at setup."""

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour) -> None:
        super().__init__(name=name, child=child)
        self._clock: Clock | None = None

    def setup(self, **kwargs: Any) -> None:
        self._clock = kwargs.get("clock", self._clock)

    def _tick_child(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """Tick the child and take its status (what these decorators do once they let it run)."""
        yield from self.decorated.tick()
        new_status = self.decorated.status
        if new_status != Status.RUNNING:
            self.stop(new_status)
        self.status = new_status
        yield self

    def update(self) -> Status:
        return self.decorated.status

    def now(self) -> float:
        if self._clock is None:
            raise NotSetUp(f"{self.name}: no clock; set the tree up with setup(clock=...)")
        return self._clock.now()


class Timeout(_ClockedDecorator):
    """FAILURE (and the child halted) once the child has run ``duration`` seconds of tree time.

    The deadline is checked before the child is ticked, as BehaviorTree.CPP does, so a child is
    never ticked after its time is up.
    """

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, duration: float) -> None:
        super().__init__(name=name, child=child)
        self.duration = float(duration)
        self._deadline = 0.0

    def initialise(self) -> None:
        self._deadline = self.now() + self.duration
        self.feedback_message = ""

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        if self.status != Status.RUNNING:
            self.initialise()
        if self.now() >= self._deadline:
            self.feedback_message = f"timed out after {self.duration:g} s"
            self.stop(Status.FAILURE)
            yield self
            return
        yield from self._tick_child()


class RateController(_ClockedDecorator):
    """Tick the child at most ``hz`` times per second of tree time; RUNNING in between.

    A child that finishes passes its status up at once; the next tick after that starts it again
    only when the period has elapsed (Nav2's RateController throttles the same way).
    """

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, hz: float) -> None:
        super().__init__(name=name, child=child)
        self.period = 1.0 / float(hz)
        self._last_tick: float | None = None

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        now = self.now()
        if self.status != Status.RUNNING:
            self.initialise()
        if self._last_tick is not None and now - self._last_tick < self.period - 1e-9:
            self.status = Status.RUNNING
            yield self
            return
        self._last_tick = now
        yield from self._tick_child()


def make_guard(name: str, child: py_trees.behaviour.Behaviour, key: str, op: str, value: Any):
    """A py_trees ``EternalGuard``: tick the child only while ``key op value`` holds, else FAILURE.

    An unset key counts as the condition not holding.
    """

    def condition(blackboard: py_trees.blackboard.Client) -> bool:
        try:
            current = blackboard.get(key)
        except KeyError:
            return False
        return compare(current, op, value)

    return py_trees.decorators.EternalGuard(
        name=name, child=child, condition=condition, blackboard_keys=[key.split(".", 1)[0]]
    )
