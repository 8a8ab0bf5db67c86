"""The progress of a run on stderr (``bearings run``): where the mission is, as it runs.

On a terminal one line is rewritten in place five times a second. When stderr is not a terminal
(a log file, a CI job, a pipe) nothing is printed unless ``--progress`` asks, and then a whole
line every :data:`LINE_EVERY_S` seconds of wall time, so that a long run (``learn_targets`` is
silent for minutes otherwise) shows it is alive without flooding the log.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, TextIO

LINE_EVERY_S = 5.0
"""Wall seconds between two progress lines when the output is not a terminal."""

REWRITE_EVERY_S = 0.2
"""Wall seconds between two rewrites of the progress line on a terminal."""


class Progress:
    """Called after every tick (the runner's ``on_tick``); :meth:`close` ends the line."""

    def __init__(self, mission: str, stream: TextIO, *, terminal: bool,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.mission = mission
        self.stream = stream
        self.terminal = terminal
        self.clock = clock
        self._last: float | None = None
        self._written = False

    def __call__(self, runner: Any) -> None:
        now = self.clock()
        every = REWRITE_EVERY_S if self.terminal else LINE_EVERY_S
        if self._last is not None and now - self._last < every:
            return
        self._last = now
        tip = runner.task.tip()
        active = "" if tip is None else tip.name + (f": {tip.feedback_message}" if tip.feedback_message else "")
        line = f"[{self.mission}] t={runner.clock.now():7.1f} s  tick {runner.ticks:6d}  {active}"
        if self.terminal:
            self.stream.write("\r" + line[:110].ljust(110))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()
        self._written = True

    def close(self) -> None:
        """End the rewritten line (so the summary starts on a line of its own)."""
        if self.terminal and self._written:
            self.stream.write("\n")
            self.stream.flush()


def progress_for(mission: str, stream: TextIO, *, asked: bool, quiet: bool) -> Progress | None:
    """The progress printer a run gets: on a terminal unless ``quiet``, elsewhere only when ``asked``."""
    terminal = stream.isatty()
    if quiet or not (terminal or asked):
        return None
    return Progress(mission, stream, terminal=terminal)
