"""The safety monitor: the robot stops on a signal or a stuck tick, whatever the tree is doing.

The tick loop cannot guard itself: a behaviour that blocks (a ``sleep``, a device read without a
timeout, an endless loop) keeps the loop from ever checking a flag. So, as ARIA's
microcontroller watchdog and Nav2's controller timeouts do, the guard sits beside the loop:

- **signals** (SIGINT, SIGTERM): the Python handler stops the base at once and, during a tick,
  raises :class:`Interrupted` to unwind the blocked behaviour. Signals also wake the monitor's
  thread through ``signal.set_wakeup_fd``, so even when the main thread is stuck in C code and
  no Python handler can run, the thread stops the base within a few milliseconds; if the loop
  has still not ended after a grace period, the thread calls the runner's emergency exit (report
  written, process ends with the signal's exit code).
- **tick watchdog**: a tick that runs longer than its period plus ``overrun_limit`` stops the
  base from the monitor's thread and records which behaviour was running (read from the main
  thread's stack); the loop ends the run as FAILURE as soon as the tick returns.
"""

from __future__ import annotations

import contextlib
import os
import select
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from types import FrameType
from typing import Any

import py_trees

from drivers.interfaces import Robot

SIGNALS = (signal.SIGINT, signal.SIGTERM)
POLL_S = 0.01  # how often the monitor thread looks at the tick (s)
GRACE_S = 1.5  # after a signal, how long the loop may take to end before the emergency exit (s)


class Interrupted(BaseException):  # noqa: N818 - it is an interruption, not an error
    """Raised in the main thread by the signal handler to unwind a tick (not an Exception: nothing
    in a behaviour's ``except Exception`` may swallow it)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def exit_code(signum: int) -> int:
    """The conventional exit status of a process ended by ``signum`` (130 for SIGINT, 143 for SIGTERM)."""
    return 128 + int(signum)


def running_behaviour(thread_id: int) -> py_trees.behaviour.Behaviour | None:
    """The innermost py_trees behaviour on a thread's stack (the one that is blocking)."""
    frame: FrameType | None = sys._current_frames().get(thread_id)  # noqa: SLF001 - documented for debuggers
    while frame is not None:
        candidate = frame.f_locals.get("self")
        if isinstance(candidate, py_trees.behaviour.Behaviour):
            return candidate
        frame = frame.f_back
    return None


class SafetyMonitor:
    """Stops ``robot`` on signals and stuck ticks; use as a context manager around the tick loop."""

    def __init__(self, robot: Robot, *, period: float, overrun_limit: float | None,
                 emergency_exit: Callable[[int], None] | None = None) -> None:
        self.robot = robot
        self.tick_limit = None if overrun_limit is None else period + overrun_limit  # None: no tick watchdog
        self.emergency_exit = emergency_exit
        self.fault: str | None = None  # set by the tick watchdog
        self.signum: int | None = None  # the first signal received
        self._tick_started: float | None = None
        self._main = threading.main_thread().ident or 0
        self._stop = threading.Event()
        self._restore: list[Callable[[], None]] = []
        self._thread = threading.Thread(target=self._watch, name="bearings-safety", daemon=True)
        self._wake_r = self._wake_w = -1
        self._armed = False

    # -- the loop's side -------------------------------------------------------------------------
    def tick_started(self) -> None:
        self._tick_started = time.monotonic()

    def tick_finished(self) -> None:
        self._tick_started = None

    @property
    def stopped_reason(self) -> str | None:
        """Why the run must end now (a signal or the watchdog), or None."""
        if self.signum is not None:
            return f"interrupted by {signal.Signals(self.signum).name}"
        return self.fault

    # -- set-up ----------------------------------------------------------------------------------
    def __enter__(self) -> SafetyMonitor:
        if threading.current_thread() is threading.main_thread():
            self._install_signals()
        self._thread.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self._stop.set()
        self._thread.join(timeout=1.0)
        for restore in reversed(self._restore):
            with contextlib.suppress(Exception):
                restore()
        for fd in (self._wake_r, self._wake_w):
            if fd >= 0:
                os.close(fd)

    def disarm(self) -> None:
        """From now on signals are only recorded (the run is ending: nothing must be unwound)."""
        self._tick_started = None
        self._armed = False

    def _install_signals(self) -> None:
        self._armed = True
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_w, False)
        previous_fd = signal.set_wakeup_fd(self._wake_w, warn_on_full_buffer=False)
        previous = {sig: signal.signal(sig, self._on_signal) for sig in SIGNALS}

        def restore() -> None:
            for sig, handler in previous.items():
                signal.signal(sig, handler)
            signal.set_wakeup_fd(previous_fd)

        self._restore.append(restore)

    def _on_signal(self, signum: int, _frame: FrameType | None) -> None:
        first = self.signum is None
        if first:
            self.signum = signum
        self.robot.stop_all()
        if first and self._armed and self._tick_started is not None:
            raise Interrupted(signum)

    # -- the monitor thread ----------------------------------------------------------------------
    def _watch(self) -> None:
        deadline: float | None = None
        while not self._stop.is_set():
            if self._wake_r >= 0:
                ready, _, _ = select.select([self._wake_r], [], [], POLL_S)
                if ready and set(os.read(self._wake_r, 64)) & set(SIGNALS):
                    self.robot.stop_all()  # even if the main thread cannot run the Python handler
                    deadline = deadline or time.monotonic() + GRACE_S
            else:
                self._stop.wait(POLL_S)
            self._check_tick()
            if deadline is not None and time.monotonic() > deadline and self.emergency_exit is not None:
                self.emergency_exit(self.signum or signal.SIGTERM)
                return

    def _check_tick(self) -> None:
        started = self._tick_started
        if started is None or self.fault is not None or self.tick_limit is None:
            return
        elapsed = time.monotonic() - started
        if elapsed > self.tick_limit:
            node = running_behaviour(self._main)
            where = f" in {node.name} ({type(node).__name__})" if node is not None else ""
            self.fault = (f"tick watchdog: a tick ran longer than {self.tick_limit:.2f} s{where}; the base was "
                          "stopped")
            self.robot.stop_all()


@contextlib.contextmanager
def early_signals() -> Iterator[None]:
    """Until the runner's monitor takes over: SIGINT/SIGTERM raise :class:`Interrupted` (loading
    a world or opening a robot can be interrupted, and the command still reports it)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, _frame: FrameType | None) -> None:
        raise Interrupted(signum)

    previous = {sig: signal.signal(sig, handler) for sig in SIGNALS}
    try:
        yield
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)
