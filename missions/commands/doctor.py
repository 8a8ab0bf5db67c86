"""``bearings doctor --robot ROBOT.yaml``: open every device of a robot profile and say what answered.

Nothing moves: the base is opened (connection sequence, first SIP) and read, the pan-tilt unit is
initialised and read back, each camera is watched for ``--seconds`` to measure its frame rate.
Everything is closed again (the base stopped, its motors disabled) before the command ends.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
import time
from typing import Any

from maps.store import InputError
from missions.commands.common import EXIT_FAILURE, EXIT_OK, fail, print_input_error

DESCRIPTION = """Check a robot before a mission: open each device of the profile (base, pan-tilt unit,
cameras), print what it reports (robot name/class/subclass, the model and conversion factors in use
and where they came from, the link speed, battery, bumpers and stall, pan-tilt limits in degrees
and its position, each camera's frame size and rate), and close everything again. Nothing is
commanded to move."""

EPILOG = """example:
  bearings doctor --robot drivers/profiles/p3at-ptu-pinhole.yaml

exit codes: 0 every device answered, 1 a device failed (the reason is printed), 2 invalid profile."""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("doctor", help="open the devices of a robot profile and report on them",
                                   description=DESCRIPTION, epilog=EPILOG,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--robot", required=True, metavar="ROBOT.yaml", help="the robot profile to check")
    parser.add_argument("--seconds", type=float, default=2.0, metavar="S",
                        help="how long to watch the cameras to measure their frame rate (default: %(default)s)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if not 0.05 <= args.seconds <= 60:
        return fail("doctor", f"--seconds must be between 0.05 and 60, got {args.seconds:g}")
    from missions.profiles import load_profile

    try:
        name, devices = load_profile(args.robot)
    except InputError as exc:
        return print_input_error(exc)
    problems: list[str] = []
    opened = _open_each(devices, problems)  # a device that does not open costs its own line, not the others'
    base, ptu = opened.get("base"), opened.get("ptu")
    cameras = {key.removeprefix("camera:"): handle for key, handle in opened.items() if key.startswith("camera:")}
    try:
        print(f"robot {name} ({args.robot})")
        camera_lines = _watch_cameras(cameras, args.seconds, problems)
        if base is not None:
            _check(problems, "base", lambda: _report_base(base))
        if ptu is not None:
            _check(problems, "ptu", lambda: _report_ptu(ptu))
        for line in camera_lines:
            print(line)
    finally:
        _close(base, ptu, cameras)
    if problems:
        for problem in problems:
            print(f"bearings doctor: {problem}", file=sys.stderr)
        return EXIT_FAILURE
    print("OK: every device answered")
    return EXIT_OK


def _open_each(devices: list[Any], problems: list[str]) -> dict[str, Any]:
    """Open every device of the profile on its own: ``{"base": ..., "ptu": ..., "camera:front": ...}``."""
    opened: dict[str, Any] = {}
    for device in devices:
        try:
            handle = device.opener(device.settings, clock=None)
        except Exception as exc:  # noqa: BLE001 - a device that cannot be opened is reported, the others checked
            what = device.role if device.role != "camera" else f"camera {device.name}"
            problems.append(f"{what}: cannot open the device: {exc}")
            continue
        opened[device.role if device.role != "camera" else f"camera:{device.name}"] = handle
    return opened


def _close(base: Any, ptu: Any, cameras: dict[str, Any]) -> None:
    """Stop, then release what was opened (cameras, pan-tilt, base last), as a run ends."""
    for device in (base, ptu):
        stop = getattr(device, "halt" if device is ptu else "stop", None)
        if callable(stop):
            with contextlib.suppress(Exception):
                stop()
    for device in (*cameras.values(), ptu, base):
        if device is not None:
            with contextlib.suppress(Exception):  # keep closing the others
                device.close()


def _check(problems: list[str], what: str, report: Any) -> None:
    try:
        for warning in report():
            print(f"  warning: {warning}")
    except Exception as exc:  # noqa: BLE001 - any failure of a device is reported, not a traceback
        problems.append(f"{what}: {exc}")


def _report_base(base: Any) -> list[str]:
    print(f"base: {_describe(base)}")
    identity = getattr(base, "identity", None)
    warnings: list[str] = []
    if identity is not None:
        print(f"  identity: name {identity.name!r}, class {identity.robot_class!r}, subclass {identity.subclass!r}")
    model = getattr(base, "model", None)
    if model is not None:
        params = model.params
        print(f"  model: {params.name}, from {model.origin}; {params.dist_conv:g} mm per position unit, "
              f"{params.angle_conv:g} rad per heading unit, velocity x{params.vel_conv:g}, "
              f"sonar x{params.range_conv:g}, DiffConvFactor {params.diff_conv:g}")
        if model.warning:
            warnings.append(model.warning)
    pose = base.odometry()
    print(f"  odometry: x {pose.x:.3f} m, y {pose.y:.3f} m, heading {math.degrees(pose.theta):.1f} deg")
    status = getattr(base, "status", None)
    if status is not None:
        warnings += _report_status(status(), getattr(base, "config", None))
    stats = getattr(base, "reader_stats", None)
    if stats is not None:
        print(f"  link: {stats.packets} packets, {stats.bad_checksums} bad checksums, "
              f"{stats.skipped_bytes} bytes skipped")
    if getattr(base, "fault", None):
        raise OSError(base.fault)
    return warnings


def _report_status(status: Any, config: Any) -> list[str]:
    warnings = []
    low = config.get("low_battery") if config is not None else None
    battery = f"battery {status.battery:.1f} V"
    if low:
        battery += f" (low at {low / 10:.1f} V)"
        if status.battery * 10 <= low:
            warnings.append(f"battery low: {status.battery:.1f} V")
    motors = "motors enabled" if status.motors_enabled else "motors DISABLED"
    print(f"  {battery}; {motors}; e-stop {'PRESSED' if status.estop else 'released'}")
    if status.estop or not status.motors_enabled:
        warnings.append("the motors are off (e-stop pressed, or the motor switch is off): the base will not move")
    stall = [side for side, on in (("left", status.left_stall), ("right", status.right_stall)) if on]
    print(f"  stall: {', '.join(stall) or 'none'}; bumpers front {status.front_bumpers:#04x} "
          f"rear {status.rear_bumpers:#04x}")
    if status.sonar:
        index, nearest = min(status.sonar, key=lambda item: item[1])
        print(f"  sonar: {len(status.sonar)} readings, nearest {nearest:.2f} m (#{index})")
    if config is not None:
        print(f"  config: serial {config.get('serial', '?')!r}, firmware watchdog {config.get('watchdog', '?')} ms, "
              f"max {config.get('trans_vel_max', '?')} mm/s and {config.get('rot_vel_max', '?')} deg/s")
    return warnings


def _report_ptu(ptu: Any) -> list[str]:
    version = getattr(ptu, "version", "")
    print(f"ptu: {_describe(ptu)}" + (f" ({version})" if version else ""))
    state = ptu.state()
    limits = getattr(ptu, "limits", None)
    degrees = ptu.limit_degrees() if hasattr(ptu, "limit_degrees") else {}
    for axis, angle in (("pan", state.pan), ("tilt", state.tilt)):
        line = f"  {axis}: now {math.degrees(angle):.2f} deg"
        if axis in degrees:
            low, high = degrees[axis]
            resolution = getattr(limits, axis).resolution / 3600.0
            line += f", limits {low:.2f} .. {high:.2f} deg, {resolution:.4f} deg per position"
        print(line)
    if getattr(ptu, "fault", None):
        raise OSError(ptu.fault)
    return []


def _watch_cameras(cameras: dict[str, Any], seconds: float, problems: list[str]) -> list[str]:
    """Grab from every camera for ``seconds``; one report line per camera (printed after the base)."""
    counts = dict.fromkeys(cameras, 0)
    last: dict[str, Any] = {}
    end = time.monotonic() + seconds
    while cameras and time.monotonic() < end:
        for name, camera in cameras.items():
            with contextlib.suppress(Exception):  # a failing grab shows up as no frames below
                frame = camera.grab()
                if frame is not None:
                    counts[name] += 1
                    last[name] = frame
        time.sleep(0.005)
    lines = []
    for name, camera in cameras.items():
        frame = last.get(name)
        if frame is None:
            stats = camera.stats() if hasattr(camera, "stats") else None
            reason = getattr(stats, "last_error", None) or getattr(camera, "fault", None) or "no frame"
            problems.append(f"camera {name}: no frame in {seconds:g} s ({reason})")
            continue
        height, width = frame.image.shape[:2]
        kind = getattr(frame.camera, "kind", type(frame.camera).__name__)
        rate = counts[name] / seconds
        line = f"camera {name}: {_describe(camera)}, {width}x{height}, {rate:.1f} frames/s, model {kind}"
        if hasattr(camera, "stats"):
            line += f", {camera.stats().failures} dropped"
        lines.append(line)
    return lines


def _describe(device: Any) -> str:
    describe = getattr(device, "describe", None)
    if callable(describe):
        return str(describe())
    settings = getattr(device, "settings", None)
    port = getattr(settings, "port", None)
    return f"{type(device).__name__}" + (f" on {port}" if port else "")
