"""Wall-clock time for runs on a robot, and wall-clock pacing for simulated runs (``--realtime``,
or as soon as an operator drives by keys: :func:`paced_when_operated`).

The only place below the command line that reads ``time.monotonic()`` or sleeps for the tree:
behaviours see these clocks through the :class:`~behaviours.clock.Clock` protocol only.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from behaviours.clock import TickClock
from drivers.interfaces import KeyboardOpener, KeySource


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
    """A simulated clock held back to wall-clock speed (simulated time never runs ahead of wall time).

    ``engaged=False`` lets it run free until :meth:`engage` is called (by the keyboard opener of
    :func:`paced_when_operated`); from then on it keeps wall-clock speed.
    """

    def __init__(self, inner: TickClock, *, engaged: bool = True) -> None:
        self.inner = inner
        self.timeline = inner.timeline
        self._wall: WallClock | None = WallClock() if engaged else None

    @property
    def engaged(self) -> bool:
        return self._wall is not None

    def engage(self) -> None:
        """Keep wall-clock speed from now on (the schedule starts now)."""
        if self._wall is None:
            self._wall = WallClock()

    def now(self) -> float:
        return self.inner.now()

    def next_tick(self, period: float) -> None:
        self.inner.next_tick(period)
        if self._wall is not None:
            self._wall.next_tick(period)


def paced_when_operated(opener: KeyboardOpener, clock: Paced,
                        said: Callable[[str], None] | None = None) -> KeyboardOpener:
    """A keyboard opener that puts a simulated run at wall-clock speed when a node opens the keyboard.

    An operator drives in real time and a key holds its motion for a timeout of tree time: left to
    run free, the simulator ran a taught route seven times faster than the operator could steer
    and timed keys out before the terminal repeated them. Only a node that drives by keys and
    runs opens the keyboard, so a mission that could be driven by keys but is not (``teach_route``
    with ``drive=waypoints``) keeps its speed. ``said`` hears one line when pacing starts.
    """

    def open_keyboard() -> KeySource:
        keys = opener()
        if not clock.engaged:
            clock.engage()
            if said is not None:
                said("the keyboard drives: the simulation now runs in real time")
        return keys

    return open_keyboard
