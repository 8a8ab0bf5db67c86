"""FLIR/DPerception PTU-D46 pan-tilt unit over its ASCII protocol: implements ``PanTilt``.

``open_ptu(PtuD46Settings(port="/dev/ttyUSB1"))`` opens the port and initialises the unit as
flir_ptu_driver does (docs/protocols.md): terse feedback (``FT``), echo off (``ED``), then anything the unit
printed (power-up banner, echoed text) is flushed, position control (``CI``), and the resolution
(``PR`` then ``TR``), position limits (``PN PX TN TX``), speed bounds (``PL PU TL TU``), version
(``V``) and current position are queried. Then one I/O thread owns the port: it sends the newest
requested move (older ones are dropped), and otherwise reads the position back (``PP``/``TP``)
every ``poll_period``. ``move()``, ``halt()`` and ``state()`` return at once.

- Targets outside the unit's limits (or the profile's tighter ``*_min_deg``/``*_max_deg``) raise
  ``ValueError`` in ``move()`` before anything is sent; speeds are clamped to the unit's bounds.
  ``state()`` carries those limits, the position step and the speed bounds
  (:class:`~drivers.interfaces.PanTiltLimits`) and the ``homings`` count, so head behaviours keep
  inside what this unit reports and notice a reset.
- A ``!`` reply to a command is kept in ``last_error`` (``errors`` counts them) and raised once
  as :class:`PtuError` from the next ``move()`` or ``state()``.
- What the unit sends is read as a stream of ``*``/``!`` messages, not lines
  (:class:`~drivers.ptu_d46_codec.MessageReader`). Unsolicited ones are tolerated: ``!P``/``!T``
  (limit hit) are counted in ``limit_hits``, text outside a message is ignored.
- A unit that resets (power glitch, ``R``) homes: it hits its limits (``!T!T!P!P``), may stay
  silent meanwhile, and ends with ``*``. Missing replies after a limit hit do not count as a lost
  link for ``homing_timeout``; when the homing ends (``homings`` counts them) the last move is sent
  again, since the unit is back at its home position.
- ``max_timeouts`` replies missing in a row, or a read/write error, is a lost link: ``fault`` is
  set and ``move()``/``state()`` raise :class:`DriverFault`. ``halt()`` and ``close()`` never raise.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import math
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Literal

import serial
from pydantic import BaseModel, ConfigDict, Field

from drivers import ptu_d46_codec as codec
from drivers.common import DriverFault, Stamp, build_settings, monotonic_stamp, quantity
from drivers.interfaces import PanTiltLimits, PanTiltState

log = logging.getLogger(__name__)

READ_TIMEOUT_S = 0.01
WRITE_TIMEOUT_S = 0.5


class PtuD46Settings(BaseModel):
    """A PTU-D46 in a robot profile (``ptu: {driver: ptu_d46, port: /dev/ttyUSB1}``)."""

    model_config = ConfigDict(extra="forbid")

    port: str = Field(min_length=1, description="serial device or pyserial URL of the unit's host port")
    baud: Literal[600, 1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200] = Field(
        9600, description="serial speed [bit/s] (the unit's default is 9600 8N1)", json_schema_extra={"unit": "bit/s"})
    reply_timeout: float = quantity(0.5, "wait for the reply to one command", "s", ge=0.02, le=5.0)
    max_timeouts: int = Field(3, ge=1, le=20, description="missing replies in a row that count as a lost link")
    poll_period: float = quantity(0.1, "period of the position read-back", "s", ge=0.02, le=2.0)
    init_settle: float = quantity(0.2, "after FT and ED, how long to let the unit's replies and power-up "
                                  "text arrive before they are flushed", "s", ge=0.0, le=5.0)
    homing_timeout: float = quantity(30.0, "after an unsolicited limit hit (the unit homing after a reset), how "
                                     "long missing replies are waited for before they count as a lost link",
                                     "s", ge=1.0, le=120.0)
    pan_min_deg: float | None = quantity(None, "soft pan limit tighter than the unit's", "deg", ge=-180, le=180)
    pan_max_deg: float | None = quantity(None, "soft pan limit tighter than the unit's", "deg", ge=-180, le=180)
    tilt_min_deg: float | None = quantity(None, "soft tilt limit tighter than the unit's", "deg", ge=-90, le=90)
    tilt_max_deg: float | None = quantity(None, "soft tilt limit tighter than the unit's", "deg", ge=-90, le=90)


class PtuError(DriverFault):
    """The unit answered ``!`` to a command (raised once, from the next move() or state())."""


@dataclass(frozen=True, slots=True)
class AxisLimits:
    """One axis: resolution (arc-seconds per position), position and speed bounds in positions."""

    resolution: float
    min_pos: int
    max_pos: int
    min_speed: int
    max_speed: int

    @property
    def min_rad(self) -> float:
        return codec.to_radians(self.min_pos, self.resolution)

    @property
    def max_rad(self) -> float:
        return codec.to_radians(self.max_pos, self.resolution)


@dataclass(frozen=True, slots=True)
class PtuLimits:
    pan: AxisLimits
    tilt: AxisLimits


class _Timeout(Exception):
    pass


class _Homing(_Timeout):
    """No reply while the unit is homing (limit hits seen, its closing ``*`` not yet)."""


class _Refused(Exception):
    pass


class PtuD46:
    """A connected PTU-D46; build it with :func:`open_ptu`."""

    def __init__(self, settings: PtuD46Settings, *, clock: Stamp | None = None,
                 port_factory: Callable[..., Any] | None = None) -> None:
        self.settings = settings
        self.fault: str | None = None
        self.last_error: str | None = None
        self.errors = 0
        self.limit_hits = 0
        self.timeouts = 0
        self.late_replies = 0
        self.homings = 0
        self.version = ""
        self.limits: PtuLimits | None = None
        self._stamp = monotonic_stamp(clock)
        self._port_factory = port_factory or serial.serial_for_url
        self._serial: Any = None
        self._messages = codec.MessageReader()
        self._unraised_error: str | None = None
        self._state = PanTiltState()
        self._positions = (0, 0)
        self._target: tuple[int, int] | None = None
        self._pending_move: tuple[int, int, int, int] | None = None  # pan, tilt, pan speed, tilt speed
        self._pending_halt = False
        self._last_move: tuple[int, int, int, int] | None = None  # sent again after the unit homed
        self._homing_since: float | None = None  # first limit hit of a reset still in progress
        self._speeds: tuple[int | None, int | None] = (None, None)
        self._missed = 0
        self._lock = threading.RLock()
        self._wake = threading.Event()
        self._closing = threading.Event()
        self._thread: threading.Thread | None = None
        self._closed = False

    # -- the PanTilt interface ---------------------------------------------------------------------
    def move(self, pan: float, tilt: float, speed: float) -> None:
        """Start moving to ``pan``/``tilt`` (rad) at ``speed`` (rad/s); ValueError outside the limits."""
        self._check()
        if not all(math.isfinite(x) for x in (pan, tilt, speed)) or speed <= 0:
            raise ValueError(f"move({pan}, {tilt}, {speed}): angles must be finite and the speed positive")
        limits = self._limits()
        pan_pos = self._position("pan", pan, limits.pan, self.settings.pan_min_deg, self.settings.pan_max_deg)
        tilt_pos = self._position("tilt", tilt, limits.tilt, self.settings.tilt_min_deg, self.settings.tilt_max_deg)
        pan_speed = _clamp(codec.to_positions(speed, limits.pan.resolution), limits.pan.min_speed, limits.pan.max_speed)
        tilt_speed = _clamp(codec.to_positions(speed, limits.tilt.resolution), limits.tilt.min_speed,
                            limits.tilt.max_speed)
        with self._lock:
            self._pending_move = (pan_pos, tilt_pos, pan_speed, tilt_speed)
            self._target = (pan_pos, tilt_pos)
            self._publish(moving=True)
        self._wake.set()

    def halt(self) -> None:
        """Stop both axes where they are (``H``); never raises."""
        with self._lock:
            self._pending_move = None
            self._pending_halt = True
            self._target = None
        self._wake.set()

    def state(self) -> PanTiltState:
        """The newest read-back position (rad) and whether the unit is still on its way."""
        self._check()
        return self._state

    def close(self) -> None:
        """Halt, stop the I/O thread and release the port; never raises."""
        if self._closed:
            return
        self._closed = True
        self.halt()
        deadline = time.monotonic() + 2 * self.settings.reply_timeout
        while self._pending_halt and self._thread is not None and self._thread.is_alive() \
                and time.monotonic() < deadline:
            time.sleep(0.005)
        self._closing.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout=2 * self.settings.reply_timeout + 0.5)
        if self.fault is None:
            self.fault = "the pan-tilt unit is closed"
        self._release_port()

    # -- accessors ---------------------------------------------------------------------------------
    def describe(self) -> str:
        return f"ptu_d46 on {self.settings.port}"

    def positions(self) -> tuple[int, int]:
        """Newest read-back position in the unit's counts (pan, tilt)."""
        return self._positions

    def limit_degrees(self) -> dict[str, tuple[float, float]]:
        """``{"pan": (min, max), "tilt": (min, max)}`` in degrees (the unit's, before soft limits)."""
        limits = self._limits()
        return {name: (math.degrees(axis.min_rad), math.degrees(axis.max_rad))
                for name, axis in (("pan", limits.pan), ("tilt", limits.tilt))}

    # -- opening -----------------------------------------------------------------------------------
    def connect(self) -> PtuD46:
        port = self.settings.port
        try:
            self._serial = self._port_factory(port, baudrate=self.settings.baud, timeout=READ_TIMEOUT_S,
                                              write_timeout=WRITE_TIMEOUT_S)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise ConnectionError(f"cannot open the PTU-D46 port {port}: {exc}") from None
        try:
            self._initialise()
        except _Refused as exc:
            self._release_port()
            raise ConnectionError(f"the PTU-D46 on {port} refused {exc} while initialising") from None
        except _Timeout as exc:
            self._release_port()
            homing = " (it is homing)" if isinstance(exc, _Homing) else ""
            raise TimeoutError(f"the PTU-D46 on {port}{homing} did not answer {exc} within "
                               f"{self.settings.reply_timeout:g} s (unit off, wrong port or baud?)") from None
        except (serial.SerialException, OSError) as exc:
            self._release_port()
            raise ConnectionError(f"the PTU-D46 on {port} failed during initialisation: {exc}") from None
        except BaseException:
            self._release_port()
            raise
        self._thread = threading.Thread(target=self._run, name=f"ptu-d46 {port}", daemon=True)
        self._thread.start()
        return self

    def _initialise(self) -> None:
        for command in ("FT", "ED"):  # replies may carry echoed text: flushed below, not parsed
            self._serial.write(codec.encode(command))
            self._drain(self.settings.init_settle / 2)
        self._expect("CI")
        pan_res = self._query("PR")
        tilt_res = self._query("TR")  # one after the other: the replies look alike
        if not (pan_res > 0 and tilt_res > 0):
            raise ConnectionError(f"the PTU-D46 on {self.settings.port} reports a resolution of "
                                  f"{pan_res}/{tilt_res} arc-seconds")
        axes = []
        for prefix, res in (("P", pan_res), ("T", tilt_res)):
            low, high = int(self._query(prefix + "N")), int(self._query(prefix + "X"))
            slow, fast = int(self._query(prefix + "L")), int(self._query(prefix + "U"))
            axes.append(codec_axis(res, low, high, slow, fast))
        self.limits = PtuLimits(*axes)
        self.version = self._expect("V", "any").text.lstrip("* ").strip()
        self._read_positions()

    def _drain(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self._serial.read(self._serial.in_waiting or 1)
        self._serial.reset_input_buffer()
        self._messages.reset()

    # -- the I/O thread ----------------------------------------------------------------------------
    def _run(self) -> None:
        next_poll = time.monotonic()
        while not self._closing.is_set():
            try:
                next_poll = self._cycle(next_poll)
            except (serial.SerialException, OSError) as exc:
                self._set_fault(f"link to the PTU-D46 on {self.settings.port} lost: {exc}")
                return
            except Exception as exc:  # noqa: BLE001 - report a driver bug as the fault, never crash silently
                self._set_fault(f"PTU-D46 driver error: {type(exc).__name__}: {exc}")
                return

    def _cycle(self, next_poll: float) -> float:
        with self._lock:
            halt, self._pending_halt = self._pending_halt, False
            move = None if halt else self._pending_move
            self._pending_move = None
            if halt:
                self._last_move = None
        try:
            if halt:
                self._command("H")
            elif move is not None:
                self._send_move(move)
            elif time.monotonic() >= next_poll:
                self._read_positions()
                next_poll = time.monotonic() + self.settings.poll_period
            else:
                self._wake.wait(max(0.0, next_poll - time.monotonic()))
                self._wake.clear()
                return next_poll
            self._missed = 0
        except _Refused as exc:
            self._missed = 0
            self._record_error(str(exc))
        except _Homing as exc:
            self._missed = 0
            log.info("PTU-D46: no reply to %s while the unit homes", exc)
        except _Timeout as exc:
            self.timeouts += 1
            self._missed += 1
            log.warning("PTU-D46: no reply to %s", exc)
            if self._missed >= self.settings.max_timeouts:
                raise serial.SerialException(f"{self._missed} replies missing in a row (last: {exc})") from None
        return next_poll

    def _send_move(self, move: tuple[int, int, int, int]) -> None:
        self._last_move = move
        pan, tilt, pan_speed, tilt_speed = move
        if self._speeds[0] != pan_speed and self._command("PS", pan_speed):
            self._speeds = (pan_speed, self._speeds[1])
        if self._speeds[1] != tilt_speed and self._command("TS", tilt_speed):
            self._speeds = (self._speeds[0], tilt_speed)
        self._command("PP", pan)
        self._command("TP", tilt)

    def _read_positions(self) -> None:
        pan = int(self._query("PP"))
        tilt = int(self._query("TP"))
        with self._lock:
            self._positions = (pan, tilt)
            target = self._target
            if target is not None and abs(target[0] - pan) <= 1 and abs(target[1] - tilt) <= 1:
                self._target = None
            self._publish(moving=self._target is not None)

    def _publish(self, *, moving: bool) -> None:
        limits = self.limits
        if limits is None:
            return
        pan, tilt = self._positions
        self._state = PanTiltState(codec.to_radians(pan, limits.pan.resolution),
                                   codec.to_radians(tilt, limits.tilt.resolution), moving, self._stamp(),
                                   self._reported, self.homings)

    @functools.cached_property
    def _reported(self) -> PanTiltLimits:
        """The limits a behaviour must keep to: the unit's, within the profile's soft limits (rad)."""
        limits, s = self._limits(), self.settings

        def bounds(axis: AxisLimits, low: float | None, high: float | None) -> tuple[float, float]:
            return (max(axis.min_rad, -math.inf if low is None else math.radians(low)),
                    min(axis.max_rad, math.inf if high is None else math.radians(high)))

        pan, tilt = limits.pan, limits.tilt
        return PanTiltLimits(bounds(pan, s.pan_min_deg, s.pan_max_deg), bounds(tilt, s.tilt_min_deg, s.tilt_max_deg),
                             codec.to_radians(1, pan.resolution), codec.to_radians(1, tilt.resolution),
                             min(codec.to_radians(pan.max_speed, pan.resolution),
                                 codec.to_radians(tilt.max_speed, tilt.resolution)),
                             max(codec.to_radians(pan.min_speed, pan.resolution),
                                 codec.to_radians(tilt.min_speed, tilt.resolution)))

    # -- one command, one reply ----------------------------------------------------------------------
    def _command(self, name: str, value: int | None = None) -> bool:
        """Send a command; True on ``*``; a ``!`` reply is recorded and surfaced, False returned."""
        reply = self._transact(codec.encode(name, value), "ack")
        if reply.kind == "error":
            self._record_error(f"{name}{'' if value is None else value}: {reply.text}")
            return False
        return True

    def _record_error(self, text: str) -> None:
        self.errors += 1
        self.last_error = text
        self._unraised_error = text
        log.warning("PTU-D46 refused %s", text)

    def _expect(self, name: str, shape: str = "ack") -> codec.Reply:
        reply = self._transact(codec.encode(name), shape)
        if reply.kind != "ok":
            raise _Refused(f"{name}: {reply.text}")
        return reply

    def _query(self, name: str) -> float:
        reply = self._expect(name, "value")
        if reply.value is None:
            raise ConnectionError(f"the PTU-D46 on {self.settings.port} answered {name} without a number: "
                                  f"{reply.text!r}")
        return reply.value

    def _transact(self, data: bytes, shape: str) -> codec.Reply:
        """Write one command and wait for its ``*``/``!`` line; unsolicited lines are skipped.

        ``shape`` is what a reply to this command looks like: ``ack`` (a bare ``*``), ``value``
        (``* number``) or ``any``; a ``*`` line of the other shape is a late reply to an earlier
        command (the unit was slow) and is skipped, so one slow reply does not shift all later ones.
        """
        self._skip_pending()
        self._serial.write(data)
        deadline = time.monotonic() + self.settings.reply_timeout
        answer: codec.Reply | None = None
        while answer is None and time.monotonic() < deadline:
            chunk = self._serial.read(self._serial.in_waiting or 1)
            for reply in self._messages.feed(chunk) if chunk else self._messages.idle():
                if answer is None and (reply.kind == "error" or (reply.kind == "ok" and _fits(reply, shape))):
                    answer = reply
                else:
                    self._note_unsolicited(reply)
        what = data.decode("ascii").strip()
        if answer is not None:
            self._homing_since = None
            return answer
        if self._homing_since is not None and time.monotonic() - self._homing_since < self.settings.homing_timeout:
            raise _Homing(what)
        raise _Timeout(what)

    def _note_unsolicited(self, reply: codec.Reply) -> None:
        """A message that answers nothing we wait for: count limit hits and late replies, follow a
        reset's homing, ignore noise."""
        if reply.kind == "limit":
            self.limit_hits += 1
            self._homing_since = self._homing_since or time.monotonic()
            log.info("PTU-D46 reports a %s limit hit", reply.axis)
        elif reply.kind == "homed":
            self._homed()
        elif reply.kind in ("ok", "error"):
            self.late_replies += 1
            self._homing_since = None

    def _homed(self) -> None:
        """The unit reset and homed: it is at its home position with its default speeds; the last
        move is sent again."""
        self.homings += 1
        self._homing_since = None
        log.warning("PTU-D46 on %s reset and homed; sending the last move again", self.settings.port)
        with self._lock:
            self._speeds = (None, None)
            if self._last_move is not None and self._pending_move is None and not self._pending_halt:
                self._pending_move = self._last_move
                self._target = self._last_move[:2]
                self._publish(moving=True)
        self._wake.set()

    def _skip_pending(self) -> None:
        """Before a command: read what is waiting (unsolicited messages, late replies) so it cannot be
        taken for this command's reply; a half-received message is dropped."""
        while self._serial.in_waiting:
            for reply in self._messages.feed(self._serial.read(self._serial.in_waiting)):
                self._note_unsolicited(reply)
        for reply in self._messages.idle():
            self._note_unsolicited(reply)
        self._messages.clear()

    # -- helpers -----------------------------------------------------------------------------------
    def _position(self, axis: str, angle: float, limits: AxisLimits, soft_min: float | None,
                  soft_max: float | None) -> int:
        low, high = limits.min_rad, limits.max_rad
        if soft_min is not None:
            low = max(low, math.radians(soft_min))
        if soft_max is not None:
            high = min(high, math.radians(soft_max))
        if not low - 1e-9 <= angle <= high + 1e-9:
            raise ValueError(f"{axis} {math.degrees(angle):.2f} deg is outside the limits "
                             f"[{math.degrees(low):.2f}, {math.degrees(high):.2f}] deg")
        return _clamp(codec.to_positions(angle, limits.resolution), limits.min_pos, limits.max_pos)

    def _limits(self) -> PtuLimits:
        if self.limits is None:
            raise DriverFault("the pan-tilt unit is not initialised")
        return self.limits

    def _check(self) -> None:
        if self.fault is not None:
            raise DriverFault(self.fault)
        error, self._unraised_error = self._unraised_error, None
        if error is not None:
            raise PtuError(f"the pan-tilt unit refused {error}")

    def _set_fault(self, reason: str) -> None:
        if self.fault is None:
            self.fault = reason
            log.error("PTU-D46 fault: %s", reason)

    def _release_port(self) -> None:
        port, self._serial = self._serial, None
        if port is not None:
            with contextlib.suppress(Exception):
                port.close()


def codec_axis(resolution: float, low: int, high: int, slow: int, fast: int) -> AxisLimits:
    """Axis limits from the unit's answers (bounds given in either order)."""
    return AxisLimits(resolution, min(low, high), max(low, high), max(0, min(slow, fast)), max(slow, fast))


def _fits(reply: codec.Reply, shape: str) -> bool:
    return shape == "any" or (reply.value is None) == (shape == "ack")


def _clamp(value: int, low: int, high: int) -> int:
    return max(low, min(high, value))


def open_ptu(settings: PtuD46Settings | Mapping[str, Any] | None = None, /, *, clock: Stamp | None = None,
             **fields: Any) -> PtuD46:
    """Open and initialise a PTU-D46; raise ``OSError`` when it cannot be reached or initialised.

    Takes a :class:`PtuD46Settings`, a mapping of its fields, or the fields as keyword arguments
    (as ``missions.profiles.open_robot`` passes them today); ``clock`` stamps the state.
    """
    model = build_settings(PtuD46Settings, settings, fields, where="ptu (ptu_d46)")
    return PtuD46(model, clock=clock).connect()
