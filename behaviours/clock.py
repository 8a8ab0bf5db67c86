"""The clock handed to the tree: simulated time in the simulator, monotonic time on a robot.

Nothing below ``missions/`` reads ``time.monotonic()`` or sleeps; time-based behaviours call
``clock.now()`` on the clock they received at setup, so a 5 s timeout lasts 5 simulated seconds.
"""

from __future__ import annotations

import time
from typing import Protocol, runtime_checkable


@runtime_checkable
class Clock(Protocol):
    """A source of time in seconds; only differences between readings are meaningful."""

    def now(self) -> float: ...


class ManualClock:
    """A clock that only moves when told: the simulator's time and the unit-test clock."""

    def __init__(self, start: float = 0.0) -> None:
        self._now = float(start)

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


class MonotonicClock:
    """Wall time on a robot: ``time.monotonic()`` relative to the clock's creation."""

    def __init__(self) -> None:
        self._start = time.monotonic()

    def now(self) -> float:
        return time.monotonic() - self._start
