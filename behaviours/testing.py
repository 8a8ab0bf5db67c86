"""A harness to unit-test one behaviour (or a subtree): hand-set blackboard, manual clock.

Example::

    from py_trees.common import Status

    from behaviours.motion import Drive
    from behaviours.testing import BehaviourHarness
    from perception.geometry import Pose2D

    harness = BehaviourHarness(Drive(distance=1.0), blackboard={"/robot/odometry": Pose2D()})
    assert harness.tick() == Status.RUNNING
    assert harness.read("/robot/command").v > 0
    harness.write("/robot/odometry", Pose2D(x=1.0))
    harness.clock.advance(0.1)
    assert harness.tick() == Status.SUCCESS

Like the runner, the harness clears ``/robot/command`` and ``/ptu/command`` before each tick, so a
behaviour that stops commanding leaves no stale command behind.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import py_trees
from py_trees.common import Access, Status

from behaviours.clock import ManualClock
from drivers.interfaces import Robot

COMMAND_KEYS = ("/robot/command", "/ptu/command")


class BehaviourHarness:
    """Owns the blackboard and the clock of one behaviour under test."""

    def __init__(
        self,
        behaviour: py_trees.behaviour.Behaviour,
        *,
        blackboard: Mapping[str, Any] | None = None,
        clock: ManualClock | None = None,
        robot: Robot | None = None,
    ) -> None:
        py_trees.blackboard.Blackboard.storage.clear()  # values only: the behaviour's access stays
        self.behaviour = behaviour
        self.clock = clock or ManualClock()
        self.robot = robot
        self._client = py_trees.blackboard.Client(name="harness")
        for key, value in (blackboard or {}).items():
            self.write(key, value)
        for node in behaviour.iterate():
            node.setup(clock=self.clock, robot=robot)

    def write(self, key: str, value: Any) -> None:
        """Set a blackboard value, as the sense branch or another behaviour would."""
        self._ensure(key)
        self._client.set(key, value, overwrite=True)

    def read(self, key: str, default: Any = None) -> Any:
        """A blackboard value, or ``default`` when unset."""
        self._ensure(key)
        try:
            return self._client.get(key)
        except KeyError:
            return default

    def tick(self) -> Status:
        """One tick, like the runner's: command keys cleared first. Returns the new status."""
        for key in COMMAND_KEYS:
            self._ensure(key)
            self._client.unset(key)
        self.behaviour.tick_once()
        return self.behaviour.status

    def tick_until(
        self,
        done: Callable[[Status], bool] = lambda s: s != Status.RUNNING,
        *,
        dt: float = 0.1,
        max_ticks: int = 10_000,
        between: Callable[[BehaviourHarness], None] | None = None,
    ) -> Status:
        """Tick, advancing the clock by ``dt`` and calling ``between`` after each tick, until ``done``."""
        for _ in range(max_ticks):
            status = self.tick()
            if done(status):
                return status
            if between is not None:
                between(self)
            self.clock.advance(dt)
        raise AssertionError(f"{self.behaviour.name} still {self.behaviour.status.value} after {max_ticks} ticks")

    def halt(self) -> None:
        """Interrupt the behaviour as a higher-priority branch would."""
        self.behaviour.stop(Status.INVALID)

    def _ensure(self, key: str) -> None:
        if not self._client.is_registered(key=key):
            self._client.register_key(key=key, access=Access.WRITE)
