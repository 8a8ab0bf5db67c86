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
from behaviours.ports import COMPARISONS, InputPort, Key
from behaviours.registry import Declared, register


class _ClockedDecorator(Declared, py_trees.decorators.Decorator):
    """A decorator that receives the tree's clock at setup."""

    KIND = "decorator"
    CHILDREN = (1, 1)

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


@register
class Timeout(_ClockedDecorator):
    """FAILURE, halting the child, when it runs longer than duration (tree clock).

    The deadline is checked before the child is ticked, as BehaviorTree.CPP does, so a child is
    never ticked after its time is up.
    """

    DURATION = InputPort("duration", float, unit="s", minimum=0.0, literal_only=True, doc="time limit in tree time")
    PORTS = (DURATION,)

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, duration: float) -> None:
        super().__init__(name=name, child=child)
        self.duration = duration
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


@register
class RateController(_ClockedDecorator):
    """Tick the child at most hz times per second (tree clock); RUNNING in between.

    A child that finishes passes its status up at once; the next tick after that starts it again
    only when the period has elapsed (Nav2's RateController throttles the same way).
    """

    HZ = InputPort("hz", float, unit="Hz", minimum=1e-6, literal_only=True, doc="highest tick rate of the child")
    PORTS = (HZ,)

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, hz: float) -> None:
        super().__init__(name=name, child=child)
        self.period = 1.0 / hz
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


GUARD_KEY = InputPort("key", Key, literal_only=True, doc="blackboard key (absolute), optionally with an attribute: "
                      "/robot/odometry.x")
GUARD_OP = InputPort("op", str, "==", choices=COMPARISONS, literal_only=True, doc="comparison")
GUARD_VALUE = InputPort("value", object, literal_only=True, doc="the value to compare with")
GUARD_PORTS = (GUARD_KEY, GUARD_OP, GUARD_VALUE)
"""``key op value``: the condition of a ``Guard`` and of a ``CheckBlackboard``."""


@register
class Guard(Declared, py_trees.decorators.EternalGuard):
    """Tick the child only while the blackboard condition holds; FAILURE otherwise.

    A py_trees ``EternalGuard`` on ``key op value``; an unset key counts as the condition not
    holding.
    """

    KIND = "decorator"
    PORTS = GUARD_PORTS
    BTCPP = "Precondition"
    CHILDREN = (1, 1)

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, key: str, op: str = "==", value: Any = None
                 ) -> None:
        def condition(blackboard: py_trees.blackboard.Client) -> bool:
            try:
                current = blackboard.get(key)
            except KeyError:
                return False
            return compare(current, op, value)

        super().__init__(name=name, child=child, condition=condition, blackboard_keys=[key.split(".", 1)[0]])
        self.key, self.op, self.value = key, op, value
