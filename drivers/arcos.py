"""ARCOS / P2OS packet codec for Pioneer bases: pure functions, bytes in and values out.

Nothing here touches a port, a thread or a clock; :mod:`drivers.pioneer` does the I/O and the
test emulator speaks through the same functions, so both ends agree on every byte. The facts,
with the public source of each, are in ``docs/protocols.md``:

- a packet is ``FA FB | N | payload | CK_hi CK_lo`` where ``N = len(payload) + 2`` (an
  unsigned byte, so up to 255) and the first payload byte is the command number or the packet type;
- the checksum adds the payload's big-endian byte pairs modulo 2**16 and XORs an odd last byte;
- data integers in a payload are little-endian; a command argument is ``0x3B`` + uint16 (>= 0),
  ``0x1B`` + abs value uint16 (< 0), or ``0x2B`` + length + characters (+ NUL, as ARIA sends).

:class:`PacketReader` is the incremental parser: feed it any chunks (torn packets, garbage,
corrupted checksums) and it returns the valid payloads, resynchronising on ``FA FB`` and
counting what it dropped. :class:`Odometry` turns the wrapping 15-bit SIP positions into a
continuous pose. Units at this level are the robot's (mm, mm/s, position units, 4096ths of a
turn); :class:`ModelParams` holds the per-model conversion factors.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field
from enum import IntEnum

HEADER = b"\xfa\xfb"
MIN_COUNT = 3  # N of the shortest packet: a command byte and the two checksum bytes
MAX_COUNT = 255  # N is one unsigned byte and ARIA's receiver takes any value of it (docs/protocols.md)
ARG_INT, ARG_NINT, ARG_STR = 0x3B, 0x1B, 0x2B
UINT16_MAX = 0xFFFF


class Command(IntEnum):
    """Client command numbers (the first payload byte of a packet sent to the robot)."""

    PULSE = 0  # also SYNC0
    OPEN = 1  # also SYNC1
    CLOSE = 2  # also SYNC2
    POLLING = 3
    ENABLE = 4
    SETA = 5
    SETV = 6
    SETO = 7
    MOVE = 8
    ROTATE = 9
    SETRV = 10
    VEL = 11
    HEAD = 12
    DHEAD = 13
    SAY = 15
    CONFIG = 18
    ENCODER = 19
    RVEL = 21
    SETRA = 23
    SONAR = 28
    STOP = 29
    DIGOUT = 30
    VEL2 = 32
    TTY2 = 42
    GETAUX = 43
    BUMPSTALL = 44
    JOYDRIVE = 47
    HOSTBAUD = 50
    E_STOP = 55


SYNC0, SYNC1, SYNC2 = 0, 1, 2
SIP_STOPPED, SIP_MOVING = 0x32, 0x33
CONFIG_PACKET, ENCODER_PACKET, AUX_PACKET = 0x20, 0x90, 0xB0
BAUD_CODES = {9600: 0, 19200: 1, 38400: 2, 57600: 3, 115200: 4}  # HOSTBAUD argument


class PacketError(ValueError):
    """A payload that is not what its type says (too short, bad argument marker...)."""


# -- framing ---------------------------------------------------------------------------------------
def checksum(payload: bytes) -> int:
    """The ARCOS checksum of a payload (the bytes after N, before the checksum)."""
    total = 0
    n = len(payload)
    for i in range(0, n - 1, 2):
        total = (total + ((payload[i] << 8) | payload[i + 1])) & 0xFFFF
    if n % 2:
        total ^= payload[-1]
    return total


def frame(payload: bytes) -> bytes:
    """Wrap a payload into a packet: header, count, payload, checksum (high byte first)."""
    payload = bytes(payload)
    count = len(payload) + 2
    if not payload or count > MAX_COUNT:
        raise PacketError(f"payload of {len(payload)} bytes does not fit an ARCOS packet (1..{MAX_COUNT - 2})")
    return HEADER + bytes([count]) + payload + checksum(payload).to_bytes(2, "big")


def unframe(packet: bytes) -> bytes:
    """The payload of one complete packet; :class:`PacketError` when framing or checksum is wrong."""
    packet = bytes(packet)
    if len(packet) < 6 or packet[:2] != HEADER:
        raise PacketError("not an ARCOS packet (no FA FB header)")
    count = packet[2]
    if len(packet) != count + 3:
        raise PacketError(f"length byte says {count + 3} bytes, got {len(packet)}")
    payload, received = packet[3:-2], int.from_bytes(packet[-2:], "big")
    if checksum(payload) != received:
        raise PacketError(f"bad checksum {received:04x} (expected {checksum(payload):04x})")
    return payload


@dataclass
class ReaderStats:
    """What a :class:`PacketReader` has seen: good packets, dropped bytes, failed checksums."""

    packets: int = 0
    bad_checksums: int = 0
    bad_lengths: int = 0
    skipped_bytes: int = 0


class PacketReader:
    """Incremental packet parser: :meth:`feed` arbitrary chunks, get back the valid payloads.

    Bytes before a header are skipped; a count outside ``MIN_COUNT..MAX_COUNT`` or a failed
    checksum drops only the first header byte, so a real packet that begins inside a bogus one is
    still found. A torn packet waits in the buffer for the rest of its bytes, unless a complete
    packet with a good checksum already starts inside it: then the waiting one was a corrupt count
    (any count up to 255 is legal, so a corrupt one would otherwise hold back up to 255 bytes of
    good packets behind it).
    """

    def __init__(self) -> None:
        self._buffer = bytearray()
        self.stats = ReaderStats()

    def feed(self, data: bytes) -> list[bytes]:
        self._buffer += data
        out: list[bytes] = []
        buf = self._buffer
        while True:
            start = buf.find(HEADER)
            if start < 0:
                keep = 1 if buf[-1:] == HEADER[:1] else 0  # a header may be torn after FA
                self.stats.skipped_bytes += len(buf) - keep
                del buf[: len(buf) - keep]
                break
            if start:
                self.stats.skipped_bytes += start
                del buf[:start]
            if len(buf) < 3:
                break
            count = buf[2]
            if not MIN_COUNT <= count <= MAX_COUNT:
                self.stats.bad_lengths += 1
                self.stats.skipped_bytes += 1
                del buf[:1]
                continue
            if len(buf) < count + 3:
                later = _complete_packet_after(buf)
                if later < 0:
                    break
                self.stats.bad_lengths += 1
                self.stats.skipped_bytes += later
                del buf[:later]
                continue
            payload = bytes(buf[3 : count + 1])
            if checksum(payload) != int.from_bytes(buf[count + 1 : count + 3], "big"):
                self.stats.bad_checksums += 1
                self.stats.skipped_bytes += 1
                del buf[:1]
                continue
            del buf[: count + 3]
            self.stats.packets += 1
            out.append(payload)
        return out

    @property
    def pending(self) -> int:
        """Bytes waiting for the rest of a packet."""
        return len(self._buffer)

    def clear(self) -> None:
        self._buffer.clear()


def _complete_packet_after(buf: bytearray) -> int:
    """Where, after the first byte, a complete packet with a good checksum starts in ``buf``; -1 if none."""
    at = buf.find(HEADER, 1)
    while at > 0:
        if len(buf) >= at + 3:
            count = buf[at + 2]
            end = at + count + 3
            if MIN_COUNT <= count <= MAX_COUNT and len(buf) >= end and \
                    checksum(bytes(buf[at + 3 : end - 2])) == int.from_bytes(buf[end - 2 : end], "big"):
                return at
        at = buf.find(HEADER, at + 1)
    return -1


# -- client commands -------------------------------------------------------------------------------
def encode_command(command: int, arg: int | str | bytes | None = None) -> bytes:
    """A complete packet for ``command`` with an optional integer or string argument."""
    if not 0 <= int(command) <= 255:
        raise PacketError(f"command number {command} is not a byte")
    payload = bytearray([int(command)])
    if arg is None:
        pass
    elif isinstance(arg, bool):
        raise PacketError("a boolean is not an ARCOS argument; send 0 or 1")
    elif isinstance(arg, int):
        if abs(arg) > UINT16_MAX:
            raise PacketError(f"argument {arg} is beyond +-{UINT16_MAX}")
        payload += bytes([ARG_INT if arg >= 0 else ARG_NINT]) + abs(arg).to_bytes(2, "little")
    else:
        text = arg.encode("latin-1") if isinstance(arg, str) else bytes(arg)
        if len(text) > MAX_COUNT - 6:  # N = command + marker + length + text + NUL + 2 checksum bytes
            raise PacketError(f"string argument of {len(text)} bytes is too long")
        payload += bytes([ARG_STR, len(text)]) + text + b"\x00"
    return frame(bytes(payload))


def decode_command(payload: bytes) -> tuple[int, int | bytes | None]:
    """``(command, argument)`` of a client packet's payload (the emulator's side)."""
    if not payload:
        raise PacketError("empty payload")
    command, rest = payload[0], payload[1:]
    if not rest:
        return command, None
    marker = rest[0]
    if marker in (ARG_INT, ARG_NINT):
        if len(rest) < 3:
            raise PacketError(f"command {command}: integer argument is cut short")
        value = int.from_bytes(rest[1:3], "little")
        return command, value if marker == ARG_INT else -value
    if marker == ARG_STR:
        if len(rest) < 2 or len(rest) < 2 + rest[1]:
            raise PacketError(f"command {command}: string argument is cut short")
        return command, bytes(rest[2 : 2 + rest[1]])
    raise PacketError(f"command {command}: unknown argument marker 0x{marker:02x}")


def encode_vel(mm_per_s: float) -> bytes:
    """VEL (11): forward velocity in mm/s, rounded to an integer."""
    return encode_command(Command.VEL, int(round(mm_per_s)))


def encode_rvel(deg_per_s: float) -> bytes:
    """RVEL (21): rotational velocity in deg/s (counter-clockwise positive), rounded."""
    return encode_command(Command.RVEL, int(round(deg_per_s)))


# -- robot packets ---------------------------------------------------------------------------------
def _cstrings(data: bytes, count: int) -> tuple[list[str], int]:
    """``count`` NUL-terminated strings from the start of ``data`` and the offset after them."""
    out, at = [], 0
    for _ in range(count):
        end = data.find(b"\x00", at)
        if end < 0:
            out.append(data[at:].decode("latin-1"))
            at = len(data)
            continue
        out.append(data[at:end].decode("latin-1"))
        at = end + 1
    return out, at


@dataclass(frozen=True, slots=True)
class Identity:
    """What the robot says about itself in its SYNC2 reply (e.g. "MobileSim", "Pioneer", "p3dx-sh")."""

    name: str = ""
    robot_class: str = ""
    subclass: str = ""


def encode_sync(step: int, identity: Identity | None = None) -> bytes:
    """The robot's echo of SYNC0/1/2 (the payload; SYNC2's carries three NUL-terminated strings)."""
    if step not in (SYNC0, SYNC1, SYNC2):
        raise PacketError(f"no sync step {step}")
    payload = bytes([step])
    if step == SYNC2:
        ident = identity or Identity()
        payload += b"".join(s.encode("latin-1") + b"\x00" for s in (ident.name, ident.robot_class, ident.subclass))
    return payload


def decode_sync(payload: bytes) -> tuple[int, Identity | None]:
    """``(step, identity)`` of a sync echo payload; identity only for SYNC2."""
    if not payload or payload[0] not in (SYNC0, SYNC1, SYNC2):
        raise PacketError("not a sync echo")
    if payload[0] != SYNC2:
        return payload[0], None
    strings, _ = _cstrings(payload[1:], 3)
    return SYNC2, Identity(*strings)


@dataclass(frozen=True, slots=True)
class Sip:
    """A standard SIP as raw integers (robot units), in payload order.

    ``x``/``y`` are the 15-bit position counters, ``theta`` is in 4096ths of a turn, velocities in
    mm/s (times VelConvFactor), ``battery`` in decivolts, ``sonar`` the (index, range) pairs that
    changed. ``extra`` keeps the optional trailing bytes (newer firmware), ``battery_x10`` and
    ``rot_vel`` are decoded from them when present.
    """

    moving: bool = False
    x: int = 0
    y: int = 0
    theta: int = 0
    left_vel: int = 0
    right_vel: int = 0
    battery: int = 0
    stall_bumpers: int = 0
    control: int = 0
    flags: int = 0
    compass: int = 0
    sonar: tuple[tuple[int, int], ...] = ()
    grip_state: int = 0
    anport: int = 0
    analog: int = 0
    digin: int = 0
    digout: int = 0
    extra: bytes = b""

    @property
    def left_stall(self) -> bool:
        return bool(self.stall_bumpers & 0x0001)

    @property
    def right_stall(self) -> bool:
        return bool(self.stall_bumpers & 0x0100)

    @property
    def rear_bumpers(self) -> int:
        """Bits 1-7 of the low byte, shifted down (bit 0: the first bumper)."""
        return (self.stall_bumpers & 0x00FE) >> 1

    @property
    def front_bumpers(self) -> int:
        """Bits 1-7 of the high byte, shifted down."""
        return (self.stall_bumpers & 0xFE00) >> 9

    @property
    def motors_enabled(self) -> bool:
        return bool(self.flags & 0x0001)

    @property
    def estop(self) -> bool:
        return bool(self.flags & 0x0020)

    @property
    def battery_x10(self) -> int | None:
        """Battery voltage in decivolts at full 16-bit range (newer firmware), or None."""
        return int.from_bytes(self.extra[0:2], "little") if len(self.extra) >= 2 else None

    @property
    def charge_state(self) -> int | None:
        return self.extra[2] if len(self.extra) >= 3 else None

    @property
    def rot_vel(self) -> int | None:
        """Rotational velocity reported by newer firmware (tenths of a deg/s, ROTVEL), or None."""
        return int.from_bytes(self.extra[3:5], "little", signed=True) if len(self.extra) >= 5 else None


_SIP_HEAD = struct.Struct("<BHHhhhBHhHBB")  # type .. sonar count (20 bytes)
_SIP_TAIL = struct.Struct("<BBBBB")


def decode_sip(payload: bytes) -> Sip:
    """Decode a standard SIP payload (type 0x32/0x33); :class:`PacketError` when it is cut short."""
    if len(payload) < _SIP_HEAD.size:
        raise PacketError(f"SIP of {len(payload)} bytes is shorter than its {_SIP_HEAD.size}-byte header")
    kind, x, y, th, lv, rv, batt, stall, control, flags, compass, n = _SIP_HEAD.unpack_from(payload)
    if kind not in (SIP_STOPPED, SIP_MOVING):
        raise PacketError(f"packet type 0x{kind:02x} is not a SIP")
    at = _SIP_HEAD.size
    if len(payload) < at + 3 * n:
        raise PacketError(f"SIP announces {n} sonar readings but is cut short")
    sonar = tuple((payload[at + 3 * i], int.from_bytes(payload[at + 3 * i + 1 : at + 3 * i + 3], "little"))
                  for i in range(n))
    at += 3 * n
    tail = payload[at : at + _SIP_TAIL.size].ljust(_SIP_TAIL.size, b"\x00")  # old firmware may stop early
    grip, anport, analog, digin, digout = _SIP_TAIL.unpack(tail)
    return Sip(kind == SIP_MOVING, x, y, th, lv, rv, batt, stall, control, flags, compass, sonar,
               grip, anport, analog, digin, digout, bytes(payload[at + _SIP_TAIL.size :]))


def encode_sip(sip: Sip) -> bytes:
    """The payload of a SIP (the emulator's side; the inverse of :func:`decode_sip`)."""
    head = _SIP_HEAD.pack(SIP_MOVING if sip.moving else SIP_STOPPED, sip.x & 0xFFFF, sip.y & 0xFFFF, sip.theta,
                          sip.left_vel, sip.right_vel, sip.battery, sip.stall_bumpers, sip.control, sip.flags,
                          sip.compass, len(sip.sonar))
    sonar = b"".join(bytes([i]) + r.to_bytes(2, "little") for i, r in sip.sonar)
    tail = _SIP_TAIL.pack(sip.grip_state, sip.anport, sip.analog, sip.digin, sip.digout)
    return head + sonar + tail + sip.extra


# -- the config packet (0x20), as ARIA's ArRobotConfigPacketReader reads it --------------------------
_CONFIG_FIELDS: tuple[tuple[str, str], ...] = (
    ("robot_type", "s"), ("subtype", "s"), ("serial", "s"), ("four_mots", "B"),
    ("rot_vel_top", "H"), ("trans_vel_top", "H"), ("rot_accel_top", "H"), ("trans_accel_top", "H"),
    ("pwm_max", "H"), ("name", "s"), ("sip_cycle", "B"), ("host_baud", "B"), ("aux_baud", "B"),
    ("gripper", "H"), ("front_sonar", "H"), ("rear_sonar", "B"), ("low_battery", "H"),
    ("rev_count", "H"), ("watchdog", "H"), ("normal_mpacs", "B"), ("stall_val", "H"),
    ("stall_count", "H"), ("joy_vel", "H"), ("joy_rot_vel", "H"), ("rot_vel_max", "H"),
    ("trans_vel_max", "H"), ("rot_accel", "H"), ("rot_decel", "H"), ("rot_kp", "H"), ("rot_kv", "H"),
    ("rot_ki", "H"), ("trans_accel", "H"), ("trans_decel", "H"), ("trans_kp", "H"), ("trans_kv", "H"),
    ("trans_ki", "H"), ("front_bumps", "B"), ("rear_bumps", "B"), ("charger", "B"), ("sonar_cycle", "B"),
    ("reset_baud", "B"), ("gyro_type", "B"), ("drift_factor", "h"), ("aux2_baud", "B"), ("aux3_baud", "B"),
    ("ticks_mm", "H"), ("shutdown_voltage", "H"), ("firmware", "s"),
)
RESET_BAUD_ALLOWED = 2  # the config packet's "reset baud" field: the robot takes HOSTBAUD


@dataclass(frozen=True, slots=True)
class RobotConfig:
    """The fields of a config packet that this driver reads (later fields are kept raw).

    Velocities in mm/s and deg/s, accelerations in mm/s^2 and deg/s^2, ``watchdog`` in ms,
    ``low_battery`` in decivolts, ``sip_cycle`` in ms, ``reset_baud`` 2 when the robot accepts
    HOSTBAUD; ``missing`` lists fields an older or shorter packet did not carry.
    """

    values: dict[str, int | str] = field(default_factory=dict)
    rest: bytes = b""
    missing: tuple[str, ...] = ()

    def get(self, name: str, default: int | str | None = None) -> int | str | None:
        return self.values.get(name, default)

    @property
    def allows_hostbaud(self) -> bool:
        """The robot takes a HOSTBAUD command (ARIA switches only then)."""
        return self.values.get("reset_baud") == RESET_BAUD_ALLOWED


def decode_config(payload: bytes) -> RobotConfig:
    """Decode a config packet (type 0x20), field by field while bytes remain."""
    if not payload or payload[0] != CONFIG_PACKET:
        raise PacketError("not a config packet")
    data, at = payload[1:], 0
    values: dict[str, int | str] = {}
    missing: list[str] = []
    for name, kind in _CONFIG_FIELDS:
        if kind == "s":
            if at >= len(data):
                missing.append(name)
                continue
            strings, used = _cstrings(data[at:], 1)
            values[name] = strings[0]
            at += used
            continue
        size = struct.calcsize("<" + kind)
        if at + size > len(data):
            missing.append(name)
            at = len(data)
            continue
        values[name] = struct.unpack_from("<" + kind, data, at)[0]
        at += size
    return RobotConfig(values, bytes(data[at:]), tuple(missing))


def encode_config(values: dict[str, int | str], rest: bytes = b"") -> bytes:
    """A config packet payload from field values (missing fields are zero/empty; emulator side)."""
    out = bytearray([CONFIG_PACKET])
    for name, kind in _CONFIG_FIELDS:
        value = values.get(name, "" if kind == "s" else 0)
        if kind == "s":
            out += str(value).encode("latin-1") + b"\x00"
        else:
            out += struct.pack("<" + kind, int(value))
    return bytes(out + rest)


# -- units per model -------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class ModelParams:
    """ARIA's conversion factors and limits of one robot model (from ARIA's ``params/<subclass>.p``;
    the table with its sources is in docs/protocols.md)."""

    name: str
    dist_conv: float  # mm per position unit
    angle_conv: float = 0.001534  # rad per THPOS unit (4096 per turn)
    vel_conv: float = 1.0  # mm/s per velocity unit
    range_conv: float = 1.0  # mm per sonar unit
    max_vel: float = 2200.0  # mm/s
    max_rot_vel: float = 500.0  # deg/s
    diff_conv: float = 0.0056  # rad/s per (mm/s) wheel speed difference (P3-DX/AT; 1/ (2 * half track))


MODELS: dict[str, ModelParams] = {
    "p3dx": ModelParams("p3dx", dist_conv=0.485, max_vel=2200.0, max_rot_vel=500.0),
    "p3at": ModelParams("p3at", dist_conv=0.465, max_vel=1200.0, max_rot_vel=300.0, diff_conv=0.0034),
    "p3dx-sh": ModelParams("p3dx-sh", dist_conv=1.0, max_vel=2200.0, max_rot_vel=500.0),
    "p3at-sh": ModelParams("p3at-sh", dist_conv=1.0, max_vel=1200.0, max_rot_vel=300.0, diff_conv=0.0034),
}


def model_for(subclass: str) -> ModelParams | None:
    """The parameters for a SYNC2 subclass such as ``"p3dx-sh"`` or ``"P3AT"``, or None."""
    key = subclass.strip().lower().replace("_", "-")
    return MODELS.get(key)


# -- odometry from wrapping counters ---------------------------------------------------------------
POSITION_BITS_MASK = 0x7FFF  # ARIA keeps 15 bits of XPOS/YPOS
POSITION_WRAP = 0x8000
POSITION_JUMP = 0x1000  # a delta beyond this is a wrap-around, not motion
THETA_UNITS = 4096


def position_delta(old: int, new: int) -> int:
    """Signed change between two 15-bit position counters, corrected for wrap-around."""
    delta = (new & POSITION_BITS_MASK) - (old & POSITION_BITS_MASK)
    if delta > POSITION_JUMP:
        delta -= POSITION_WRAP
    elif delta < -POSITION_JUMP:
        delta += POSITION_WRAP
    return delta


def theta_delta(old: int, new: int) -> int:
    """Signed change between two headings in 4096ths of a turn, in [-2048, 2048)."""
    return (new - old + THETA_UNITS // 2) % THETA_UNITS - THETA_UNITS // 2


@dataclass
class Odometry:
    """A continuous pose (mm, mm, rad) in the frame of the first SIP, from raw SIP counters.

    The robot's own counters wrap (15 bits of position, 4096 per turn) and restart on every new
    connection; this integrates their deltas, so the pose is continuous across both. The heading
    is the sum of THPOS deltas; positions are the robot's XPOS/YPOS deltas (already integrated by
    the firmware in its frame) rotated into the frame of the first SIP after :meth:`restart`.
    """

    params: ModelParams
    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0
    _last: tuple[int, int, int] | None = None
    _frame: float = 0.0  # our heading minus the robot's heading (rad), fixed at (re)start

    def restart(self) -> None:
        """The robot's counters restart (a new connection): keep the pose, re-anchor on the next SIP."""
        self._last = None

    def update(self, sip: Sip) -> tuple[float, float, float]:
        raw = (sip.x & POSITION_BITS_MASK, sip.y & POSITION_BITS_MASK, sip.theta % THETA_UNITS)
        if self._last is None:
            self._frame = self.theta - raw[2] * self.params.angle_conv
        else:
            dx = position_delta(self._last[0], raw[0]) * self.params.dist_conv
            dy = position_delta(self._last[1], raw[1]) * self.params.dist_conv
            c, s = math.cos(self._frame), math.sin(self._frame)
            self.x += c * dx - s * dy
            self.y += s * dx + c * dy
            self.theta += theta_delta(self._last[2], raw[2]) * self.params.angle_conv
        self._last = raw
        return self.x, self.y, self.theta


def measured_velocity(sip: Sip, params: ModelParams) -> tuple[float, float]:
    """``(v mm/s, w deg/s)`` the robot reports: v the mean wheel speed; w its ROTVEL (tenths of a
    deg/s) when the SIP carries one, else from the wheel speed difference (ARIA's
    ``ArRobot::processMotorPacket``: ``radToDeg((right - left) / 2 * DiffConvFactor)``)."""
    left, right = sip.left_vel * params.vel_conv, sip.right_vel * params.vel_conv
    rot_vel = sip.rot_vel
    w = rot_vel / 10.0 if rot_vel is not None else math.degrees((right - left) / 2.0 * params.diff_conv)
    return (left + right) / 2.0, w
