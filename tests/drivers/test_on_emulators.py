"""End to end through the profile loader: ``bearings doctor`` and ``bearings run --robot`` against the
emulated Pioneer (TCP as MobileSim, pty as the robot's firmware), PTU-D46 (pty) and a video-file camera."""

from __future__ import annotations

import json
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from drivers import arcos
from maps.store import load_yaml
from missions.cli import main
from missions.profiles import PROFILES
from tests.drivers.conftest import FAST_BASE, FAST_PTU

BASE_TIMING = ", ".join(f"{k}: {v}" for k, v in FAST_BASE.items())
PTU_TIMING = ", ".join(f"{k}: {v}" for k, v in FAST_PTU.items())


def _video(path: Path) -> Path:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 20.0, (80, 60))
    for i in range(6):
        writer.write(np.full((60, 80, 3), 40 * i, np.uint8))
    writer.release()
    return path


def _profile(tmp_path: Path, base_port: str, ptu_port: str | None = None, video: Path | None = None,
             extra: str = "") -> Path:
    lines = ["robot: bench", f'base: {{driver: pioneer, port: "{base_port}", {BASE_TIMING}{extra}}}']
    if ptu_port:
        lines.append(f'ptu: {{driver: ptu_d46, port: "{ptu_port}", {PTU_TIMING}}}')
    if video:
        lines += ["cameras:", f'  front: {{driver: opencv, device: "{video}", fps: 100, loop: true}}']
    path = tmp_path / "robot.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_doctor_reports_every_device(tmp_path, arcos, ptu_emulator, capsys):
    base = arcos(identity=arcos_identity("lab-dx", "p3dx"))
    ptu = ptu_emulator()
    profile = _profile(tmp_path, base.port, ptu.port, _video(tmp_path / "clip.avi"))
    assert main(["doctor", "--robot", str(profile), "--seconds", "0.3"]) == 0
    out = capsys.readouterr().out
    assert "robot bench" in out
    assert "name 'lab-dx', class 'Pioneer', subclass 'p3dx'" in out
    assert "base: pioneer on " in out and " at 38400 bit/s" in out  # the robot allowed HOSTBAUD
    assert "model: p3dx, from the robot's SYNC2 subclass 'p3dx'; 0.485 mm per position unit" in out
    assert "DiffConvFactor 0.0056" in out and "warning" not in out
    assert "battery 12.6 V (low at 11.0 V); motors enabled; e-stop released" in out
    assert "pan: now 0.00 deg, limits -158.91 .. 158.91 deg, 0.0514 deg per position" in out
    assert "tilt: now 0.00 deg, limits -46.65 .. 31.06 deg" in out
    assert "camera front: opencv" in out and "80x60" in out and "frames/s" in out
    assert out.rstrip().endswith("OK: every device answered")
    assert base.wait_for(lambda: base.named("CLOSE")) and not base.enabled  # left closed and disabled
    assert not [e for e in base.events if e.name in ("VEL", "RVEL") and e.arg]  # nothing was moved


def test_doctor_says_when_a_model_override_is_used(tmp_path, arcos, capsys):
    base = arcos(model="p3dx-sh")
    profile = _profile(tmp_path, base.port, extra=", model_override: p3at")
    assert main(["doctor", "--robot", str(profile), "--seconds", "0.1"]) == 0
    out = capsys.readouterr().out
    assert "model: p3at, from model_override in the profile (the robot reports 'p3dx-sh'); 0.465 mm" in out
    assert "warning: model_override p3at is in use but the robot reports 'p3dx-sh'" in out


def test_doctor_fails_with_the_reason(tmp_path, arcos, capsys):
    missing = _profile(tmp_path, str(tmp_path / "ttyUSB5"))
    assert main(["doctor", "--robot", str(missing), "--seconds", "0.1"]) == 1
    err = capsys.readouterr().err
    assert "base: cannot open the device" in err and "ttyUSB5" in err and "Traceback" not in err
    base = arcos()
    bad = _profile(tmp_path, base.port, extra=", wheels: 4")
    assert main(["doctor", "--robot", str(bad)]) == 2
    assert "unknown key 'wheels' in base" in capsys.readouterr().err
    base.estop = True
    assert main(["doctor", "--robot", str(_profile(tmp_path, base.port)), "--seconds", "0.1"]) == 0
    assert "warning: the motors are off" in capsys.readouterr().out


def test_doctor_checks_every_device_when_one_does_not_open(tmp_path, ptu_emulator, capsys):
    ptu = ptu_emulator()
    profile = _profile(tmp_path, str(tmp_path / "ttyUSB5"), ptu.port)  # no base there, a pan-tilt unit here
    assert main(["doctor", "--robot", str(profile), "--seconds", "0.1"]) == 1
    captured = capsys.readouterr()
    assert "base: cannot open the device" in captured.err and "ttyUSB5" in captured.err
    assert "ptu: " in captured.out and "pan: now" in captured.out  # the pan-tilt unit was still checked


def test_a_library_mission_runs_on_the_emulated_robot_and_leaves_it_stopped(tmp_path, arcos, ptu_emulator, capsys):
    base = arcos(transport="tcp", sip_period=0.01, time_scale=10.0)  # MobileSim's way in
    ptu = ptu_emulator()
    profile = _profile(tmp_path, base.port, ptu.port)
    report = tmp_path / "report.json"
    start = time.monotonic()
    code = main(["run", "square", "--robot", str(profile), "--set", "side=0.3", "--rate", "100", "--quiet",
                 "--report", str(report)])
    assert code == 0, capsys.readouterr()
    assert time.monotonic() - start < 8.0
    result = json.loads(report.read_text())
    assert result["status"] == "SUCCESS"
    x, y, _ = base.pose()  # the square closes (on the emulator's ground truth)
    assert abs(x) < 0.08 and abs(y) < 0.08
    assert base.wait_for(lambda: base.named("CLOSE"))
    assert not base.moving and not base.enabled
    last_vel = [e.arg for e in base.events if e.name in ("VEL", "RVEL")][-2:]
    assert last_vel == [0, 0] and base.named("ENABLE")[-1].arg == 0
    assert ptu.named("H")  # the pan-tilt unit was halted too
    assert base.bad_packets == 0
    assert base.sessions_ended == 1 and not base.connected  # MobileSim closed the session on CLOSE
    model = result["base"]
    assert (model["model"], model["source"], model["reported_subclass"]) == ("p3dx", "robot", "p3dx")
    assert model["dist_conv_mm"] == 0.485 and model["baud"] is None


ONE_METRE = """mission: one_metre
rate: 50
max_time: 30
cameras: []
tree:
  Sequence:
    name: go
    children:
      - Drive: {distance: 1.0, speed: 0.25}
      - Stop
"""


def test_a_p3at_profile_on_a_robot_that_reports_p3dx_sh_drives_true(tmp_path, arcos, capsys):
    """The case of issue 24: told to drive 1 m with the shipped P3-AT profile on a robot reporting p3dx-sh,
    the robot used to drive 2.14 m while odometry said 0.99 m. Now odometry is the robot's own."""
    base = arcos(model="p3dx-sh", sip_period=0.01, time_scale=4.0)
    shipped = load_yaml(PROFILES / "p3at-ptu-pinhole.yaml")["base"]
    fields = {**{k: v for k, v in shipped.items() if k != "port"}, **FAST_BASE}
    profile = tmp_path / "robot.yaml"
    settings = ", ".join(f"{k}: {v}" for k, v in fields.items())
    profile.write_text(f"base: {{port: {json.dumps(base.port)}, {settings}}}\n")
    mission = tmp_path / "one_metre.yaml"
    mission.write_text(ONE_METRE)
    report = tmp_path / "report.json"
    code = main(["run", str(mission), "--robot", str(profile), "--quiet", "--report", str(report)])
    assert code == 0, capsys.readouterr()
    result = json.loads(report.read_text())
    truth = base.pose()[0]
    assert result["odometry"]["x"] == pytest.approx(truth, rel=0.01)
    assert truth == pytest.approx(1.0, abs=0.05)
    assert result["base"]["model"] == "p3dx-sh" and result["base"]["source"] == "robot"


def test_a_lost_link_ends_the_mission_in_failure_with_the_reason(tmp_path, arcos, capsys):
    base = arcos(sip_period=0.01, time_scale=2.0, watchdog=0.3)
    profile = _profile(tmp_path, base.port)
    report = tmp_path / "report.json"
    base_events_before = len(base.events)
    timer = _after(0.4, base.drop_link)
    try:
        code = main(["run", "square", "--robot", str(profile), "--rate", "50", "--quiet", "--report", str(report)])
    finally:
        timer.join()
    assert code == 1
    result = json.loads(report.read_text())
    assert result["status"] == "FAILURE" and "lost" in result["reason"]
    assert "DriverFault" in result["reason"]
    assert len(base.events) > base_events_before
    assert base.wait_for(lambda: not base.moving, timeout=3.0)  # the robot's watchdog, as on hardware


def test_shipped_profiles_are_valid_for_the_drivers():
    from drivers.cameras import HttpCameraSettings, OpenCVCameraSettings
    from drivers.pioneer import PioneerSettings
    from drivers.ptu_d46 import PtuD46Settings

    models = {"pioneer": PioneerSettings, "ptu_d46": PtuD46Settings, "opencv": OpenCVCameraSettings,
              "http": HttpCameraSettings}
    names = sorted(p.name for p in PROFILES.glob("*.yaml"))
    assert {"p3dx-omni.yaml", "p3at-ptu-pinhole.yaml", "pioneer-ptu.yaml"} <= set(names)
    for name in names:
        doc = load_yaml(PROFILES / name)
        entries = [doc["base"], *([doc["ptu"]] if doc.get("ptu") else []), *(doc.get("cameras") or {}).values()]
        for entry in entries:
            fields = {k: v for k, v in entry.items() if k != "driver"}
            models[entry["driver"]].model_validate(fields)


def test_every_setting_is_documented():
    from drivers.cameras import HttpCameraSettings, OpenCVCameraSettings
    from drivers.pioneer import PioneerSettings
    from drivers.ptu_d46 import PtuD46Settings
    from drivers.safety.settings import SafetySettings

    page = (Path(__file__).resolve().parents[2] / "docs" / "hardware.md").read_text()
    for model in (PioneerSettings, PtuD46Settings, OpenCVCameraSettings, HttpCameraSettings, SafetySettings):
        for name in model.model_fields:
            assert f"`{name}`" in page, f"{model.__name__}.{name} is not in docs/hardware.md"


def arcos_identity(name: str, subclass: str) -> arcos.Identity:
    return arcos.Identity(name, "Pioneer", subclass)


def _after(seconds: float, action):
    import threading

    timer = threading.Timer(seconds, action)
    timer.daemon = True
    timer.start()
    return timer


@pytest.fixture(autouse=True)
def _quiet_driver_logs(caplog):
    caplog.set_level("CRITICAL", logger="drivers")
