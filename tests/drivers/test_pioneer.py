"""The Pioneer driver against the ARCOS emulator: over a pty as the robot's firmware, over TCP as
MobileSim (tests/drivers/arcos_emulator.py says how each mode follows its reference).

The stop-timing tests read the emulator's event log: every accepted command is recorded with the
time it arrived, so "the stop arrived within 200 ms of the fault" is measured on the robot's side.
"""

from __future__ import annotations

import math
import threading
import time

import pytest
import serial

from drivers import arcos as protocol
from drivers.arcos import Identity
from drivers.common import DriverFault
from drivers.interfaces import Base, Robot
from drivers.pioneer import PioneerBase, PioneerSettings, open_base
from maps.store import InputError
from missions.profiles import PROFILES, load_profile
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
    assert pioneer.params.name == "p3dx" and pioneer.model.source == "robot" and pioneer.fault is None
    status = pioneer.status()
    assert status.motors_enabled and not status.estop and not pioneer.stalled()
    assert pioneer.battery() == pytest.approx(12.6)
    assert emulator.wait_for(lambda: len(pioneer.sonar()) == 16)  # the P3-DX ring of ARIA's params/p3dx.p
    assert set(pioneer.sonar().values()) == {5.0}
    steps = [e.name for e in emulator.events if e.name in ("OPEN", "CONFIG", "HOSTBAUD", "SONAR", "ENABLE")]
    serial_link = transport == "pty"  # MobileSim's TCP has no speed to switch
    assert steps == ["OPEN", "CONFIG", *(["HOSTBAUD"] if serial_link else []), "SONAR", "ENABLE"]
    assert emulator.named("ENABLE")[0].arg == 1
    assert pioneer.baud == (38400 if serial_link else None) and emulator.bad_packets == 0


def test_pauses_before_open_and_before_close(arcos, monkeypatch):
    """One SIP cycle after the SYNC2 echo before OPEN, and between ENABLE 0 and CLOSE (ARIA 100 ms,
    p2os 200 ms): checked in the order of what the driver does, not on a clock."""
    emulator = arcos()
    log: list[tuple[str, object]] = []
    original_pause = PioneerBase._pause
    monkeypatch.setattr(PioneerBase, "_pause", lambda self, s: (log.append(("pause", s)), original_pause(self, s)))

    def recording_port(*args, **kwargs):
        port = serial.serial_for_url(*args, **kwargs)
        write = port.write

        def logged_write(data: bytes) -> int:
            commands = tuple(protocol.decode_command(p)[0] for p in protocol.PacketReader().feed(data))
            log.append(("write", commands))
            return write(data)

        port.write = logged_write
        return port

    pioneer = PioneerBase(PioneerSettings(port=emulator.port, **FAST_BASE), port_factory=recording_port).connect()
    pioneer.close()
    command = protocol.Command
    sync2 = log.index(("write", (protocol.SYNC2,)))  # (OPEN and CLOSE have the numbers of SYNC1 and SYNC2)
    assert log[sync2 + 1 : sync2 + 3] == [("pause", 0.1), ("write", (command.OPEN,))]
    close = len(log) - 1
    assert log[close] == ("write", (command.CLOSE,))
    assert log[close - 2 : close] == [("write", (command.STOP, command.VEL, command.RVEL, command.ENABLE)),
                                      ("pause", 0.1)]
    assert emulator.wait_for(lambda: emulator.named("session_end"))
    assert [e.name for e in emulator.events][-4:] == ["ENABLE", "CLOSE", "session_end", "speed"]
    assert emulator.baud == 9600  # CLOSE takes the firmware back to its start speed


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


def _silent_client(emulator):
    """A client that syncs, opens, enables, commands 300 mm/s and then says nothing more."""
    port = serial.serial_for_url(emulator.port, timeout=0.05)
    for step in (0, 1, 2):
        port.write(protocol.encode_command(step))
        time.sleep(0.02)
    port.write(protocol.encode_command(protocol.Command.OPEN) + protocol.encode_command(protocol.Command.ENABLE, 1)
               + protocol.encode_vel(300))
    assert emulator.wait_for(lambda: emulator.v == 300.0)
    return port


def test_the_firmware_watchdog_stops_a_silent_client(arcos):
    """The robot's firmware honours its watchdog: a client that goes quiet is stopped (the last resort
    when the link dies and the driver's stop cannot get through)."""
    emulator = arcos(watchdog=0.25)
    port = _silent_client(emulator)
    try:
        assert emulator.wait_for(lambda: emulator.named("watchdog"), timeout=1.0)
        assert not emulator.moving and emulator.state == "open"  # stopped, the session still open
    finally:
        port.close()


def test_mobilesim_only_warns_about_a_silent_client(arcos):
    """MobileSim's watchdog warns and does not stop the robot: over TCP, the driver's own re-sending and
    stops are all there is."""
    emulator = arcos(transport="tcp", watchdog=0.1)
    port = _silent_client(emulator)
    try:
        assert emulator.wait_for(lambda: emulator.named("watchdog_warning"), timeout=1.0)
        assert emulator.moving and not emulator.named("watchdog")
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


def _drive_straight(pioneer, emulator, metres: float) -> tuple[float, float]:
    """Drive forward until the emulator's truth has covered ``metres``; (truth, odometry) at rest."""
    pioneer.drive(0.5, 0.0)
    assert emulator.wait_for(lambda: emulator.pose()[0] >= metres, timeout=5.0)
    pioneer.stop()
    assert emulator.wait_for(lambda: not emulator.moving)
    time.sleep(0.1)  # a few SIPs after the robot is at rest
    return emulator.pose()[0], pioneer.odometry().x


def test_odometry_uses_the_model_the_robot_reports_whatever_the_profile(arcos, devices):
    """The shipped P3-AT profile on a robot that reports p3dx-sh (1 mm units, not the AT's 0.465 mm):
    odometry follows the robot's report, within 1 % of the emulator's truth."""
    _, entries = load_profile(PROFILES / "p3at-ptu-pinhole.yaml")
    settings = entries[0].settings.model_dump()
    emulator = arcos(model="p3dx-sh", time_scale=8.0)
    settings.update(port=emulator.port, **FAST_BASE)
    pioneer = devices(open_base(settings))
    assert pioneer.params.name == "p3dx-sh" and pioneer.model.source == "robot" and pioneer.model_warning is None
    truth, odometry = _drive_straight(pioneer, emulator, 1.0)
    assert odometry == pytest.approx(truth, rel=0.01)
    assert pioneer.report_sections()["base"]["origin"] == "the robot's SYNC2 subclass 'p3dx-sh'"


def test_a_model_override_is_used_and_said(base):
    pioneer, emulator = base(settings={"model_override": "p3at"}, model="p3dx-sh", time_scale=8.0)
    assert pioneer.params.name == "p3at" and pioneer.model.source == "override"
    assert "model_override p3at" in pioneer.model_warning and "'p3dx-sh'" in pioneer.model_warning
    report = pioneer.report_sections()["base"]
    assert (report["model"], report["source"], report["reported_subclass"]) == ("p3at", "override", "p3dx-sh")
    assert report["dist_conv_mm"] == 0.465
    truth, odometry = _drive_straight(pioneer, emulator, 0.5)
    assert odometry == pytest.approx(0.465 * truth, rel=0.01)  # what the override does: it is really used


def test_the_old_model_setting_is_refused():
    with pytest.raises(InputError, match="model: unknown setting"):
        open_base(port="/dev/null", model="p3dx")


def test_unknown_subclass_needs_an_override(arcos):
    emulator = arcos(identity=Identity("x", "Pioneer", "amigo"))
    with pytest.raises(ConnectionError, match="'amigo'.*model_override"):
        open_base(port=emulator.port, **FAST_BASE)
    assert emulator.wait_for(lambda: emulator.named("session_end"))  # told CLOSE, as ARIA does


def test_rotvel_is_the_measured_turn_rate_when_the_robot_sends_it(base):
    """With the P3-DX's DiffConvFactor forced on a P3-AT, the wheel speeds give a turn rate 65 % too high;
    the ROTVEL field of newer firmware gives the robot's own."""
    pioneer, emulator = base(settings={"model_override": "p3dx"}, model="p3at")
    pioneer.drive(0.0, math.radians(40))
    assert emulator.wait_for(lambda: pioneer.status().w == pytest.approx(math.radians(40), abs=1e-6))
    old, old_emulator = base(settings={"model_override": "p3dx"}, model="p3at", new_firmware=False)
    old.drive(0.0, math.radians(40))
    assert old_emulator.wait_for(lambda: old.status().w == pytest.approx(math.radians(40) * 0.0056 / 0.0034,
                                                                        rel=0.02))


def test_open_errors_are_oserrors_with_the_port(tmp_path, arcos):
    missing = str(tmp_path / "ttyUSB9")
    with pytest.raises(ConnectionError, match="ttyUSB9"):
        open_base(port=missing)
    emulator = arcos(transport="tcp")
    emulator.accept_connections = False
    emulator._listener.close()  # nothing listens on that port any more
    with pytest.raises(OSError, match="127.0.0.1"):
        open_base(port=emulator.port, **FAST_BASE)


def test_invalid_settings_are_input_errors():
    with pytest.raises(InputError) as info:
        open_base(port="/dev/null", model_override="p3xx", sip_timeout=30, wheels=4)
    text = str(info.value)
    assert "model_override" in text and "sip_timeout" in text and "wheels: unknown setting" in text
    settings = PioneerSettings(port="socket://localhost:8101")
    assert settings.model_override is None and settings.switch_baud == 38400 and settings.resend_period <= 0.5
    schema = PioneerSettings.model_json_schema()["properties"]
    assert all(p.get("description") for p in schema.values())
    assert schema["sip_timeout"]["unit"] == "s"


# -- the link's speed (over a pty the emulator reads the speed the driver set on its end) -------------
def test_hostbaud_moves_the_link_when_the_robot_allows_it(base):
    pioneer, emulator = base(time_scale=4.0)
    assert pioneer.baud == 38400 and emulator.baud == 38400
    assert [e.arg for e in emulator.named("HOSTBAUD")] == [protocol.BAUD_CODES[38400]]
    garbled = emulator.garbled
    truth, odometry = _drive_straight(pioneer, emulator, 0.3)
    assert odometry == pytest.approx(truth, abs=0.003) and emulator.garbled == garbled  # nothing lost at 38400
    pioneer.close()
    assert emulator.wait_for(lambda: emulator.baud == 9600)  # CLOSE: the firmware is back at its start speed


@pytest.mark.parametrize(("robot", "settings"), [({"hostbaud": False}, {}), ({}, {"switch_baud": 0}),
                                                 ({}, {"switch_baud": 9600})])
def test_the_link_stays_at_its_speed_unless_both_ends_want_another(base, robot, settings):
    pioneer, emulator = base(settings=settings, **robot)
    assert pioneer.baud == 9600 and emulator.baud == 9600 and not emulator.named("HOSTBAUD")


def test_a_robot_that_does_not_switch_is_followed_back(base):
    """The config packet says HOSTBAUD is allowed but the robot stays at 9600: nothing is heard at 38400,
    so after 0.9 s the driver goes back to 9600, as ARIA does, and the link works."""
    pioneer, emulator = base(honour_hostbaud=False)
    assert emulator.named("HOSTBAUD") and emulator.garbled > 0  # 38400 against 9600 was noise both ways
    assert pioneer.baud == 9600 and emulator.baud == 9600
    sips = pioneer.status().sips
    assert emulator.wait_for(lambda: pioneer.status().sips > sips + 3) and pioneer.fault is None


def test_a_robot_left_open_at_another_speed_is_closed_at_every_speed(base):
    """A client switched the robot to 38400 and died: the driver, at 9600, hears only noise, sends CLOSE
    at every speed (ARIA's remedy), and connects once the robot is back at 9600."""
    pioneer, emulator = base(start_open=True, start_baud=38400)
    assert emulator.named("session_end") and pioneer.fault is None and pioneer.identity is not None
    assert pioneer.baud == 38400 and emulator.baud == 38400  # synced at 9600, then moved again


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


def test_calls_never_touch_the_port_nor_wait_for_the_io_thread(arcos):
    """drive(), odometry(), stalled() while the I/O thread is stuck inside a read that does not end:
    they all return, and none of them reads or writes the port from the calling thread."""
    emulator = arcos()
    stuck, release, freeze = threading.Event(), threading.Event(), threading.Event()
    touched: list[str] = []
    callers: set[threading.Thread] = set()  # the threads that make the calls under test

    def watched_port(*args, **kwargs):
        port = serial.serial_for_url(*args, **kwargs)
        read, write = port.read, port.write

        def watched_read(size: int = 1) -> bytes:
            if threading.current_thread() in callers:
                touched.append("read")
            elif freeze.is_set():
                stuck.set()
                release.wait(10.0)
            return read(size)

        def watched_write(data: bytes) -> int:
            if threading.current_thread() in callers:
                touched.append("write")
            return write(data)

        port.read, port.write = watched_read, watched_write
        return port

    pioneer = PioneerBase(PioneerSettings(port=emulator.port, **{**FAST_BASE, "sip_timeout": 5.0}),
                          port_factory=watched_port).connect()
    try:
        freeze.set()
        assert stuck.wait(5.0)  # the I/O thread is now inside a read that will not return
        calls = threading.Thread(target=lambda: [(pioneer.drive(0.1, 0.1), pioneer.odometry(), pioneer.stalled())
                                                 for _ in range(50)], daemon=True)
        callers.add(calls)
        calls.start()
        calls.join(10.0)  # only a hang detector: a call that waited for the I/O thread would never return
        assert not calls.is_alive() and touched == [] and not release.is_set()
    finally:
        release.set()
        pioneer.close()


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


@pytest.mark.parametrize(("transport", "mode"), [("pty", "firmware"), ("tcp", "firmware"), ("tcp", "mobilesim")])
def test_dropped_link_is_reported_and_the_robot_is_stopped(base, transport, mode):
    """The driver's stop cannot cross a dead link: the firmware (also behind a serial server) stops
    by its watchdog; MobileSim ends the session of a client that went away, which stops the robot."""
    pioneer, emulator = base(transport=transport, mode=mode, watchdog=0.3)
    pioneer.drive(0.3, 0.0)
    assert emulator.wait_for(lambda: emulator.moving)
    emulator.drop_link()
    assert emulator.wait_for(lambda: pioneer.fault is not None, timeout=1.0)
    assert time.monotonic() - emulator.link_dropped_at < FAST_BASE["sip_timeout"] + STOP_WITHIN
    assert "lost" in pioneer.fault
    with pytest.raises(DriverFault):
        pioneer.drive(0.3, 0.0)
    assert emulator.wait_for(lambda: not emulator.moving, timeout=1.0)
    if mode == "mobilesim":
        assert emulator.named("session_end") and not emulator.named("watchdog")
    else:
        assert emulator.named("watchdog")


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
    tail = [e.name for e in emulator.events if e.t >= closing and e.name not in ("session_end", "speed")]
    assert "STOP" in tail and tail[-2:] == ["ENABLE", "CLOSE"] and emulator.named("ENABLE")[-1].arg == 0
    assert _zero_velocity_after(emulator, closing).t - closing < STOP_WITHIN
    with pytest.raises(DriverFault, match="closed"):
        pioneer.drive(0.1, 0.0)
    pioneer.close()  # twice is fine


def test_mobilesim_ends_the_session_and_the_connection_on_close(base, devices):
    pioneer, emulator = base(transport="tcp", time_scale=4.0)
    assert emulator.mode == "mobilesim" and pioneer.identity.name == "MobileSim" and pioneer.baud is None
    _drive_straight(pioneer, emulator, 0.2)
    pioneer.close()
    assert emulator.wait_for(lambda: emulator.sessions_ended == 1 and not emulator.connected)
    assert emulator.named("session_end")[0].arg == b"CLOSE" and not emulator.enabled and not emulator.moving
    again = devices(open_base(port=emulator.port, **FAST_BASE))  # MobileSim listens again: a new session
    assert again.fault is None and emulator.connected


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
