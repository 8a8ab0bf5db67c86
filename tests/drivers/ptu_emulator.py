"""A PTU-D46 for the tests, speaking its ASCII protocol over a pty so :mod:`drivers.ptu_d46` runs as is.

Power-up state as on the unit: verbose feedback, echo on, a banner waiting in the buffer. It moves
each axis towards its target at the commanded speed (positions/s, times ``time_scale``), enforces
its position and speed limits with ``!`` errors, records every command with its time, and injects
faults: ``reply_delay`` (slow replies), ``mute`` (no replies at all), ``refuse`` (the next command
with a given name gets a ``!`` answer), ``inject_line`` (unsolicited text such as ``!P``),
``inject`` (raw bytes, no line end) and ``drop_link()``.

``home()`` (or the ``R`` command) resets the unit as flir_ptu_driver describes it: it finds its
limits, writing ``!T``, ``!T``, ``!P``, ``!P`` as it hits them and ``*`` when it is done, with no
line ends (``!T!T!P!P*`` on one line), then stands at its home position (0, 0). While it homes it
answers nothing (the commands are recorded with ``ignored=True``): the worst case a driver must
live with. See docs/protocols.md.
"""

from __future__ import annotations

import contextlib
import os
import select
import threading
import time
import tty
from dataclasses import dataclass

from drivers import ptu_d46_codec as codec
from tests.drivers.emulator_thread import EmulatorThread

BANNER = "PTU-D46 Controller (C) 1988-2010 DPerception, Inc. All Rights Reserved. v2.14.0"


HOMING_STEPS = ("!T", "!T", "!P", "!P", "*")


@dataclass(frozen=True)
class Command:
    t: float
    name: str
    value: float | None
    ignored: bool = False  # arrived while the unit was homing


@dataclass
class Axis:
    resolution: float
    low: int
    high: int
    slow: int
    fast: int
    position: float = 0.0
    target: float = 0.0
    speed: int = 1000

    def step(self, dt: float) -> None:
        gap = self.target - self.position
        travel = self.speed * dt
        self.position = self.target if abs(gap) <= travel else self.position + travel * (1 if gap > 0 else -1)


class PtuEmulator(EmulatorThread):
    THREAD_NAME = "ptu-emulator"

    def __init__(self, *, pan_resolution: float = 185.1428, tilt_resolution: float = 185.1428,
                 pan_limits: tuple[int, int] = (-3090, 3090), tilt_limits: tuple[int, int] = (-907, 604),
                 speed_bounds: tuple[int, int] = (57, 2902), time_scale: float = 1.0, reply_delay: float = 0.0,
                 banner: bool = True) -> None:
        super().__init__()
        self.axes = {"P": Axis(pan_resolution, *pan_limits, *speed_bounds),
                     "T": Axis(tilt_resolution, *tilt_limits, *speed_bounds)}
        self.time_scale = time_scale
        self.reply_delay = reply_delay
        self.terse = False
        self.echo = True
        self.limits_enabled = True
        self.mute = False
        self.commands: list[Command] = []
        self.homings = 0
        self._homing: list[tuple[float, str]] = []  # (when, what) still to be written by a reset
        self.refusals: dict[tuple[str, bool], str] = {}
        self.crashed: BaseException | None = None
        self._text = ""
        self._outbox: list[tuple[float, bytes]] = []
        self._lock = threading.RLock()
        self._last_step = time.monotonic()
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self.port = os.ttyname(self._slave)
        if banner:
            self._write(f"{BANNER}\r\n".encode())

    # -- life cycle ----------------------------------------------------------------------------------
    def _release(self) -> None:
        self.drop_link()


    # -- faults and queries --------------------------------------------------------------------------
    def drop_link(self) -> None:
        with self._lock:
            for name in ("_master", "_slave"):
                fd = getattr(self, name)
                if fd >= 0:
                    with contextlib.suppress(OSError):
                        os.close(fd)
                    setattr(self, name, -1)

    def inject_line(self, text: str) -> None:
        with self._lock:
            self._write(f"{text}\r\n".encode())

    def inject(self, text: str) -> None:
        """Write ``text`` as is (no line end)."""
        with self._lock:
            self._write(text.encode())

    def home(self, duration: float = 0.3) -> None:
        """Reset the unit: ``!T!T!P!P*`` spread over ``duration`` seconds, silent meanwhile."""
        with self._lock:
            self._start_homing(time.monotonic(), duration)

    @property
    def homing(self) -> bool:
        return bool(self._homing)

    def _start_homing(self, now: float, duration: float) -> None:
        step = duration / len(HOMING_STEPS)
        self._homing = [(now + step * (i + 1), text) for i, text in enumerate(HOMING_STEPS)]
        self._outbox.clear()  # a reset drops what was about to be said

    def refuse(self, name: str, message: str = "Illegal argument", *, query: bool = False) -> None:
        """Answer ``! message`` to the next ``name`` command that sets a value (or, with ``query``,
        to the next query)."""
        with self._lock:
            self.refusals[(name.upper(), query)] = message

    def named(self, name: str) -> list[Command]:
        with self._lock:
            return [c for c in self.commands if c.name == name]

    def position(self) -> tuple[float, float]:
        with self._lock:
            return self.axes["P"].position, self.axes["T"].position

    # -- the loop ----------------------------------------------------------------------------------
    def _loop(self) -> None:
        try:
            while self._running.is_set():
                data = self._read(0.003)
                now = time.monotonic()
                with self._lock:
                    if data:
                        self._receive(data.decode("ascii", errors="replace"), now)
                    dt = (now - self._last_step) * self.time_scale
                    self._last_step = now
                    for axis in self.axes.values():
                        axis.step(dt)
                    self._run_homing(now)
                    due = [p for t, p in self._outbox if t <= now]
                    self._outbox = [(t, p) for t, p in self._outbox if t > now]
                    for packet in due:
                        self._write(packet)
        except BaseException as exc:
            self.crashed = exc
            raise

    def _run_homing(self, now: float) -> None:
        while self._homing and self._homing[0][0] <= now:
            _, text = self._homing.pop(0)
            self._write(text.encode())
            if not self._homing:  # done: at home, default speed
                self.homings += 1
                for axis in self.axes.values():
                    axis.position = axis.target = 0.0
                    axis.speed = 1000

    def _receive(self, text: str, now: float) -> None:
        if self.echo:
            self._write(text.encode())
        self._text += text
        cut = max(self._text.rfind(" "), self._text.rfind("\r"), self._text.rfind("\n"))
        if cut < 0:
            return
        complete, self._text = self._text[: cut + 1], self._text[cut + 1 :]
        for name, value in codec.split_commands(complete):
            self.commands.append(Command(now, name, value, ignored=self.homing))
            if self.homing:
                continue
            if name == "R" and value is None:
                self._start_homing(now, 0.3)  # its "*" at the end is the answer
                continue
            reply = self._execute(name, value)
            if not self.mute:
                self._outbox.append((now + self.reply_delay, f"{reply}\r\n".encode()))

    def _execute(self, name: str, value: float | None) -> str:
        if (name, value is None) in self.refusals:
            return f"! {self.refusals.pop((name, value is None))}"
        if name in ("FT", "FV"):
            self.terse = name == "FT"
        elif name in ("ED", "EE"):
            self.echo = name == "EE"
        elif name in ("LE", "LD"):
            self.limits_enabled = name == "LE"
        elif name in ("CI", "I", "S", "A"):
            pass
        elif name in ("H", "HP", "HT"):
            for key in ("P", "T") if name == "H" else (name[1],):
                self.axes[key].target = self.axes[key].position
        elif name == "V":
            return f"* {BANNER}"
        elif len(name) == 2 and name[0] in self.axes and name[1] in "PRNXLUS":
            return self._axis_command(self.axes[name[0]], name, value)
        else:
            return "! Illegal command"
        return "*"

    def _axis_command(self, axis: Axis, name: str, value: float | None) -> str:
        what = {"P": "position", "R": "resolution", "N": "minimum position", "X": "maximum position",
                "L": "lower speed limit", "U": "upper speed limit", "S": "speed"}[name[1]]
        label = "Pan" if name[0] == "P" else "Tilt"
        if value is None:
            number = {"P": round(axis.position), "R": axis.resolution, "N": axis.low, "X": axis.high,
                      "L": axis.slow, "U": axis.fast, "S": axis.speed}[name[1]]
            return f"* {number}" if self.terse else f"* Current {label} {what} is {number}"
        if name[1] == "P":
            if self.limits_enabled and not axis.low <= value <= axis.high:
                return f"! {label} position out of range"
            axis.target = float(value)
            return "*"
        if name[1] == "S":
            if not axis.slow <= abs(value) <= axis.fast:
                return f"! {label} speed out of range"
            axis.speed = int(abs(value))
            return "*"
        return "! Illegal argument"

    # -- the link ----------------------------------------------------------------------------------
    def _read(self, timeout: float) -> bytes:
        if self._master < 0:
            time.sleep(timeout)
            return b""
        try:
            ready, _, _ = select.select([self._master], [], [], timeout)
            return os.read(self._master, 4096) if ready else b""
        except (BlockingIOError, InterruptedError):
            return b""
        except (OSError, ValueError):
            return b""

    def _write(self, data: bytes) -> None:
        if self._master < 0:
            return
        with contextlib.suppress(OSError):
            os.write(self._master, data)
