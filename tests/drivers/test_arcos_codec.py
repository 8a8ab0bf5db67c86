"""The ARCOS codec: example packets worked out by hand from the framing rules of docs/protocols.md,
SIP/config/sync decoding, resynchronisation, packets up to 255 bytes, wrap-around, units per
model, the measured velocity, and round-trip properties."""

from __future__ import annotations

import math
import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drivers import arcos
from drivers.arcos import Command, Identity, Odometry, PacketReader, Sip

EXAMPLES = {  # docs/protocols.md, "ARCOS framing": header, count, payload, checksum
    "SYNC0": ((Command.PULSE, None), "FA FB 03 00 00 00"),
    "ENABLE 1": ((Command.ENABLE, 1), "FA FB 06 04 3B 01 00 05 3B"),
    "VEL 200": ((Command.VEL, 200), "FA FB 06 0B 3B C8 00 D3 3B"),
    "RVEL -30": ((Command.RVEL, -30), "FA FB 06 15 1B 1E 00 33 1B"),
    "STOP": ((Command.STOP, None), "FA FB 03 1D 00 1D"),
}


@pytest.mark.parametrize("name", EXAMPLES)
def test_examples_of_the_protocol_notes(name):
    (command, arg), text = EXAMPLES[name]
    packet = bytes.fromhex(text)
    assert arcos.encode_command(command, arg) == packet
    assert arcos.decode_command(arcos.unframe(packet)) == (command, arg)
    assert PacketReader().feed(packet) == [packet[3:-2]]


def test_velocity_helpers_round_to_robot_units():
    assert arcos.encode_vel(199.6) == bytes.fromhex("FA FB 06 0B 3B C8 00 D3 3B")
    assert arcos.encode_rvel(-30.2) == bytes.fromhex("FA FB 06 15 1B 1E 00 33 1B")


def test_checksum_pairs_big_endian_and_xors_an_odd_byte():
    assert arcos.checksum(b"\x04\x3b\x01\x00") == 0x053B
    assert arcos.checksum(b"\x1d") == 0x001D
    assert arcos.checksum(b"\x12\x34\x56") == 0x1234 ^ 0x56
    assert arcos.checksum(b"\xff\xff\x00\x02") == 0x0001  # masked to 16 bits after each add


def test_string_argument_has_length_and_a_nul():
    packet = arcos.encode_command(Command.SAY, "hi")
    assert packet[3:-2] == bytes([Command.SAY, 0x2B, 2]) + b"hi\x00"
    assert arcos.decode_command(packet[3:-2]) == (Command.SAY, b"hi")


def test_bad_arguments_are_refused():
    with pytest.raises(arcos.PacketError):
        arcos.encode_command(Command.VEL, 70000)
    with pytest.raises(arcos.PacketError):
        arcos.encode_command(Command.ENABLE, True)
    with pytest.raises(arcos.PacketError):
        arcos.decode_command(bytes([Command.VEL, 0x3B, 0x01]))
    with pytest.raises(arcos.PacketError):
        arcos.unframe(bytes.fromhex("FA FB 06 0B 3B C8 00 D3 3C"))


def test_a_long_packet_keeps_an_unsigned_count():
    """The config packet has N = 0x89: a signed length byte would break it (a pitfall of old drivers)."""
    payload = bytes([arcos.CONFIG_PACKET]) + bytes(range(134))
    packet = arcos.frame(payload)
    assert packet[2] == 0x89
    assert PacketReader().feed(packet) == [payload]


def _sip_bytes() -> bytes:
    """A SIP built byte by byte from the offsets in docs/protocols.md (not with the codec)."""
    body = bytes([0x33])
    body += struct.pack("<H", 0x7FF0) + struct.pack("<H", 100)  # XPOS, YPOS
    body += struct.pack("<h", 1024)  # THPOS: a quarter turn
    body += struct.pack("<hh", -120, 130)  # L VEL, R VEL
    body += bytes([124])  # BATTERY 12.4 V
    body += bytes([0b0000_0101, 0b0000_0011])  # STALL&BUMPERS: left stall + rear bumper 1; right stall + front 0
    body += struct.pack("<h", 0) + struct.pack("<H", 0x0021)  # CONTROL, FLAGS: motors on, e-stop
    body += bytes([0, 2]) + bytes([3]) + struct.pack("<H", 1500) + bytes([7]) + struct.pack("<H", 250)
    body += bytes([1, 2, 3, 4, 5])  # GRIPSTATE ANPORT ANALOG DIGIN DIGOUT
    body += struct.pack("<H", 131) + bytes([1]) + struct.pack("<h", -45)  # BATTERYX10, CHARGESTATE, ROTVEL
    return body


def test_sip_fields_at_their_offsets():
    sip = arcos.decode_sip(_sip_bytes())
    assert sip.moving and (sip.x, sip.y, sip.theta) == (0x7FF0, 100, 1024)
    assert (sip.left_vel, sip.right_vel, sip.battery) == (-120, 130, 124)
    assert sip.left_stall and sip.right_stall
    assert sip.rear_bumpers == 0b10 and sip.front_bumpers == 0b1
    assert sip.motors_enabled and sip.estop
    assert sip.sonar == ((3, 1500), (7, 250))
    assert (sip.grip_state, sip.anport, sip.analog, sip.digin, sip.digout) == (1, 2, 3, 4, 5)
    assert (sip.battery_x10, sip.charge_state, sip.rot_vel) == (131, 1, -45)
    assert arcos.encode_sip(sip) == _sip_bytes()


def test_old_firmware_sip_without_optional_fields():
    body = _sip_bytes()[: -(5 + 5)]  # no tail, no extras
    sip = arcos.decode_sip(body)
    assert sip.battery_x10 is None and sip.rot_vel is None and sip.digout == 0


def test_cut_sips_are_refused():
    with pytest.raises(arcos.PacketError):
        arcos.decode_sip(_sip_bytes()[:15])
    body = bytearray(_sip_bytes()[:20])
    body[19] = 5  # five sonar readings announced, none there
    with pytest.raises(arcos.PacketError):
        arcos.decode_sip(bytes(body))


def test_sync_echoes_and_identity():
    assert arcos.decode_sync(b"\x00") == (0, None)
    payload = b"\x02MobileSim\x00Pioneer\x00p3dx-sh\x00"
    assert arcos.decode_sync(payload) == (2, Identity("MobileSim", "Pioneer", "p3dx-sh"))
    assert arcos.encode_sync(2, Identity("MobileSim", "Pioneer", "p3dx-sh")) == payload


def test_config_packet_decodes_while_bytes_remain():
    values = {"robot_type": "Pioneer", "subtype": "p3at", "serial": "AT123", "rot_vel_top": 300,
              "trans_vel_top": 1200, "name": "Rover", "watchdog": 2000, "trans_ki": 7, "reset_baud": 2,
              "drift_factor": -12, "ticks_mm": 128, "firmware": "1.9"}
    config = arcos.decode_config(arcos.encode_config(values, rest=b"\x09\x09"))
    assert {k: config.get(k) for k in values} == values
    assert config.rest == b"\x09\x09" and config.missing == ()
    assert config.allows_hostbaud
    short = arcos.decode_config(arcos.encode_config(values)[:30])
    assert short.get("robot_type") == "Pioneer" and "watchdog" in short.missing and not short.allows_hostbaud


def test_reader_resynchronises_on_garbage_and_corrupt_packets():
    good = [arcos.encode_command(Command.VEL, 100), arcos.encode_command(Command.RVEL, -5)]
    corrupt = bytearray(arcos.encode_command(Command.VEL, 300))
    corrupt[4] ^= 0xFF
    stream = b"\x00\x17\xfa" + good[0] + b"\xfa\xfb\x01\x01" + bytes(corrupt) + b"\xfa\xfb" + good[1]
    reader = PacketReader()
    out = [p for byte in stream for p in reader.feed(bytes([byte]))]  # one byte at a time: torn everywhere
    assert out == [g[3:-2] for g in good]
    assert reader.stats.bad_checksums >= 1 and reader.stats.bad_lengths >= 1 and reader.stats.skipped_bytes > 0


def test_a_255_byte_packet_round_trips_torn_anywhere():
    payload = bytes([arcos.CONFIG_PACKET]) + bytes((7 * i) % 250 for i in range(252))  # N = 255, no FA in it
    packet = arcos.frame(payload)
    assert len(packet) == 258 and packet[2] == 255 == arcos.MAX_COUNT
    reader = PacketReader()
    out = [p for byte in packet for p in reader.feed(bytes([byte]))]
    assert out == [payload] and reader.stats.skipped_bytes == 0
    with pytest.raises(arcos.PacketError):
        arcos.frame(payload + b"\x00")  # 256 does not fit the count byte
    command = arcos.encode_command(Command.SAY, "x" * 249)  # the longest string argument
    assert len(command) == 258 and arcos.decode_command(arcos.unframe(command)) == (Command.SAY, b"x" * 249)


def test_a_corrupt_count_does_not_hold_back_the_packets_behind_it():
    """Any count up to 255 is legal, so a corrupt one would wait for 255 bytes; a complete packet with a
    good checksum that starts inside it is taken at once instead."""
    good = [arcos.encode_command(Command.VEL, 100), arcos.encode_command(Command.RVEL, -5)]
    reader = PacketReader()
    assert reader.feed(b"\xfa\xfb\xf0\x01" + good[0]) == [good[0][3:-2]]
    assert reader.feed(good[1]) == [good[1][3:-2]]
    assert reader.stats.bad_lengths == 1 and reader.stats.skipped_bytes == 4


def test_a_packet_that_starts_inside_a_bogus_one_is_found():
    real = arcos.encode_command(Command.STOP)
    bogus = b"\xfa\xfb\x08\x01"  # claims 8 more bytes; the real packet starts inside them
    reader = PacketReader()
    assert reader.feed(bogus + real + b"\x00" * 8) == [real[3:-2]]


def test_position_wrap_around():
    assert arcos.position_delta(0x7FF0, 0x0010) == 0x20
    assert arcos.position_delta(0x0010, 0x7FF0) == -0x20
    assert arcos.position_delta(100, 600) == 500
    assert arcos.theta_delta(4090, 6) == 12
    assert arcos.theta_delta(6, 4090) == -12


@pytest.mark.parametrize(("model", "mm"), [("p3dx", 485.0), ("p3at", 465.0), ("p3dx-sh", 1000.0), ("p3at-sh", 1000.0)])
def test_units_per_model(model, mm):
    odometry = Odometry(arcos.MODELS[model])
    odometry.update(Sip(x=0x7E00, theta=0))
    x, y, theta = odometry.update(Sip(x=(0x7E00 + 1000) & 0x7FFF, theta=1024))  # crosses the wrap
    assert x == pytest.approx(mm) and y == pytest.approx(0.0)
    assert theta == pytest.approx(1024 * 0.001534)


def test_odometry_starts_at_zero_in_the_first_sips_frame_and_survives_restarts():
    params = arcos.MODELS["p3dx-sh"]
    odometry = Odometry(params)
    quarter = 1024  # the robot already faces +y in its own frame
    odometry.update(Sip(x=5000, y=5000, theta=quarter))
    x, y, theta = odometry.update(Sip(x=5000, y=5100, theta=quarter))  # 100 mm along the robot's +y
    assert (x, y, theta) == pytest.approx((100.0, 0.0, 0.0), abs=0.2)
    odometry.restart()  # a new connection: the robot's counters start again at 0
    odometry.update(Sip(x=0, y=0, theta=0))
    x, y, theta = odometry.update(Sip(x=50, y=0, theta=0))
    assert (x, y, theta) == pytest.approx((150.0, 0.0, 0.0), abs=0.2)


def test_measured_velocity_prefers_the_robots_rotvel():
    params = arcos.MODELS["p3at"]  # DiffConvFactor 0.0034
    wheels = Sip(left_vel=100, right_vel=300)  # old firmware: no ROTVEL
    v, w = arcos.measured_velocity(wheels, params)
    assert v == 200.0 and w == pytest.approx(math.degrees(100 * 0.0034))  # (300 - 100) / 2 * 0.0034 rad/s = 19.48 deg/s
    rot_vel = (-125).to_bytes(2, "little", signed=True)
    reported = Sip(left_vel=100, right_vel=300, extra=(126).to_bytes(2, "little") + b"\x00" + rot_vel)
    assert arcos.measured_velocity(reported, params) == (200.0, -12.5)  # ROTVEL -125 tenths of a deg/s


def test_model_lookup_by_subclass():
    assert arcos.model_for("P3DX-SH").name == "p3dx-sh"
    assert arcos.model_for("p3at").dist_conv == 0.465
    assert arcos.model_for("amigo") is None


# -- properties ----------------------------------------------------------------------------------------
arguments = st.one_of(st.none(), st.integers(-0xFFFF, 0xFFFF), st.binary(max_size=40))


@given(command=st.integers(0, 255), arg=arguments)
@settings(max_examples=100, deadline=None)
def test_command_round_trip(command, arg):
    packet = arcos.encode_command(command, arg)
    assert len(packet) <= 3 + arcos.MAX_COUNT
    assert arcos.decode_command(arcos.unframe(packet)) == (command, arg)


u16, i16, u8 = st.integers(0, 0xFFFF), st.integers(-0x8000, 0x7FFF), st.integers(0, 255)
sips = st.builds(Sip, moving=st.booleans(), x=u16, y=u16, theta=i16, left_vel=i16, right_vel=i16, battery=u8,
                 stall_bumpers=u16, control=i16, flags=u16, compass=u8,
                 sonar=st.lists(st.tuples(u8, u16), max_size=16).map(tuple), grip_state=u8, anport=u8, analog=u8,
                 digin=u8, digout=u8, extra=st.binary(max_size=12))


@given(sip=sips)
@settings(max_examples=100, deadline=None)
def test_sip_round_trip(sip):
    payload = arcos.encode_sip(sip)
    assert arcos.decode_sip(arcos.unframe(arcos.frame(payload))) == sip


@given(payloads=st.lists(st.binary(min_size=1, max_size=60), max_size=8),
       noise=st.lists(st.binary(max_size=12).map(lambda b: b.replace(b"\xfa", b"")), max_size=9),
       cuts=st.lists(st.integers(1, 40), max_size=30))
@settings(max_examples=100, deadline=None)
def test_reader_finds_every_packet_whatever_the_noise_and_the_chunking(payloads, noise, cuts):
    stream = b""
    for i, payload in enumerate(payloads):
        stream += (noise[i] if i < len(noise) else b"") + arcos.frame(payload)
    reader, out, at = PacketReader(), [], 0
    for cut in cuts:
        out += reader.feed(stream[at : at + cut])
        at += cut
    out += reader.feed(stream[at:])
    assert out == payloads


@given(data=st.binary(max_size=300))
@settings(max_examples=150, deadline=None)
def test_reader_never_raises_on_noise(data):
    for payload in PacketReader().feed(data):
        assert arcos.MIN_COUNT - 2 <= len(payload) <= arcos.MAX_COUNT - 2


@given(start=st.integers(0, 0x7FFF), steps=st.lists(st.integers(-0xFFF, 0xFFF), max_size=30))
@settings(max_examples=100, deadline=None)
def test_odometry_is_continuous_across_wraps(start, steps):
    odometry = Odometry(arcos.MODELS["p3dx-sh"])
    odometry.update(Sip(x=start))
    raw, total = start, 0
    for step in steps:
        raw, total = (raw + step) & 0x7FFF, total + step
        x, _, _ = odometry.update(Sip(x=raw))
    assert math.isclose(odometry.x, float(total), abs_tol=1e-6)
