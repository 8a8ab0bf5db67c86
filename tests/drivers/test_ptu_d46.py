"""The PTU-D46 driver against the emulated unit (pty), and its codec."""

from __future__ import annotations

import math
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drivers import ptu_d46_codec as codec
from drivers.common import DriverFault
from drivers.interfaces import PanTilt
from drivers.ptu_d46 import PtuD46Settings, PtuError, open_ptu
from maps.store import InputError
from tests.drivers.conftest import FAST_PTU

RES = 185.1428  # arc-seconds per position: 0.0514 deg


# -- codec ---------------------------------------------------------------------------------------------
def test_codec_commands_and_replies():
    assert codec.encode("pp", -90) == b"PP-90 "
    assert codec.encode("PR") == b"PR "
    assert codec.split_commands("pp100 TP\r ps  x! ") == [("PP", 100.0), ("TP", None), ("PS", None), ("?x!", None)]
    assert codec.parse_line("*") == codec.Reply("ok", "*", None)
    assert codec.parse_line("* 185.1428").value == pytest.approx(185.1428)
    assert codec.parse_line("* Current Pan position is -583").value == -583
    assert codec.parse_line("! Illegal argument") == codec.Reply("error", "Illegal argument")
    assert codec.parse_line("!P").axis == "pan" and codec.parse_line("!T").axis == "tilt"
    assert codec.parse_line("PTU-D46 Controller v2.14.0").kind == "noise"
    assert codec.to_positions(math.radians(0.0514285), RES) == 1
    assert codec.to_radians(3090, RES) == pytest.approx(math.radians(158.914), abs=1e-5)


def test_line_reader_handles_torn_lines_and_both_line_ends():
    reader = codec.LineReader()
    assert reader.feed(b"* 1") == []
    assert reader.feed(b"2\r\n!P\r\n\r\n*") == ["* 12", "!P"]
    assert reader.feed(b"\n") == ["*"]
    assert reader.feed(b"x" * 300) == [] and reader.dropped == 300


@given(st.binary(max_size=200))
@settings(max_examples=100, deadline=None)
def test_line_reader_and_parser_never_raise(data):
    for line in codec.LineReader().feed(data):
        assert codec.parse_line(line).kind in ("ok", "error", "limit", "noise")


@given(st.floats(-3.0, 3.0))
@settings(max_examples=100, deadline=None)
def test_positions_round_trip_within_half_a_count(angle):
    assert abs(codec.to_radians(codec.to_positions(angle, RES), RES) - angle) <= math.radians(RES / 3600) / 2 + 1e-12


# -- driver --------------------------------------------------------------------------------------------
def test_initialisation_sequence(ptu):
    pan_tilt, emulator = ptu(tilt_resolution=46.2857)
    assert isinstance(pan_tilt, PanTilt)
    sent = [c.name for c in emulator.commands]
    assert sent[:3] == ["FT", "ED", "CI"]
    assert sent[3:5] == ["PR", "TR"]  # one after the other: the replies look alike
    assert {"PN", "PX", "TN", "TX", "PL", "PU", "TL", "TU", "V"} <= set(sent)
    assert pan_tilt.limits.pan.resolution == pytest.approx(RES)
    assert pan_tilt.limits.tilt.resolution == pytest.approx(46.2857)
    degrees = pan_tilt.limit_degrees()
    assert degrees["pan"] == pytest.approx((-158.914, 158.914), abs=1e-3)
    assert degrees["tilt"] == pytest.approx((-907 * 46.2857 / 3600, 604 * 46.2857 / 3600), abs=1e-3)
    assert "v2.14.0" in pan_tilt.version
    assert pan_tilt.state().pan == 0.0 and not pan_tilt.state().moving


def test_moves_in_radians_with_speed_and_reads_back(ptu):
    pan_tilt, emulator = ptu(time_scale=10.0)
    pan_tilt.move(math.radians(30.0), math.radians(-20.0), math.radians(40.0))
    assert pan_tilt.state().moving
    assert _wait(lambda: not pan_tilt.state().moving)
    state = pan_tilt.state()
    assert state.pan == pytest.approx(math.radians(30.0), abs=math.radians(0.06))
    assert state.tilt == pytest.approx(math.radians(-20.0), abs=math.radians(0.06))
    assert pan_tilt.positions() == (583, -389)
    speed = emulator.named("PS")[-1].value
    assert speed == codec.to_positions(math.radians(40.0), RES)
    sets = [(c.name, c.value) for c in emulator.commands if c.name in ("PP", "TP") and c.value is not None]
    assert sets == [("PP", 583), ("TP", -389)]


def test_only_the_newest_move_is_sent(ptu):
    pan_tilt, emulator = ptu()
    emulator.reply_delay = 0.015
    for degrees in range(1, 11):
        pan_tilt.move(math.radians(degrees), 0.0, 1.0)
    assert _wait(lambda: not pan_tilt.state().moving)
    targets = [c.value for c in emulator.named("PP") if c.value is not None]
    assert targets[-1] == codec.to_positions(math.radians(10), RES) and len(targets) < 10


def test_speeds_are_clamped_to_the_unit_bounds(ptu):
    pan_tilt, emulator = ptu()
    pan_tilt.move(0.1, 0.0, 100.0)
    assert _wait(lambda: emulator.named("PS"))
    assert emulator.named("PS")[-1].value == 2902
    assert pan_tilt.errors == 0


def test_limits_are_enforced_before_sending(ptu):
    pan_tilt, emulator = ptu(settings={"pan_max_deg": 90.0})
    before = len(emulator.commands)
    with pytest.raises(ValueError, match="pan 100.00 deg is outside"):
        pan_tilt.move(math.radians(100.0), 0.0, 1.0)
    with pytest.raises(ValueError, match="tilt"):
        pan_tilt.move(0.0, math.radians(-60.0), 1.0)
    with pytest.raises(ValueError):
        pan_tilt.move(0.0, 0.0, 0.0)
    time.sleep(0.05)
    assert not [c for c in emulator.commands[before:] if c.value is not None]  # nothing was commanded


def test_refused_command_is_surfaced_once(ptu):
    pan_tilt, emulator = ptu()
    emulator.refuse("PP", "Motor power off")
    pan_tilt.move(0.2, 0.0, 1.0)
    assert _wait(lambda: pan_tilt.errors == 1)
    with pytest.raises(PtuError, match="Motor power off"):
        pan_tilt.state()
    assert pan_tilt.state() is not None  # raised once; the unit still answers
    assert "Motor power off" in pan_tilt.last_error
    emulator.refuse("TP", "Illegal argument", query=True)  # a refused read-back is surfaced too, not fatal
    assert _wait(lambda: pan_tilt.errors == 2)
    with pytest.raises(PtuError, match="TP"):
        pan_tilt.state()
    assert pan_tilt.fault is None


def test_unsolicited_lines_are_tolerated(ptu):
    pan_tilt, emulator = ptu()
    emulator.inject_line("!P")
    emulator.inject_line("PTU-D46 Controller ready")
    emulator.inject_line("!T")
    assert _wait(lambda: pan_tilt.limit_hits == 2)
    pan_tilt.move(0.1, 0.05, 1.0)
    assert _wait(lambda: not pan_tilt.state().moving)
    assert pan_tilt.fault is None and pan_tilt.errors == 0


def test_slow_replies_are_waited_for(ptu):
    pan_tilt, emulator = ptu()
    emulator.reply_delay = 0.06  # a third of the reply timeout
    pan_tilt.move(0.1, 0.0, 1.0)
    assert _wait(lambda: not pan_tilt.state().moving, timeout=3.0)
    assert pan_tilt.fault is None


def test_missing_replies_become_a_fault(ptu):
    pan_tilt, emulator = ptu(settings={"max_timeouts": 2, "reply_timeout": 0.05})
    emulator.mute = True
    assert _wait(lambda: pan_tilt.fault is not None, timeout=2.0)
    assert "replies missing" in pan_tilt.fault and pan_tilt.timeouts >= 2
    with pytest.raises(DriverFault):
        pan_tilt.state()
    pan_tilt.halt()  # never raises


def test_dropped_link_is_a_fault(ptu):
    pan_tilt, emulator = ptu()
    emulator.drop_link()
    assert _wait(lambda: pan_tilt.fault is not None)
    with pytest.raises(DriverFault):
        pan_tilt.move(0.0, 0.0, 1.0)


def test_halt_and_close(ptu):
    pan_tilt, emulator = ptu(time_scale=0.2)
    pan_tilt.move(math.radians(90), 0.0, math.radians(10))
    assert _wait(lambda: emulator.named("PP") and emulator.position()[0] > 1)
    pan_tilt.halt()
    assert _wait(lambda: emulator.named("H"))
    assert _wait(lambda: not pan_tilt.state().moving)
    pan_tilt.close()
    assert len(emulator.named("H")) == 2
    with pytest.raises(DriverFault, match="closed"):
        pan_tilt.state()
    pan_tilt.close()


def test_open_errors(tmp_path, ptu_emulator):
    with pytest.raises(ConnectionError, match="ttyUSB7"):
        open_ptu(port=str(tmp_path / "ttyUSB7"))
    emulator = ptu_emulator()
    emulator.mute = True
    with pytest.raises(TimeoutError, match="did not answer CI"):
        open_ptu(port=emulator.port, **{**FAST_PTU, "reply_timeout": 0.05})
    with pytest.raises(InputError, match="poll_period"):
        open_ptu(port="/dev/null", poll_period=0)
    schema = PtuD46Settings.model_json_schema()["properties"]
    assert all(p.get("description") for p in schema.values())


def _wait(predicate, timeout: float = 2.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.005)
    return bool(predicate())
