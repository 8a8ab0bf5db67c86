"""An ARCOS robot for the tests: speaks the protocol over a pty (like a USB-serial Pioneer) or TCP
(like MobileSim on port 8101), so the real :mod:`drivers.pioneer` code is what gets exercised.

It behaves as one of the two references (docs/protocols.md says where each behaviour comes from):

- ``mode="firmware"`` (the default over a pty), the robot's ARCOS firmware: an out-of-sequence
  SYNC starts the handshake again at SYNC0; the watchdog stops a robot that hears no command for
  ``watchdog`` seconds (the session stays open); CLOSE ends the session but the serial link stays;
  HOSTBAUD moves the link to another speed when the config packet says it may (``hostbaud``),
  and CLOSE brings it back to the start speed. Over a pty the speed is real: the emulator reads
  the speed the driver set on its end, and while the two differ what crosses is noise.
- ``mode="mobilesim"`` (the default over TCP), AMRISim's ``EmulatePioneer``: the handshake echoes
  whatever SYNC the client sends; the watchdog only warns (a ``watchdog_warning`` event) and the
  robot keeps moving; CLOSE, or the client going away, ends the session: the robot is stopped,
  its motors disabled, the TCP connection closed; each session starts its odometry at (0, 0, 0);
  positions are 16-bit counters; HOSTBAUD is ignored (there is no serial speed).

It checks every checksum of what it receives (``bad_packets`` counts failures), sends a SIP every
``sip_period`` with the optional fields (battery x10, charge state, ROTVEL), integrates the
commanded VEL/RVEL (``time_scale`` speeds the world up so that a mission finishes quickly), and
encodes positions in the units of ``model`` (the subclass it reports, unless ``identity`` says
otherwise). Every accepted command is recorded with its time in ``events``.

Faults to inject: ``garbage()`` bytes, ``corrupt(n)`` checksums of the next SIPs, ``tear`` packets
into pieces, ``mute`` the SIPs (the link still hears commands), ``drop_link()``, ``reply_delay``
on connection replies, ``sync_glitch`` (a wrong echo), ``start_open`` (a robot still open from an
earlier client, at ``start_baud``), ``honour_hostbaud=False`` (a robot that says it takes HOSTBAUD
and does not), stalls, bumpers, battery, sonar, e-stop.

Obstacles: the sonar ring is the model's (ARIA's geometry, :mod:`drivers.pioneer_body`: 16
transducers), reading 5000 mm (no echo) unless ``wall_ahead`` (m) puts a wall across the start
heading at that distance from the start pose: then each transducer reads the distance along its
axis to the wall, and a robot whose front reaches the wall stops there with its middle front
bumper pressed (released when it backs away). Every SIP sent with a bumper pressed is an event
(``sip_bumpers``), so a test can tell how many SIP cycles a reaction took.
"""

from __future__ import annotations

import contextlib
import math
import os
import random
import select
import socket
import termios
import threading
import time
import tty
from dataclasses import dataclass

from drivers import arcos
from drivers.arcos import Command, Identity
from drivers.pioneer_body import BODIES
from tests.drivers.emulator_thread import EmulatorThread

SPEED_GRACE_S = 0.1  # a pty carries no speed per byte: bytes read this soon after a speed change still count
SONARS_PER_SIP = 4  # readings in a SIP when none changed: the robot fires its sonars in turn
NO_ECHO_MM = 5000  # what the sonar reads when nothing answers (MobileSim's maximum)
MIDDLE_FRONT_BUMPER = 0b00100  # bumper 2 of 5
BAUDS = {code: baud for baud, code in arcos.BAUD_CODES.items()}


@dataclass(frozen=True)
class Event:
    t: float
    name: str
    arg: int | bytes | None = None


class ArcosEmulator(EmulatorThread):
    THREAD_NAME = "arcos-emulator"

    def __init__(self, *, transport: str = "pty", mode: str | None = None, model: str = "p3dx",
                 identity: Identity | None = None, sip_period: float = 0.1, watchdog: float = 2.0,
                 time_scale: float = 1.0, start_pose: tuple[float, float, float] = (0.0, 0.0, 0.0),
                 reply_delay: float = 0.0, send_config: bool = True, start_open: bool = False,
                 new_firmware: bool = True, sync_glitch: int = 0, hostbaud: bool = True,
                 honour_hostbaud: bool = True, start_baud: int = 9600, seed: int = 0) -> None:
        super().__init__()
        self.transport = transport
        self.mode = mode or ("mobilesim" if transport == "tcp" else "firmware")
        self.params = arcos.MODELS[model]
        self.body = BODIES[model]
        name = "MobileSim" if self.mode == "mobilesim" else "emulator"
        self.identity = identity or Identity(name, "Pioneer", model)
        self.sip_period = sip_period
        self.watchdog = watchdog
        self.time_scale = time_scale
        self.reply_delay = reply_delay
        self.send_config = send_config
        self.new_firmware = new_firmware
        self.hostbaud = hostbaud and self.mode == "firmware"
        self.honour_hostbaud = honour_hostbaud
        self.rng = random.Random(seed)
        self._init_world(start_pose)
        self._init_protocol(start_open=start_open, start_baud=start_baud, sync_glitch=sync_glitch)
        # the link
        self._master = self._slave = -1
        self._listener: socket.socket | None = None
        self._conn: socket.socket | None = None
        self.port = self._open_link()

    # -- set-up ------------------------------------------------------------------------------------
    def _init_world(self, start_pose: tuple[float, float, float]) -> None:
        self.x, self.y = start_pose[0] * 1000.0, start_pose[1] * 1000.0  # mm
        self.theta = start_pose[2]  # rad
        self.start_pose = (self.x, self.y, self.theta)
        self._odometry_origin = (0.0, 0.0, 0.0)  # firmware: its counters never restart
        self.v = 0.0  # mm/s commanded
        self.w = 0.0  # deg/s commanded
        self.enabled = False
        self.estop = False
        self.stall_left = self.stall_right = False
        self.front_bumpers = self.rear_bumpers = 0
        self.battery = 12.6  # V
        self.sonar_ranges: dict[int, int] = {i: NO_ECHO_MM for i in range(len(self.body.sonar))}  # mm
        self._sonar_dirty = set(self.sonar_ranges)
        self._next_sonar = 0
        self.wall_ahead: float | None = None  # m from the start pose along its heading
        self.silent_sonar: set[int] = set()  # transducers that never report

    def _init_protocol(self, *, start_open: bool, start_baud: int, sync_glitch: int) -> None:
        self.state = "open" if start_open else "sync0"
        self.events: list[Event] = []
        self.bad_packets = 0
        self.sips_sent = 0
        self.tx_dropped = 0
        self.garbled = 0  # bytes lost to a speed mismatch, both ways
        self.sessions_ended = 0
        self.link_dropped_at: float | None = None
        self.crashed: BaseException | None = None
        self.last_rx = time.monotonic()
        self.start_baud = 9600
        self.baud = start_baud
        self._watchdog_warned = False
        # faults
        self.tear = False
        self.mute = False
        self.sync_glitch = sync_glitch
        self.accept_connections = True
        self._corrupt = 0
        self._outbox: list[tuple[float, bytes]] = []
        self._reader = arcos.PacketReader()
        self._lock = threading.RLock()
        self._next_sip = time.monotonic()
        self._last_step = time.monotonic()
        self._line_speed: int | None = None  # the speed the driver's end of the pty is at
        self._speed_changed_at = time.monotonic()

    def _open_link(self) -> str:
        if self.transport == "pty":
            self._master, self._slave = os.openpty()
            tty.setraw(self._slave)  # no echo, no line editing before the driver opens it
            os.set_blocking(self._master, False)
            return os.ttyname(self._slave)
        listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        listener.bind(("127.0.0.1", 0))
        listener.listen(2)
        listener.setblocking(False)
        self._listener = listener
        return f"socket://127.0.0.1:{listener.getsockname()[1]}"

    def _release(self) -> None:
        self._close_link()
        if self._listener is not None:
            with contextlib.suppress(OSError):
                self._listener.close()
            self._listener = None

    # -- faults ------------------------------------------------------------------------------------
    def garbage(self, n: int = 64) -> None:
        """Send ``n`` bytes of noise, with bogus headers in it, between packets."""
        noise = bytearray(self.rng.randrange(256) for _ in range(n))
        noise[n // 3 : n // 3 + 3] = b"\xfa\xfb\x01"  # a header with an impossible count
        noise[2 * n // 3 : 2 * n // 3 + 4] = b"\xfa\xfb\x05\x32"  # a torn bogus packet
        self._write(bytes(noise))

    def corrupt(self, n: int = 1) -> None:
        """Corrupt one payload byte of each of the next ``n`` SIPs after the checksum is computed."""
        with self._lock:
            self._corrupt += n

    def drop_link(self) -> None:
        """Cut the link: the pty or the TCP connection is closed under the driver (MobileSim then ends
        the session, as when its client goes away)."""
        with self._lock:
            self.link_dropped_at = time.monotonic()
            if self.mode == "mobilesim" and self.state != "sync0":
                self._end_session(time.monotonic(), "link_dropped")
            self._close_link(keep_listener=True)

    # -- queries for the tests -----------------------------------------------------------------------
    def pose(self) -> tuple[float, float, float]:
        """True pose (m, m, rad) relative to the start pose, in the start pose's frame."""
        with self._lock:
            x, y, theta = _relative((self.x, self.y, self.theta), self.start_pose)
            return x / 1000.0, y / 1000.0, theta

    def named(self, name: str) -> list[Event]:
        with self._lock:
            return [e for e in self.events if e.name == name]

    def first_after(self, name: str, t: float) -> Event | None:
        return next((e for e in self.named(name) if e.t >= t), None)

    def wait_for(self, predicate, timeout: float = 5.0) -> bool:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if predicate():
                return True
            time.sleep(0.005)
        return bool(predicate())

    @property
    def moving(self) -> bool:
        return self.v != 0.0 or self.w != 0.0

    @property
    def connected(self) -> bool:
        """A client is on the link (TCP: a connection is open; pty: the pty exists)."""
        return self._connected()

    # -- the loop ----------------------------------------------------------------------------------
    def _loop(self) -> None:
        try:
            self._serve()
        except BaseException as exc:  # a bug in the emulator must fail the test, not hang it
            self.crashed = exc
            raise

    def _serve(self) -> None:
        while self._running.is_set():
            self._accept()
            data = self._read(0.003)
            now = time.monotonic()
            with self._lock:
                data = self._hear(data, now)
                for payload in self._reader.feed(data) if data else ():
                    self._handle(payload, now)
                self.bad_packets = self._reader.stats.bad_checksums + self._reader.stats.bad_lengths
                self._step(now)
                self._watch(now)
                self._flush_outbox(now)
                if self.state == "open" and now >= self._next_sip:
                    self._next_sip = max(self._next_sip + self.sip_period, now)
                    if not self.mute and self._connected():
                        self._send_sip()

    def _watch(self, now: float) -> None:
        """The watchdog: the firmware stops a robot that hears nothing; MobileSim only warns."""
        if not (self.moving and now - self.last_rx > self.watchdog):
            return
        if self.mode == "firmware":
            self.v = self.w = 0.0
            self.events.append(Event(now, "watchdog"))
        elif not self._watchdog_warned:
            self._watchdog_warned = True
            self.events.append(Event(now, "watchdog_warning"))

    def _step(self, now: float) -> None:
        dt = (now - self._last_step) * self.time_scale
        self._last_step = now
        if not (self.enabled and not self.estop) or (self.stall_left or self.stall_right):
            return
        w = math.radians(self.w)
        if abs(w) < 1e-12:
            self.x += self.v * dt * math.cos(self.theta)
            self.y += self.v * dt * math.sin(self.theta)
        else:  # exact arc for constant v, w
            r = self.v / w
            self.x += r * (math.sin(self.theta + w * dt) - math.sin(self.theta))
            self.y -= r * (math.cos(self.theta + w * dt) - math.cos(self.theta))
        self.theta = _wrap(self.theta + w * dt)
        self._touch_wall()

    def _touch_wall(self) -> None:
        """A front that reaches the wall stays at it, the middle front bumper pressed (until it backs off)."""
        if self.wall_ahead is None:
            return
        x, _, theta = _relative((self.x, self.y, self.theta), self.start_pose)
        front = x + self.body.length_front * 1000.0 * math.cos(theta)
        wall = self.wall_ahead * 1000.0
        if front >= wall:
            back = front - wall
            c, s = math.cos(self.start_pose[2]), math.sin(self.start_pose[2])
            self.x, self.y = self.x - back * c, self.y - back * s
            self.front_bumpers |= MIDDLE_FRONT_BUMPER
        elif front < wall - 5.0:
            self.front_bumpers &= ~MIDDLE_FRONT_BUMPER

    def _sense_wall(self) -> None:
        """Each transducer's range along its axis to the wall (no echo beyond 5 m or facing away)."""
        if self.wall_ahead is None:
            return
        x, y, theta = _relative((self.x, self.y, self.theta), self.start_pose)
        c, s = math.cos(theta), math.sin(theta)
        for index, (sx, sy, heading) in enumerate(self.body.sonar):
            along = x + c * sx - s * sy  # the transducer's distance along the start heading, mm
            facing = math.cos(theta + math.radians(heading))
            reading = NO_ECHO_MM
            if facing > 1e-6:
                reading = min(NO_ECHO_MM, int(round((self.wall_ahead * 1000.0 - along) / facing)))
            if reading != self.sonar_ranges[index]:
                self.sonar_ranges[index] = reading
                self._sonar_dirty.add(index)

    def _handle(self, payload: bytes, now: float) -> None:
        try:
            command, arg = arcos.decode_command(payload)
        except arcos.PacketError:
            self.bad_packets += 1
            return
        self.last_rx = now
        self._watchdog_warned = False
        name = Command(command).name if command in Command._value2member_map_ else str(command)
        if self.state in ("sync0", "sync1", "sync2"):
            self._handle_sync(command, now)
            return
        if self.state == "synced":
            if command == Command.OPEN:
                self.state = "open"
                self._next_sip = now
                self.events.append(Event(now, "OPEN"))
            return
        self.events.append(Event(now, name, arg))
        self._handle_open(command, arg, now)

    def _handle_sync(self, command: int, now: float) -> None:
        expected = int(self.state[-1])
        if command not in (arcos.SYNC0, arcos.SYNC1, arcos.SYNC2):
            return
        if command != expected:
            if self.mode == "firmware":
                self.state = "sync0"  # ARCOS starts again at SYNC0
                return
            expected = command  # AMRISim warns and follows the client's sequence
        if command == arcos.SYNC1 and self.sync_glitch > 0:
            self.sync_glitch -= 1
            self._reply(arcos.encode_sync(arcos.SYNC0), now)  # out of sequence: the driver restarts
            self.state = "sync0"
            return
        self._reply(arcos.encode_sync(command, self.identity), now)
        self.state = f"sync{command + 1}" if command < arcos.SYNC2 else "synced"
        if command == arcos.SYNC2 and self.mode == "mobilesim":
            self._odometry_origin = (self.x, self.y, self.theta)  # each session starts at (0, 0, 0)

    def _handle_open(self, command: int, arg: int | bytes | None, now: float) -> None:
        value = arg if isinstance(arg, int) else 0
        if command == Command.CLOSE:
            self._end_session(now, "CLOSE")
        elif command == Command.ENABLE:
            self.enabled = bool(value) and not self.estop
            if not value:
                self.v = self.w = 0.0
        elif command == Command.VEL:
            self.v = float(max(-self.params.max_vel, min(self.params.max_vel, value))) if self.enabled else 0.0
        elif command == Command.RVEL:
            self.w = float(max(-self.params.max_rot_vel, min(self.params.max_rot_vel, value))) if self.enabled else 0.0
        elif command in (Command.STOP, Command.E_STOP):
            self.v = self.w = 0.0
        elif command == Command.CONFIG and self.send_config:
            self._reply(arcos.encode_config(self._config_values()), now)
        elif command == Command.HOSTBAUD and self.hostbaud and self.honour_hostbaud and value in BAUDS:
            self._set_speed(BAUDS[value], now)

    def _end_session(self, now: float, why: str) -> None:
        """CLOSE (or, in MobileSim, the client going away): stopped, motors off, back to the handshake;
        the firmware returns to its start speed, MobileSim closes the connection."""
        self.v = self.w = 0.0
        self.enabled = False
        self.state = "sync0"
        self.sessions_ended += 1
        self.events.append(Event(now, "session_end", why.encode()))
        if self.mode == "mobilesim":
            self._outbox.clear()
            self._close_link(keep_listener=True)
        elif self.baud != self.start_baud:
            self._set_speed(self.start_baud, now)

    def _config_values(self) -> dict[str, int | str]:
        sim = self.mode == "mobilesim"
        return {"robot_type": self.identity.robot_class, "subtype": self.identity.subclass,
                "serial": "SIM" if sim else "EMU0001", "four_mots": 0, "rot_vel_top": int(self.params.max_rot_vel),
                "trans_vel_top": int(self.params.max_vel), "rot_accel_top": 300, "trans_accel_top": 2000,
                "pwm_max": 1000, "name": "MobileSim" if sim else self.identity.name,
                "sip_cycle": int(self.sip_period * 1000), "host_baud": 0 if sim else arcos.BAUD_CODES[self.start_baud],
                "watchdog": int(self.watchdog * 1000), "low_battery": 110, "trans_vel_max": int(self.params.max_vel),
                "rot_vel_max": 300, "reset_baud": arcos.RESET_BAUD_ALLOWED if (self.hostbaud or sim) else 0,
                "firmware": "emulated"}

    # -- the line speed ------------------------------------------------------------------------------
    def _set_speed(self, baud: int, now: float) -> None:
        self.baud = baud
        self._speed_changed_at = now
        self.events.append(Event(now, "speed", baud))

    def _speed_matches(self, now: float, *, grace: bool) -> bool:
        """Both ends of the pty at the same speed (TCP has none); with ``grace``, a mismatch younger
        than SPEED_GRACE_S still counts as a match (bytes read now may have been written before it)."""
        if self.transport != "pty" or self._slave < 0:
            return True
        with contextlib.suppress(termios.error, OSError):
            speed = termios.tcgetattr(self._slave)[5]
            if speed != self._line_speed:
                self._line_speed, self._speed_changed_at = speed, now
        matches = self._line_speed == getattr(termios, f"B{self.baud}")
        return matches or (grace and now - self._speed_changed_at < SPEED_GRACE_S)

    def _hear(self, data: bytes, now: float) -> bytes:
        """What arrives at a speed other than ours is noise, not packets."""
        if data and not self._speed_matches(now, grace=True):
            self.garbled += len(data)
            return b""
        return data

    # -- output ------------------------------------------------------------------------------------
    def _send_sip(self) -> None:
        l_vel, r_vel = self._wheel_speeds()
        self._sense_wall()
        sonar = []
        for index in sorted(self._sonar_dirty - self.silent_sonar)[:8]:  # a changed range first, then in turn
            sonar.append((index, self.sonar_ranges[index]))
            self._sonar_dirty.discard(index)
        for _ in range(len(self.sonar_ranges)):
            if len(sonar) >= SONARS_PER_SIP:
                break
            self._next_sonar = (self._next_sonar + 1) % len(self.sonar_ranges)
            if self._next_sonar not in self.silent_sonar:
                sonar.append((self._next_sonar, self.sonar_ranges[self._next_sonar]))
        if self.front_bumpers or self.rear_bumpers:
            self.events.append(Event(time.monotonic(), "sip_bumpers", self.front_bumpers | self.rear_bumpers << 8))
        low = int(self.stall_left) | (self.rear_bumpers << 1)
        high = int(self.stall_right) | (self.front_bumpers << 1)
        stall = low | (high << 8)
        flags = (1 if self.enabled else 0) | (0x20 if self.estop else 0)
        volts = int(round(self.battery * 10))
        extra = volts.to_bytes(2, "little") + b"\x00" + int(round(self.w * 10)).to_bytes(2, "little", signed=True) \
            if self.new_firmware else b""
        x, y, theta = _relative((self.x, self.y, self.theta), self._odometry_origin)
        mask = 0xFFFF if self.mode == "mobilesim" else 0x7FFF  # AMRISim sends 16-bit counters; ARIA keeps 15
        sip = arcos.Sip(self.moving and self.mode == "firmware", int(round(x / self.params.dist_conv)) & mask,
                        int(round(y / self.params.dist_conv)) & mask,
                        int(round(theta / self.params.angle_conv)) % 4096, int(round(l_vel)), int(round(r_vel)),
                        min(volts, 255), stall, 0, flags, 0, tuple(sonar), extra=extra)
        packet = bytearray(arcos.frame(arcos.encode_sip(sip)))
        if self._corrupt > 0:
            self._corrupt -= 1
            packet[5] ^= 0x5A  # a payload byte; the checksum no longer matches
        self.sips_sent += 1
        self._write(bytes(packet))

    def _wheel_speeds(self) -> tuple[float, float]:
        if not self.enabled or self.stall_left or self.stall_right:
            return 0.0, 0.0
        half = math.radians(self.w) / self.params.diff_conv
        return (self.v - half) * self.time_scale, (self.v + half) * self.time_scale

    def _reply(self, payload: bytes, now: float) -> None:
        self._outbox.append((now + self.reply_delay, arcos.frame(payload)))

    def _flush_outbox(self, now: float) -> None:
        due = [p for t, p in self._outbox if t <= now]
        self._outbox = [(t, p) for t, p in self._outbox if t > now]
        for packet in due:
            self._write(packet)

    def _write(self, data: bytes) -> None:
        if not self._speed_matches(time.monotonic(), grace=False):
            self.garbled += len(data)
            data = bytes(self.rng.randrange(256) for _ in data)  # what a mismatched UART makes of it
        if not self.tear or len(data) < 2:
            self._raw_write(data)
            return
        cut = self.rng.randrange(1, len(data))
        self._raw_write(data[:cut])
        time.sleep(0.002)  # the driver may read the first piece alone
        self._raw_write(data[cut:])

    def _raw_write(self, data: bytes) -> None:
        try:
            if self.transport == "pty":
                if self._master < 0:
                    raise OSError("link down")
                os.write(self._master, data)
            else:
                if self._conn is None:
                    raise OSError("no client")
                self._conn.sendall(data)
        except OSError:
            self.tx_dropped += len(data)

    # -- the link ----------------------------------------------------------------------------------
    def _connected(self) -> bool:
        return self._master >= 0 if self.transport == "pty" else self._conn is not None

    def _accept(self) -> None:
        if self._listener is None or not self.accept_connections:
            return
        try:
            conn, _ = self._listener.accept()
        except (BlockingIOError, OSError):
            return
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        conn.setblocking(False)
        with self._lock:
            if self._conn is not None:
                with contextlib.suppress(OSError):
                    self._conn.close()
            self._conn = conn
            self._reader.clear()
            self.state = "sync0"

    def _read(self, timeout: float) -> bytes:
        fd = self._master if self.transport == "pty" else self._conn
        if fd is None or fd == -1:
            time.sleep(timeout)
            return b""
        try:
            ready, _, _ = select.select([fd], [], [], timeout)
            if not ready:
                return b""
            data = os.read(fd, 4096) if self.transport == "pty" else fd.recv(4096)
        except (BlockingIOError, InterruptedError):
            return b""
        except (OSError, ValueError):
            data = b""
        if not data and self.transport == "tcp":  # the client went away
            with self._lock:
                if self.mode == "mobilesim" and self.state != "sync0":
                    self._end_session(time.monotonic(), "client_gone")
                self._close_link(keep_listener=True)
                self.state = "sync0"
        return data

    def _close_link(self, keep_listener: bool = False) -> None:
        for name in ("_master", "_slave"):
            fd = getattr(self, name)
            if fd >= 0:
                with contextlib.suppress(OSError):
                    os.close(fd)
                setattr(self, name, -1)
        if self._conn is not None:
            with contextlib.suppress(OSError):
                self._conn.shutdown(socket.SHUT_RDWR)
            with contextlib.suppress(OSError):
                self._conn.close()
            self._conn = None


def _relative(pose: tuple[float, float, float], origin: tuple[float, float, float]) -> tuple[float, float, float]:
    """``pose`` in the frame of ``origin`` (both x, y, theta)."""
    dx, dy = pose[0] - origin[0], pose[1] - origin[1]
    c, s = math.cos(-origin[2]), math.sin(-origin[2])
    return c * dx - s * dy, s * dx + c * dy, _wrap(pose[2] - origin[2])


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi
