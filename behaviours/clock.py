"""The clock handed to the tree: simulated time in the simulator, monotonic time on a robot.

Nothing below ``missions/`` reads ``time.monotonic()`` or sleeps; time-based behaviours call
``clock.now()`` on the clock they received at setup, so a 5 s timeout lasts 5 simulated seconds.
The wall clock lives in :mod:`missions.clocks`.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable


@runtime_checkable
class Clock(Protocol):
    """A source of time in seconds; only differences between readings are meaningful."""

    def now(self) -> float: ...


@runtime_checkable
class TickClock(Clock, Protocol):
    """The clock a runner ticks a tree on: it also knows how to get to the next tick.

    On a robot that means waiting for wall time (``missions.clocks.WallClock``); in the
    simulator it means stepping the world (``Simulation.clock()``): the simulator is a driver
    that the clock steps. ``timeline`` names the time axis in recordings.
    """

    timeline: str

    def next_tick(self, period: float) -> None:
        """Move to the start of the next tick, ``period`` seconds after the previous one."""


class ManualClock:
    """A clock that only moves when told: the unit-test clock, and a runner's clock without a world."""

    timeline = "sim_time"

    def __init__(self, start: float = 0.0) -> None:
        self._now = float(start)
        self._origin = float(start)
        self._ticks = 0

    def now(self) -> float:
        return self._now

    def advance(self, seconds: float) -> float:
        """Move time forward by ``seconds`` (>= 0) and return the new time."""
        if seconds < 0:
            raise ValueError("time cannot go backwards")
        self._now += seconds
        return self._now

    def set(self, seconds: float) -> None:
        """Jump to an absolute time not earlier than now."""
        if seconds < self._now:
            raise ValueError("time cannot go backwards")
        self._now = float(seconds)

    def next_tick(self, period: float) -> None:
        """Jump to the next tick: ``start + ticks * period`` (no drift from summing the period)."""
        self._ticks += 1
        self._now = max(self._now, self._origin + self._ticks * period)
