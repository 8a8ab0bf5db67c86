"""The Pioneer driver against the ARCOS emulator (pty like a USB-serial robot, TCP like MobileSim).

The stop-timing tests read the emulator's event log: every accepted command is recorded with the
time it arrived, so "the stop arrived within 200 ms of the fault" is measured on the robot's side.
"""

from __future__ import annotations

import math
import time

import pytest
import serial

from drivers import arcos as protocol
from drivers.arcos import Identity
from drivers.common import DriverFault
from drivers.interfaces import Base, Robot
from drivers.pioneer import PioneerSettings, open_base
from maps.store import InputError
from tests.drivers.conftest import FAST_BASE

STOP_WITHIN = 0.2  # s, from the issue: on any fault the base gets a stop within 200 ms


def _zero_velocity_after(emulator, t: float):
    """The first event after ``t`` that leaves the robot commanded to rest (STOP, or VEL 0 with RVEL 0)."""
    for event in emulator.named("STOP") + emulator.named("ENABLE"):
        if event.t >= t and (event.name == "STOP" or event.arg == 0):
            return event
    return None


@pytest.mark.parametrize("transport", ["pty", "tcp"])
def test_connects_and_reports_what_the_robot_said(base, transport):
    pioneer, emulator = base(transport=transport, identity=Identity("lab", "Pioneer", "p3dx"))
    assert isinstance(pioneer, Base)
    assert pioneer.identity == Identity("lab", "Pioneer", "p3dx")
    assert pioneer.config is not None and pioneer.config.get("watchdog") == 2000
    assert pioneer.params.name == "p3dx" and pioneer.fault is None
    status = pioneer.status()
    assert status.motors_enabled and not status.estop and not pioneer.stalled()
    assert pioneer.battery() == pytest.approx(12.6)
    assert emulator.wait_for(lambda: len(pioneer.sonar()) == 8)
    assert set(pioneer.sonar().values()) == {5.0}
    names = [e.name for e in emulator.events]
    assert names[:4] == ["OPEN", "CONFIG", "SONAR", "ENABLE"] and emulator.named("ENABLE")[0].arg == 1
    assert emulator.bad_packets == 0


def test_odometry_follows_the_integrated_motion(base):  # over TCP in the mission test
    pioneer, emulator = base(time_scale=8.0, start_pose=(3.0, -2.0, 2.5))
    pioneer.drive(0.5, 0.0)
    assert emulator.wait_for(lambda: emulator.v == 500.0)
    time.sleep(0.12)
    pioneer.drive(0.0, math.radians(60))
    assert emulator.wait_for(lambda: emulator.v == 0.0 and emulator.w == 60.0)
    time.sleep(0.12)
    pioneer.drive(0.2, math.radians(-30))
    time.sleep(0.1)
    pioneer.stop()
    assert emulator.wait_for(lambda: not emulator.moving)
    time.sleep(0.06)  # a few SIPs after the robot is at rest
    truth, pose = emulator.pose(), pioneer.odometry()
    assert truth[0] > 0.4  # it did drive
    assert pose.x == pytest.approx(truth[0], abs=0.003) and pose.y == pytest.approx(truth[1], abs=0.003)
    assert pose.theta == pytest.approx(truth[2], abs=0.004)
    assert {e.arg for e in emulator.named("VEL")} >= {500, 0, 200}
    assert {e.arg for e in emulator.named("RVEL")} >= {60, -30, 0}
    assert emulator.bad_packets == 0


def test_velocity_reports_and_clamping(base):
    pioneer, emulator = base(settings={"max_speed": 0.4, "max_turn_rate": 50})
    pioneer.drive(1.0, math.radians(90))
    assert emulator.wait_for(lambda: (emulator.v, emulator.w) == (400.0, 50.0))
    assert pioneer.clamped_commands == 1
    assert emulator.wait_for(lambda: pioneer.status().v == pytest.approx(0.4, abs=0.002))
    assert pioneer.status().w == pytest.approx(math.radians(50), abs=0.01)
    with pytest.raises(ValueError):
        pioneer.drive(math.nan, 0.0)


def test_commands_are_resent_well_inside_the_watchdog(base):
    pioneer, emulator = base(watchdog=0.2)
    pioneer.drive(0.1, 0.0)
    time.sleep(0.4)  # twice the (shortened) robot watchdog
    assert not emulator.named("watchdog") and emulator.v == 100.0
    times = [e.t for e in emulator.named("VEL")]
    gaps = [b - a for a, b in zip(times, times[1:], strict=False)]
    assert max(gaps) < 4 * FAST_BASE["resend_period"]  # well inside the 0.5 s the robot needs


def test_the_emulator_watchdog_stops_a_silent_client(arcos):
    """The emulated robot honours its watchdog: a client that goes quiet is stopped (the last resort
    when the link dies and the driver's stop cannot get through)."""
    emulator = arcos(watchdog=0.25)
    port = serial.serial_for_url(emulator.port, timeout=0.05)
    try:
        for step in (0, 1, 2):
            port.write(protocol.encode_command(step))
            time.sleep(0.02)
        port.write(protocol.encode_command(protocol.Command.OPEN) + protocol.encode_command(protocol.Command.ENABLE, 1)
                   + protocol.encode_vel(300))
        assert emulator.wait_for(lambda: emulator.v == 300.0)
        quiet = time.monotonic()
        assert emulator.wait_for(lambda: emulator.named("watchdog"), timeout=1.0)
        assert emulator.named("watchdog")[0].t - quiet == pytest.approx(0.25, abs=0.08)
        assert not emulator.moving
    finally:
        port.close()


# -- the connection sequence ---------------------------------------------------------------------------
def test_out_of_sequence_echo_restarts_at_sync0(base):
    pioneer, emulator = base(sync_glitch=2)
    assert pioneer.identity.subclass == "p3dx" and emulator.sync_glitch == 0


def test_a_robot_left_open_is_closed_then_synced(base):
    pioneer, emulator = base(start_open=True)
    assert pioneer.identity is not None and pioneer.fault is None
    assert emulator.state == "open"


def test_slow_replies_within_the_timeout(base):
    pioneer, emulator = base(reply_delay=0.06)
    assert pioneer.identity is not None and pioneer.config is not None


def test_no_reply_is_a_timeout_error(arcos):
    emulator = arcos(reply_delay=5.0)
    start = time.monotonic()
    with pytest.raises(TimeoutError, match="no ARCOS reply") as info:
        open_base(port=emulator.port, **{**FAST_BASE, "connect_timeout": 0.25})
    assert isinstance(info.value, OSError) and time.monotonic() - start < 0.8


def test_model_auto_and_mismatch(base):
    pioneer, _ = base(settings={"model": "auto"}, model="p3at-sh")
    assert pioneer.params.name == "p3at-sh" and pioneer.model_warning is None
    other, _ = base(settings={"model": "p3dx"}, model="p3at")
    assert other.params.name == "p3dx" and "p3at" in other.model_warning


def test_unknown_subclass_needs_a_model(arcos):
    emulator = arcos(identity=Identity("x", "Pioneer", "amigo"))
    with pytest.raises(ConnectionError, match="amigo"):
        open_base(port=emulator.port, model="auto", **FAST_BASE)


def test_open_errors_are_oserrors_with_the_port(tmp_path, arcos):
    missing = str(tmp_path / "ttyUSB9")
    with pytest.raises(ConnectionError, match="ttyUSB9"):
        open_base(port=missing, model="p3dx")
    emulator = arcos(transport="tcp")
    emulator.accept_connections = False
    emulator._listener.close()  # nothing listens on that port any more
    with pytest.raises(OSError, match="127.0.0.1"):
        open_base(port=emulator.port, model="p3dx", **FAST_BASE)


def test_invalid_settings_are_input_errors():
    with pytest.raises(InputError) as info:
        open_base(port="/dev/null", model="p3xx", sip_timeout=30, wheels=4)
    text = str(info.value)
    assert "model" in text and "sip_timeout" in text and "wheels: unknown setting" in text
    settings = PioneerSettings(port="socket://localhost:8101")
    assert settings.model == "auto" and settings.resend_period <= 0.5
    schema = PioneerSettings.model_json_schema()["properties"]
    assert all(p.get("description") for p in schema.values())
    assert schema["sip_timeout"]["unit"] == "s"


# -- sensors -------------------------------------------------------------------------------------------
def test_stall_bumpers_battery_sonar(base):
    pioneer, emulator = base()
    emulator.stall_left = True
    emulator.front_bumpers = 0b101
    emulator.battery = 11.7
    emulator.sonar_ranges[3] = 420
    emulator._sonar_dirty.add(3)
    assert emulator.wait_for(lambda: pioneer.stalled() and pioneer.sonar()[3] == pytest.approx(0.42))
    status = pioneer.status()
    assert status.left_stall and not status.right_stall and status.front_bumpers == 0b101
    assert pioneer.battery() == pytest.approx(11.7)
    emulator.stall_left, emulator.estop = False, True
    assert emulator.wait_for(lambda: pioneer.status().estop and not pioneer.stalled())


def test_odometry_crosses_the_position_wrap(base):
    start = (0x7FF0 * 0.485) / 1000.0  # a few mm before the 15-bit counter wraps
    pioneer, emulator = base(start_pose=(start, 0.0, 0.0), time_scale=4.0)
    pioneer.drive(0.5, 0.0)
    time.sleep(0.15)
    pioneer.stop()
    assert emulator.wait_for(lambda: not emulator.moving)
    time.sleep(0.06)
    assert emulator.pose()[0] > 0.1
    assert pioneer.odometry().x == pytest.approx(emulator.pose()[0], abs=0.003)


def test_calls_never_block(base):
    pioneer, emulator = base(settings={"sip_timeout": 1.0})
    emulator.mute = True  # no SIPs: the driver has nothing new, but must not wait for it
    durations = []
    for _ in range(50):
        start = time.perf_counter()
        pioneer.drive(0.1, 0.1)
        pioneer.odometry()
        pioneer.stalled()
        durations.append(time.perf_counter() - start)
    assert sorted(durations)[25] < 0.001 and max(durations) < 0.05  # no wait for I/O, even at worst


# -- faults --------------------------------------------------------------------------------------------
def test_noisy_link_garbage_corrupt_and_torn_packets(base):
    pioneer, emulator = base(time_scale=2.0)
    emulator.tear = True
    pioneer.drive(0.3, 0.0)
    for _ in range(5):  # one SIP in three corrupted, noise between them, every packet torn in two
        emulator.garbage(40)
        emulator.corrupt(1)
        time.sleep(0.06)
    emulator.tear = False
    pioneer.stop()
    assert emulator.wait_for(lambda: not emulator.moving)
    time.sleep(0.08)
    stats = pioneer.reader_stats
    assert stats.bad_checksums >= 5 and stats.skipped_bytes > 100
    assert pioneer.fault is None
    assert pioneer.odometry().x == pytest.approx(emulator.pose()[0], abs=0.003)


def test_no_sip_is_a_fault_and_the_stop_arrives_in_time(base):
    pioneer, emulator = base()
    pioneer.drive(0.3, 0.2)
    assert emulator.wait_for(lambda: emulator.moving)
    emulator.mute = True
    muted = time.monotonic()
    assert emulator.wait_for(lambda: pioneer.fault is not None, timeout=1.0)
    assert "no SIP" in pioneer.fault
    assert emulator.wait_for(lambda: _zero_velocity_after(emulator, muted) is not None)
    stop = _zero_velocity_after(emulator, muted)
    assert stop is not None and stop.t - muted <= FAST_BASE["sip_timeout"] + STOP_WITHIN
    assert any(e.arg == 0 for e in emulator.named("ENABLE") if e.t >= muted)  # motors disabled
    assert not emulator.moving
    with pytest.raises(DriverFault, match="no SIP"):
        pioneer.drive(0.1, 0.0)
    with pytest.raises(DriverFault):
        pioneer.odometry()
    pioneer.stop()  # the safety path never raises


@pytest.mark.parametrize("transport", ["pty", "tcp"])
def test_dropped_link_is_reported_and_the_robot_watchdog_stops_it(base, transport):
    pioneer, emulator = base(transport=transport, watchdog=0.3)
    pioneer.drive(0.3, 0.0)
    assert emulator.wait_for(lambda: emulator.moving)
    emulator.drop_link()
    assert emulator.wait_for(lambda: pioneer.fault is not None, timeout=1.0)
    assert time.monotonic() - emulator.link_dropped_at < FAST_BASE["sip_timeout"] + STOP_WITHIN
    assert "lost" in pioneer.fault
    with pytest.raises(DriverFault):
        pioneer.drive(0.3, 0.0)
    # the driver's stop cannot cross a dead link: the robot's own watchdog stops it
    assert emulator.wait_for(lambda: not emulator.moving, timeout=1.0)
    assert emulator.named("watchdog")[0].t - emulator.link_dropped_at == pytest.approx(0.3, abs=0.08)


def test_reconnects_when_allowed_and_keeps_odometry_continuous(base):
    pioneer, emulator = base(transport="tcp", time_scale=3.0, settings={"reconnect": True, "reconnect_timeout": 2.0})
    pioneer.drive(0.3, 0.0)
    time.sleep(0.15)
    pioneer.stop()
    assert emulator.wait_for(lambda: not emulator.moving)
    time.sleep(0.06)
    before = pioneer.odometry()
    emulator.drop_link()
    assert emulator.wait_for(lambda: pioneer.reconnects == 1, timeout=2.0)
    assert pioneer.fault is None
    after = pioneer.odometry()
    assert (after.x, after.y) == pytest.approx((before.x, before.y), abs=0.002)
    pioneer.drive(0.3, 0.0)
    assert emulator.wait_for(lambda: emulator.v == 300.0)
    time.sleep(0.1)
    pioneer.stop()
    assert emulator.wait_for(lambda: not emulator.moving)
    time.sleep(0.06)
    assert pioneer.odometry().x == pytest.approx(emulator.pose()[0], abs=0.004)  # across both sessions


def test_reconnection_gives_up_after_its_timeout(base):
    pioneer, emulator = base(transport="tcp", settings={"reconnect": True, "reconnect_timeout": 0.5})
    emulator.accept_connections = False
    emulator._listener.close()
    emulator.drop_link()
    assert emulator.wait_for(lambda: pioneer.fault is not None, timeout=2.0)
    assert "reconnecting failed" in pioneer.fault
    with pytest.raises(DriverFault):
        pioneer.odometry()


def test_stop_all_on_an_exception_stops_at_once(base):
    pioneer, emulator = base()
    robot = Robot(base=pioneer)
    pioneer.drive(0.4, 0.0)
    assert emulator.wait_for(lambda: emulator.moving)
    failed = time.monotonic()
    robot.stop_all()  # what the runner does in its finally, whatever went wrong
    assert emulator.wait_for(lambda: not emulator.moving, timeout=STOP_WITHIN)
    assert _zero_velocity_after(emulator, failed).t - failed < STOP_WITHIN


def test_close_stops_disables_and_closes(base):
    pioneer, emulator = base()
    pioneer.drive(0.4, 0.1)
    assert emulator.wait_for(lambda: emulator.moving)
    closing = time.monotonic()
    pioneer.close()
    assert emulator.wait_for(lambda: emulator.state == "sync0" and not emulator.enabled)
    tail = [e.name for e in emulator.events if e.t >= closing]
    assert "STOP" in tail and tail[-2:] == ["ENABLE", "CLOSE"] and emulator.named("ENABLE")[-1].arg == 0
    assert _zero_velocity_after(emulator, closing).t - closing < STOP_WITHIN
    with pytest.raises(DriverFault, match="closed"):
        pioneer.drive(0.1, 0.0)
    pioneer.close()  # twice is fine


def test_a_stuck_control_loop_stops_the_base(base):
    pioneer, emulator = base(settings={"command_timeout": 0.15})
    pioneer.drive(0.3, 0.0)
    assert emulator.wait_for(lambda: emulator.moving)
    last_drive = time.monotonic()
    assert emulator.wait_for(lambda: not emulator.moving, timeout=1.0)
    assert time.monotonic() - last_drive < 0.15 + STOP_WITHIN
    assert pioneer.deadman_stops == 1 and pioneer.fault is None
    pioneer.drive(0.3, 0.0)  # the next command resumes
    assert emulator.wait_for(lambda: emulator.moving)


def test_a_robot_of_real_drivers(base, ptu, devices):
    pioneer, emulator = base()
    pan_tilt, ptu_emulator = ptu()
    robot = Robot(base=pioneer, ptu=pan_tilt, name="emulated")
    pioneer.drive(0.2, 0.0)
    pan_tilt.move(0.2, 0.0, 1.0)
    assert emulator.wait_for(lambda: emulator.moving)
    robot.close()
    assert emulator.wait_for(lambda: not emulator.moving and not emulator.enabled)
    assert ptu_emulator.named("H")
    assert pioneer.fault and pan_tilt.fault
