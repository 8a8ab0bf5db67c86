"""Pioneer 3-DX / 3-AT base over ARCOS (pyserial): implements :class:`drivers.interfaces.Base`.

``open_base(PioneerSettings(port="/dev/ttyUSB0"))`` opens the port (any pyserial URL:
``socket://localhost:8101`` reaches MobileSim/AMRISim) and runs the connection sequence as ARIA
does (docs/protocols.md): SYNC0-2, restarting at SYNC0 on anything out of sequence (CLOSE first if
the robot is still open from an earlier session; after two silent tries on a serial device, CLOSE
at every speed, for a robot left at another speed); the conversion factors of the subclass the
robot reports in SYNC2 (``model_override`` may force others, and says so); a pause of one SIP
cycle, OPEN; CONFIG; HOSTBAUD to ``switch_baud`` when the config packet allows it (back to
``baud`` if nothing answers at the new speed within 0.9 s); SONAR; ENABLE 1. It waits for the
first SIP and starts one I/O thread. That thread alone reads the port: it parses SIPs into an immutable
:class:`BaseStatus`, re-sends the current VEL/RVEL every ``resend_period`` (<= 0.5 s, so the
robot's 2 s watchdog never fires while the link is up), and watches for faults. ``drive()``,
``odometry()`` and ``stalled()`` only swap or read Python objects and return at once.

Faults (see also :mod:`drivers.common`):

- no SIP for ``sip_timeout`` (0.5 s), a read/write error, a closed socket or pty: the thread
  sends STOP and ENABLE 0 at once (best effort: a dead link cannot carry them, and then the
  robot's own watchdog stops it) and sets ``fault``; ``drive()``/``odometry()``/``stalled()``
  raise :class:`DriverFault` from then on. With ``reconnect: true`` a lost link is retried for
  ``reconnect_timeout`` first; meanwhile the pose is held (its stamp ages) and commands are
  dropped, and after reconnecting the base waits for a fresh ``drive()``.
- ``stop()`` writes STOP, VEL 0 and RVEL 0 from the calling thread at once (it does not wait for
  the I/O thread) and never raises; ``close()`` stops, disables the motors (ENABLE 0), pauses one
  SIP cycle and sends CLOSE. Bases still open when the interpreter exits are closed by an
  ``atexit`` hook.
- no ``drive()`` call for ``command_timeout`` while moving (a stuck tick loop): the thread
  commands zero velocity itself; the next ``drive()`` resumes (``deadman_stops`` counts these).
- a pressed bumper: the SIP that carries it stops a command that moves towards it at once, from
  the I/O thread (STOP, VEL 0, RVEL 0; ``bumper_stops`` counts these), as ARIA's bumpers action
  does, without waiting for the next tick; while it stays pressed, ``drive()`` refuses motion
  towards it (motion away, or a turn, passes).

Sensing: ``range_source()`` is the robot's :class:`~drivers.interfaces.RangeSource` for the
collision monitor: the sonar ring with the geometry of the model the robot reports and the
bumpers (:mod:`drivers.pioneer_body`, from ARIA's parameter files); a transducer not heard for
``sonar_timeout`` reads as no data.
- the process dies without closing the base (``kill -9``, a crash, a plugin's ``os._exit``):
  with ``guard`` (the default) a guard process holding a copy of the link stops the robot and
  CLOSEs the session at once (:mod:`drivers.link_guard`); the firmware watchdog is the last net.

The odometry frame starts at the pose of the first SIP (0, 0, 0) and stays continuous across
the robot's 15-bit position wrap-around and across reconnections. The measured turn rate is the
SIP's ROTVEL when the firmware sends it, else it is derived from the wheel speeds.
"""

from __future__ import annotations

import atexit
import contextlib
import logging
import math
import threading
import time
import weakref
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import serial

from drivers import arcos
from drivers.arcos import Command, Identity, ModelParams, Odometry, RobotConfig, Sip
from drivers.arcos_port import ArcosPort
from drivers.common import DriverFault, Stamp, build_settings, monotonic_stamp
from drivers.link_guard import LinkGuard
from drivers.pioneer_body import BODIES, PioneerBody, PioneerRanges
from drivers.pioneer_settings import ModelChoice, PioneerSettings, choose_model
from perception.geometry import Pose2D, wrap_angle
from perception.ranges import RangeScan

log = logging.getLogger(__name__)

CLOSE_SETTLE_S = 0.15  # after CLOSE to a robot that was still open, before syncing again
RECONNECT_PAUSE_S = 0.2
CYCLE_PAUSE_S = 0.1  # ARIA: one SIP cycle after the SYNC2 echo before OPEN; p2os waits 200 ms around CLOSE


@dataclass(frozen=True, slots=True)
class BaseStatus:
    """Everything one SIP told, in SI units: pose (odometry frame), measured velocity, sensors."""

    pose: Pose2D
    v: float = 0.0  # m/s, mean of the wheel speeds
    w: float = 0.0  # rad/s, from the wheel speed difference
    battery: float = 0.0  # V
    left_stall: bool = False
    right_stall: bool = False
    front_bumpers: int = 0  # bit i: bumper i pressed
    rear_bumpers: int = 0
    motors_enabled: bool = False
    estop: bool = False
    sonar: tuple[tuple[int, float], ...] = ()  # (index, range m), every sonar seen so far
    sonar_fired: tuple[tuple[int, float], ...] = ()  # (index, stamp of the SIP that last reported it)
    silent_sonar: frozenset[int] = frozenset()  # indices not heard for sonar_timeout
    sips: int = 0
    stamp: float = 0.0

    @property
    def stalled(self) -> bool:
        return self.left_stall or self.right_stall


class _LinkLost(Exception):
    """Internal: the link is gone (read/write error or no SIP); carries the reason."""


_OPEN_BASES: weakref.WeakSet[PioneerBase] = weakref.WeakSet()


@atexit.register
def _close_open_bases() -> None:  # pragma: no cover - runs at interpreter exit
    for base in list(_OPEN_BASES):
        with contextlib.suppress(Exception):
            base.close()


class PioneerBase:
    """A connected Pioneer base; build it with :func:`open_base`."""

    def __init__(self, settings: PioneerSettings, *, clock: Stamp | None = None,
                 port_factory: Callable[..., Any] | None = None) -> None:
        self.settings = settings
        self.fault: str | None = None
        self.identity: Identity | None = None
        self.config: RobotConfig | None = None
        self.model: ModelChoice | None = None
        self.reconnects = 0
        self.deadman_stops = 0
        self.clamped_commands = 0
        self.bumper_stops = 0
        self.link_down: str | None = None  # reason while a reconnection is being attempted
        self._stamp = monotonic_stamp(clock)
        self._link = ArcosPort(settings.port, port_factory or serial.serial_for_url)
        self._odometry: Odometry | None = None
        self._status: BaseStatus | None = None
        self._sonar: dict[int, float] = {}
        self._sonar_heard: dict[int, float] = {}  # index -> time.monotonic() of its last reading
        self._sonar_fired: dict[int, float] = {}  # index -> the stamp of the SIP that last reported it
        self._sips = 0  # SIPs decoded since the base was built
        self._target = (0.0, 0.0)  # mm/s, deg/s
        self._wake = threading.Event()
        self._closing = threading.Event()
        self._thread: threading.Thread | None = None
        self._last_drive = time.monotonic()
        self._last_sip = time.monotonic()
        self._closed = False
        self._guard: LinkGuard | None = None

    # -- the Base interface ----------------------------------------------------------------------
    def drive(self, v: float, w: float) -> None:
        """Command ``v`` m/s forward and ``w`` rad/s counter-clockwise; clamped to the limits."""
        self._check()
        if not (math.isfinite(v) and math.isfinite(w)):
            raise ValueError(f"drive({v}, {w}): velocities must be finite")
        max_v, max_w = self.limits()
        mm_s = max(-max_v, min(max_v, v)) * 1000.0
        deg_s = max(-max_w, min(max_w, math.degrees(w)))
        if abs(v) > max_v or abs(math.degrees(w)) > max_w:
            self.clamped_commands += 1
        self._last_drive = time.monotonic()
        if self.link_down is not None:
            return  # reconnecting: the robot is stopped; the next drive() after it resumes
        status = self._status
        if status is not None and _towards_pressed_bumper(status, mm_s):
            mm_s = deg_s = 0.0  # the bumper stays pressed: no motion towards it
        target = (mm_s, deg_s)
        if target != self._target:
            self._target = target
            self._wake.set()

    def stop(self) -> None:
        """Zero velocity, written from this thread at once; never raises."""
        self._target = (0.0, 0.0)
        self._send_stop()

    def odometry(self) -> Pose2D:
        """The newest odometry pose (stamp: when its SIP arrived)."""
        self._check()
        return self._current().pose

    def stalled(self) -> bool:
        """True while the robot reports a stalled wheel."""
        self._check()
        return self._current().stalled

    def close(self) -> None:
        """Stop, disable the motors, CLOSE the connection and release the port; never raises."""
        if self._closed:
            return
        self._closed = True
        self._closing.set()
        self.stop()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=1.0)
        if self.fault is None:
            self.fault = "the base is closed"
        self._say_goodbye()
        self._release_port()
        _OPEN_BASES.discard(self)

    # -- accessors for doctor and the runner ---------------------------------------------------------
    def describe(self) -> str:
        baud = "" if self.baud is None else f" at {self.baud} bit/s"
        return f"pioneer on {self.settings.port}{baud}"

    @property
    def baud(self) -> int | None:
        """The serial speed in use (None over a socket)."""
        return self._link.baud

    @property
    def params(self) -> ModelParams | None:
        """The conversion factors in use (None before the robot has said what it is)."""
        return self.model.params if self.model is not None else None

    @property
    def model_warning(self) -> str | None:
        """Set when ``model_override`` contradicts the subclass the robot reports."""
        return self.model.warning if self.model is not None else None

    def report_sections(self) -> dict[str, Any]:
        """What the run report says about the base: the model and factors in use and where they came
        from, the link's speed, what the robot said about itself."""
        section: dict[str, Any] = {"port": self.settings.port, "baud": self.baud}
        if self.model is not None:
            section.update(self.model.as_report())
        if self.identity is not None:
            section["robot_name"] = self.identity.name
        return {"base": section}

    def status(self) -> BaseStatus:
        """The newest decoded SIP (pose, velocity, battery, stall, bumpers, sonar); never blocks."""
        return self._current()

    def battery(self) -> float:
        """Battery voltage (V) from the newest SIP."""
        return self._current().battery

    def sonar(self) -> dict[int, float]:
        """Newest range (m) of every sonar seen so far, by index."""
        return dict(self._current().sonar)

    def body(self) -> PioneerBody:
        """Footprint, sonar ring and bumpers of the model in use (a P3-DX's before the robot has said)."""
        return BODIES[self.model.params.name if self.model is not None else "p3dx"]

    def range_scan(self) -> RangeScan:
        """The newest SIP's sonar readings and bumpers as one scan, stamped when the SIP arrived."""
        status = self._current()
        return self.body().scan(dict(status.sonar), status.silent_sonar, status.front_bumpers, status.rear_bumpers,
                                status.stamp, with_sonar=self.settings.sonar, fired=dict(status.sonar_fired))

    def range_source(self) -> PioneerRanges:
        """This base's sonar ring and bumpers as the robot's range source."""
        sensors = f"{len(self.body().sonar)} sonars and " if self.settings.sonar else ""
        return PioneerRanges(self.range_scan, f"pioneer {self.body().model}: {sensors}"
                             f"{self.body().front_bumpers + self.body().rear_bumpers} bumpers")

    def limits(self) -> tuple[float, float]:
        """``(max forward speed m/s, max turn rate deg/s)`` the driver clamps commands to."""
        params = self.params or arcos.MODELS["p3at"]  # the slower model until the robot has said
        max_v = self.settings.max_speed if self.settings.max_speed is not None else params.max_vel / 1000.0
        max_w = self.settings.max_turn_rate if self.settings.max_turn_rate is not None else params.max_rot_vel
        return min(max_v, params.max_vel / 1000.0), min(max_w, params.max_rot_vel)

    @property
    def reader_stats(self) -> arcos.ReaderStats:
        """Packets parsed, bad checksums and skipped bytes on the link so far."""
        return self._link.reader.stats

    # -- connecting --------------------------------------------------------------------------------
    def connect(self) -> PioneerBase:
        """Open the port, run the connection sequence, wait for the first SIP, start the I/O thread."""
        try:
            self._connect_once(time.monotonic() + self.settings.connect_timeout)
        except serial.SerialException as exc:
            self._release_port()
            raise ConnectionError(f"lost the link to the Pioneer on {self.settings.port} while connecting: "
                                  f"{exc}") from None
        except BaseException:
            self._say_goodbye()
            self._release_port()
            raise
        self._thread = threading.Thread(target=self._run, name=f"pioneer {self.settings.port}", daemon=True)
        _OPEN_BASES.add(self)
        self._thread.start()
        return self

    def _connect_once(self, deadline: float) -> None:
        self._open_port()
        self._sync(deadline)
        self._pause(CYCLE_PAUSE_S)
        self._send(arcos.encode_command(Command.OPEN))
        self.model = choose_model(self.identity.subclass if self.identity else "", self.settings.model_override,
                                  self.settings.port)  # after OPEN, as ARIA: a robot it has no factors for is CLOSEd
        if self.model.warning:
            log.warning("%s", self.model.warning)
        if self.settings.request_config:
            self.config = self._await_config(deadline) or self.config
        if self._may_switch_baud() and self._link.switch_speed(self.settings.switch_baud):
            log.info("Pioneer on %s: link moved to %d bit/s", self.settings.port, self.settings.switch_baud)
        self._send(arcos.encode_command(Command.SONAR, 1 if self.settings.sonar else 0))
        self._send(arcos.encode_command(Command.ENABLE, 1))
        self._send_velocity()
        self._await_first_sip(deadline)
        self._start_guard()

    def _start_guard(self) -> None:
        """A process that stops the robot if this one dies with the session open (drivers/link_guard.py)."""
        fd = self._link.fileno() if self.settings.guard else None
        if fd is not None:
            farewell = (arcos.encode_command(Command.STOP) + arcos.encode_vel(0) + arcos.encode_rvel(0)
                        + arcos.encode_command(Command.ENABLE, 0) + arcos.encode_command(Command.CLOSE))
            self._guard = LinkGuard.start(fd, farewell)

    def _open_port(self) -> None:
        self._link.open(self.settings.baud)

    def _sync(self, deadline: float) -> None:
        """SYNC0, SYNC1, SYNC2 with their echoes; anything out of sequence starts again at SYNC0."""
        step, silent = 0, 0
        while step <= arcos.SYNC2:
            if time.monotonic() > deadline:
                raise TimeoutError(f"no ARCOS reply on {self.settings.port} within "
                                   f"{self.settings.connect_timeout:g} s (robot off, wrong port or baud?)")
            self._send(arcos.encode_command(step))
            payload = self._next_packet(min(deadline, time.monotonic() + self.settings.reply_timeout))
            silent = silent + 1 if payload is None else 0
            if payload is None:
                step = 0
                if silent == 2:
                    self._link.close_at_every_speed()
            elif payload[0] in (arcos.SIP_STOPPED, arcos.SIP_MOVING):
                self._close_stale_session()
                step = 0
            elif payload[0] == step:
                if step == arcos.SYNC2:
                    self.identity = arcos.decode_sync(payload)[1]
                step += 1
            else:
                step = 0

    def _close_stale_session(self) -> None:
        """The robot is still open from an earlier client: CLOSE it, let it settle, start again."""
        log.info("Pioneer on %s was still connected; closing that session first", self.settings.port)
        self._send(arcos.encode_command(Command.CLOSE))
        time.sleep(CLOSE_SETTLE_S)
        self._link.forget_input()

    def _may_switch_baud(self) -> bool:
        """ARIA moves to a faster speed only on a serial device and when the config packet allows it."""
        target = self.settings.switch_baud
        return bool(target) and self._link.baud not in (None, target) and self.config is not None \
            and self.config.allows_hostbaud

    def _await_config(self, deadline: float) -> RobotConfig | None:
        sent_at = None
        end = min(deadline, time.monotonic() + 2 * self.settings.reply_timeout)
        while time.monotonic() < end:
            if sent_at is None or time.monotonic() - sent_at > self.settings.reply_timeout:
                self._send(arcos.encode_command(Command.CONFIG, 1))
                sent_at = time.monotonic()
            payload = self._next_packet(min(end, sent_at + self.settings.reply_timeout))
            if payload is not None and payload[0] == arcos.CONFIG_PACKET:
                try:
                    return arcos.decode_config(payload)
                except arcos.PacketError:
                    return None
            if payload is not None:
                self._handle(payload)
        log.info("Pioneer on %s sent no config packet; going on without it", self.settings.port)
        return None

    def _await_first_sip(self, deadline: float) -> None:
        """Wait for a SIP; then, briefly, for one that shows the motors enabled (an e-stop keeps
        them off: the base still opens, and ``status().motors_enabled`` tells)."""
        seen = self._sips
        enabled_by = None
        while True:
            now = time.monotonic()
            if self._sips > seen:
                enabled_by = enabled_by or min(deadline, now + self.settings.reply_timeout)
                if self._current().motors_enabled or now >= enabled_by:
                    break
            elif now > deadline:
                raise TimeoutError(f"the Pioneer on {self.settings.port} accepted the connection but sent no "
                                   f"SIP within {self.settings.connect_timeout:g} s")
            payload = self._next_packet(enabled_by or deadline)
            if payload is not None:
                self._handle(payload)
        self._last_sip = time.monotonic()

    def _next_packet(self, until: float) -> bytes | None:
        """The next valid packet before ``until`` (used while connecting, before the I/O thread)."""
        if self._closing.is_set():
            raise ConnectionError("the base is being closed")
        return self._link.next_packet(until)

    # -- the I/O thread ----------------------------------------------------------------------------
    def _run(self) -> None:
        next_send = time.monotonic()
        while not self._closing.is_set():
            try:
                next_send = self._cycle(next_send)
            except _LinkLost as exc:
                if not self._recover(str(exc)):
                    return
                next_send = time.monotonic()
            except Exception as exc:  # noqa: BLE001 - a bug must still stop the robot and be reported
                self._set_fault(f"Pioneer driver error: {type(exc).__name__}: {exc}")
                self._send_stop(disable=True)
                return

    def _cycle(self, next_send: float) -> float:
        if not self._link.is_open:
            raise _LinkLost("the port is closed")
        try:
            payloads = self._link.read()
        except (serial.SerialException, OSError) as exc:
            raise _LinkLost(f"link to {self.settings.port} lost: {exc}") from None
        for payload in payloads:
            self._handle(payload)
        now = time.monotonic()
        if now - self._last_sip > self.settings.sip_timeout:
            raise _LinkLost(f"no SIP from the Pioneer on {self.settings.port} for "
                            f"{now - self._last_sip:.2f} s (limit {self.settings.sip_timeout:g} s)")
        if self._target != (0.0, 0.0) and now - self._last_drive > self.settings.command_timeout:
            self._target = (0.0, 0.0)
            self.deadman_stops += 1
            log.warning("no drive() for %.2f s: stopping the base", now - self._last_drive)
            self._wake.set()
        if self._wake.is_set() or now >= next_send:
            self._wake.clear()
            try:
                self._send_velocity()
            except (serial.SerialException, OSError) as exc:
                raise _LinkLost(f"link to {self.settings.port} lost: {exc}") from None
            return now + self.settings.resend_period
        return next_send

    def _handle(self, payload: bytes) -> None:
        kind = payload[0]
        if kind in (arcos.SIP_STOPPED, arcos.SIP_MOVING):
            try:
                sip = arcos.decode_sip(payload)
            except arcos.PacketError as exc:
                log.debug("dropping a malformed SIP: %s", exc)
                return
            self._update(sip)
        elif kind == arcos.CONFIG_PACKET:
            with contextlib.suppress(arcos.PacketError):
                self.config = arcos.decode_config(payload)

    def _update(self, sip: Sip) -> None:
        params = self.params
        if params is None:
            return  # not synced yet: a SIP cannot be read without the robot's units
        if self._odometry is None:
            self._odometry = Odometry(params)
        x, y, theta = self._odometry.update(sip)
        heard = time.monotonic()
        stamp = self._stamp()
        for index, raw in sip.sonar:
            self._sonar[index] = raw * params.range_conv / 1000.0
            self._sonar_heard[index] = heard
            self._sonar_fired[index] = stamp
        silent = frozenset(i for i, t in self._sonar_heard.items() if heard - t > self.settings.sonar_timeout)
        v, w = arcos.measured_velocity(sip, params)
        self._status = BaseStatus(
            pose=Pose2D(x / 1000.0, y / 1000.0, wrap_angle(theta), stamp),
            v=v / 1000.0,
            w=math.radians(w),
            battery=(sip.battery_x10 if sip.battery_x10 is not None else sip.battery) / 10.0,
            left_stall=sip.left_stall,
            right_stall=sip.right_stall,
            front_bumpers=sip.front_bumpers,
            rear_bumpers=sip.rear_bumpers,
            motors_enabled=sip.motors_enabled,
            estop=sip.estop,
            sonar=tuple(sorted(self._sonar.items())),
            sonar_fired=tuple(sorted(self._sonar_fired.items())),
            silent_sonar=silent,
            sips=self._sips + 1,
            stamp=stamp,
        )
        self._sips += 1
        self._last_sip = time.monotonic()
        if _towards_pressed_bumper(self._status, self._target[0]):
            self._bumper_stop()

    def _bumper_stop(self) -> None:
        """A bumper pressed in the direction of motion: stop now, from the thread that read the SIP."""
        self._target = (0.0, 0.0)
        self.bumper_stops += 1
        log.warning("Pioneer on %s: bumper pressed while moving towards it; stopped", self.settings.port)
        self._send_stop()

    def _recover(self, reason: str) -> bool:
        """After a lost link: stop, then reconnect if allowed; False when the thread must end."""
        log.warning("%s", reason)
        self._send_stop(disable=True)
        if not self.settings.reconnect or self._closing.is_set():
            self._set_fault(reason)
            return False
        self.link_down = reason
        self._target = (0.0, 0.0)
        deadline = time.monotonic() + self.settings.reconnect_timeout
        while not self._closing.is_set() and time.monotonic() < deadline:
            self._release_port()
            try:
                self._connect_once(min(deadline, time.monotonic() + self.settings.connect_timeout))
            except (OSError, serial.SerialException) as exc:
                log.info("reconnecting to %s: %s", self.settings.port, exc)
                self._closing.wait(RECONNECT_PAUSE_S)
                continue
            self.reconnects += 1
            self._target = (0.0, 0.0)
            self.link_down = None
            self._last_sip = time.monotonic()
            return True
        if not self._closing.is_set():
            self._set_fault(f"{reason}; reconnecting failed for {self.settings.reconnect_timeout:g} s")
        self.link_down = None
        return False

    # -- writing -----------------------------------------------------------------------------------
    def _send(self, data: bytes) -> None:
        self._link.send(data)

    def _send_velocity(self) -> None:
        mm_s, deg_s = self._target
        self._send(arcos.encode_vel(mm_s) + arcos.encode_rvel(deg_s))

    def _send_stop(self, *, disable: bool = False) -> None:
        """STOP, VEL 0, RVEL 0 (and ENABLE 0) now, from the calling thread; never raises."""
        data = arcos.encode_command(Command.STOP) + arcos.encode_vel(0) + arcos.encode_rvel(0)
        if disable:
            data += arcos.encode_command(Command.ENABLE, 0)
        with contextlib.suppress(Exception):  # safety path: a dead link cannot carry it anyway
            self._send(data)

    def _say_goodbye(self) -> None:
        """Stop, motors off, a pause of one SIP cycle (ARIA 100 ms, p2os 200 ms), CLOSE; the port is
        flushed so CLOSE is on the wire before it is released."""
        with contextlib.suppress(Exception):
            self._send(arcos.encode_command(Command.STOP) + arcos.encode_vel(0) + arcos.encode_rvel(0)
                       + arcos.encode_command(Command.ENABLE, 0))
            self._link.flush()
            self._pause(CYCLE_PAUSE_S)
            self._send(arcos.encode_command(Command.CLOSE))
            self._link.flush()

    def _pause(self, seconds: float) -> None:
        """The protocol's pauses (before OPEN, before CLOSE, around HOSTBAUD): one place to see them."""
        time.sleep(seconds)

    def _release_port(self) -> None:
        guard, self._guard = self._guard, None
        if guard is not None:
            guard.release()
        self._link.release()
        if self._odometry is not None:
            self._odometry.restart()

    # -- helpers -----------------------------------------------------------------------------------
    def _set_fault(self, reason: str) -> None:
        if self.fault is None:
            self.fault = reason
            log.error("Pioneer base fault: %s", reason)

    def _check(self) -> None:
        if self.fault is not None:
            raise DriverFault(self.fault)

    def _current(self) -> BaseStatus:
        status = self._status
        if status is None:
            raise DriverFault("the Pioneer base is not connected")
        return status


def _towards_pressed_bumper(status: BaseStatus, mm_s: float) -> bool:
    """Does forward speed ``mm_s`` move towards a pressed bumper (front: forward, rear: backward)?"""
    return (mm_s > 0 and status.front_bumpers != 0) or (mm_s < 0 and status.rear_bumpers != 0)


def open_base(settings: PioneerSettings | Mapping[str, Any] | None = None, /, *, clock: Stamp | None = None,
              **fields: Any) -> PioneerBase:
    """Connect to a Pioneer base and return it running; raise ``OSError`` when it cannot be reached.

    Takes a :class:`PioneerSettings` (or a mapping of its fields), or the fields as keyword
    arguments as ``missions.profiles.open_robot`` passes them today. ``clock`` stamps the
    odometry (default ``time.monotonic``).
    """
    model = build_settings(PioneerSettings, settings, fields, where="base (pioneer)")
    return PioneerBase(model, clock=clock).connect()
