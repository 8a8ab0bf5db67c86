"""The PTU-D46 driver against the emulated unit (pty), and its codec (the message grammar of
docs/protocols.md: a stream of ``*``/``!`` messages, which need not be on lines of their own)."""

from __future__ import annotations

import math
import time

import numpy as np
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
    assert codec.parse_message("*") == codec.Reply("ok", "*", None)
    assert codec.parse_message("* 185.1428").value == pytest.approx(185.1428)
    assert codec.parse_message("* Current Pan position is -583").value == -583
    assert codec.parse_message("! Illegal argument") == codec.Reply("error", "Illegal argument")
    assert codec.parse_message("!P").axis == "pan" and codec.parse_message("!T").axis == "tilt"
    assert codec.parse_message("PTU-D46 Controller v2.14.0").kind == "noise"
    assert codec.to_positions(math.radians(0.0514285), RES) == 1
    assert codec.to_radians(3090, RES) == pytest.approx(math.radians(158.914), abs=1e-5)


def _kinds(replies):
    return [(r.kind, r.text) for r in replies]


def test_messages_are_split_at_their_markers_not_at_line_ends():
    reader = codec.MessageReader()
    assert reader.feed(b"PTU-D46 Controller v2.14.0\r\n* 1") == [] and reader.noise == 26  # banner: noise
    assert _kinds(reader.feed(b"2\r\n!P!P\r\n*\n")) == [("ok", "* 12"), ("limit", "!P"), ("limit", "!P"),
                                                         ("ok", "*")]  # torn, run together, both line ends
    assert _kinds(reader.feed(b"*! Illegal argument\r\n")) == [("ok", "*"), ("error", "Illegal argument")]
    assert _kinds(reader.feed(b"! Pan! too far\r\n")) == [("error", "Pan! too far")]  # "!" inside a text
    assert _kinds(reader.feed(b"* 1* 2\r\n")) == [("ok", "* 1"), ("ok", "* 2")]  # "*" always starts one
    reader.feed(b"* " + b"9" * 300)
    assert reader.feed(b"\r\n") == [] and reader.noise > 300  # an endless message is dropped


def test_a_reset_is_read_as_limit_hits_then_homed():
    """flir_ptu_driver's reset answer, ``!T!T!P!P*`` on one line with no line end after it."""
    reader = codec.MessageReader()
    assert _kinds(reader.feed(b"!T!T!P!P*")) == [("limit", "!T"), ("limit", "!T"), ("limit", "!P"), ("limit", "!P")]
    assert _kinds(reader.idle()) == [("homed", "*")]  # its last byte: complete when nothing more comes
    assert _kinds(reader.feed(b"!T\r\n")) + _kinds(reader.feed(b"*\r\n")) == [("limit", "!T"), ("ok", "*")]
    assert reader.idle() == []  # a bare "*" waits for its line end unless limit hits came before it
    reader.feed(b"!P!T")
    reader.clear()  # a command is sent in between: the limit hits are kept
    assert _kinds(reader.feed(b"*\r\n")) == [("homed", "*")]


@given(st.lists(st.binary(max_size=40), max_size=8))
@settings(max_examples=100, deadline=None)
def test_message_reader_never_raises(chunks):
    reader = codec.MessageReader()
    for chunk in chunks:
        for reply in reader.feed(chunk) + reader.idle():
            assert reply.kind in ("ok", "error", "limit", "homed")


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


def test_the_state_carries_what_the_unit_reports_within_the_soft_limits(ptu):
    pan_tilt, _ = ptu(settings={"pan_max_deg": 120.0})
    limits = pan_tilt.state().limits
    assert np.degrees(limits.pan).tolist() == pytest.approx([-3090 * RES / 3600, 120.0])  # -158.91: the unit's
    assert np.degrees(limits.tilt).tolist() == pytest.approx([-907 * RES / 3600, 604 * RES / 3600])
    assert math.degrees(limits.pan_step) == pytest.approx(RES / 3600)
    assert math.degrees(limits.max_speed) == pytest.approx(2902 * RES / 3600)  # 149.2 deg/s
    assert math.degrees(limits.min_speed) == pytest.approx(57 * RES / 3600)
    pan, _ = limits.clip(math.radians(-159.0), 0.0)
    pan_tilt.move(pan, 0.0, 1.0)  # the mission's -159 clipped into the unit: accepted
    assert pan_tilt.state().homings == 0


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


def test_run_together_limit_hits_are_not_errors(ptu):
    pan_tilt, emulator = ptu()
    emulator.inject("!P!T")
    pan_tilt.move(0.1, 0.0, 1.0)
    assert _wait(lambda: pan_tilt.limit_hits == 2 and not pan_tilt.state().moving)
    assert pan_tilt.errors == 0 and pan_tilt.fault is None


def test_a_unit_that_resets_and_homes_mid_session_goes_back_to_its_target(ptu):
    """The unit resets: silent while it finds its limits (``!T!T!P!P``, then ``*``), then at home. The
    mission must not fail nor hang: no error, no fault, and the last move is sent again."""
    pan_tilt, emulator = ptu(time_scale=10.0, settings={"max_timeouts": 2})
    pan_tilt.move(math.radians(30.0), math.radians(-10.0), math.radians(60.0))
    assert _wait(lambda: not pan_tilt.state().moving)
    target = pan_tilt.positions()
    emulator.home(duration=1.0)  # five times the reply timeout, more than max_timeouts replies missed
    assert _wait(lambda: pan_tilt.homings == 1, timeout=6.0)
    assert [c for c in emulator.commands if c.ignored]  # it did ask, and was not answered, meanwhile
    assert _wait(lambda: not pan_tilt.state().moving and pan_tilt.positions() == target, timeout=6.0)
    assert pan_tilt.state() is not None  # no PtuError was waiting
    assert pan_tilt.fault is None and pan_tilt.errors == 0 and pan_tilt.limit_hits == 4
    assert emulator.homings == 1 and emulator.position() == pytest.approx(target, abs=1)  # where it was sent


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


def _wait(predicate, timeout: float = 5.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.005)
    return bool(predicate())
