"""Wall-clock time for runs on a robot, and wall-clock pacing for simulated runs (``--realtime``).

The only place below the command line that reads ``time.monotonic()`` or sleeps for the tree:
behaviours see these clocks through the :class:`~behaviours.clock.Clock` protocol only.
"""

from __future__ import annotations

import time

from behaviours.clock import TickClock


class WallClock:
    """Monotonic time since the clock was made; :meth:`next_tick` sleeps until the tick is due.

    A tick that ran late does not make the next ones run early to catch up: the schedule
    restarts from now (a robot should not get a burst of commands after a stall).
    """

    timeline = "wall_time"

    def __init__(self) -> None:
        self._start = time.monotonic()
        self._due = self._start

    def now(self) -> float:
        return time.monotonic() - self._start

    def next_tick(self, period: float) -> None:
        self._due += period
        late = time.monotonic() - self._due
        if late > period:
            self._due = time.monotonic()
        elif late < 0:
            time.sleep(-late)


class Paced:
    """A simulated clock held back to wall-clock speed (simulated time never runs ahead of wall time)."""

    def __init__(self, inner: TickClock) -> None:
        self.inner = inner
        self.timeline = inner.timeline
        self._wall = WallClock()

    def now(self) -> float:
        return self.inner.now()

    def next_tick(self, period: float) -> None:
        self.inner.next_tick(period)
        self._wall.next_tick(period)
