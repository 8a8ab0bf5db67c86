"""Robot profiles: validated like missions; drivers not in this version are a clear input error."""

from __future__ import annotations

import sys

import pytest

from drivers.fake import FakeBase
from drivers.interfaces import Robot
from maps.store import InputError
from missions.cli import main
from missions.profiles import PROFILES, load_profile, robot_safety


@pytest.mark.parametrize("path", sorted(PROFILES.glob("*.yaml")), ids=lambda p: p.stem)
def test_shipped_profiles_are_valid_and_need_their_hardware(path, capsys):
    name, devices = load_profile(path)
    assert devices[0].role == "base" and devices[0].driver == "pioneer"
    assert all(d.settings.name == d.name for d in devices if d.role == "camera")  # frames carry the profile's name
    assert main(["run", "square", "--robot", str(path), "--quiet"]) == 1  # no robot here: a device fault
    err = capsys.readouterr().err
    assert f"FAILURE (device fault: cannot open the robot of {path}:" in err and "Traceback" not in err


def test_driver_settings_errors_are_located_in_the_profile(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_text("base: {driver: pioneer, port: /dev/ttyUSB0, model_override: p4dx}\n"
                    "cameras:\n  eye: {driver: opencv, device: 0, fps: 1000}\n")
    with pytest.raises(InputError) as info:
        load_profile(path)
    found = [(d.line, d.message) for d in info.value.diagnostics]
    assert any(line == 1 and m.startswith("base.model_override must be one of") for line, m in found), found
    assert any(line == 3 and m.startswith("cameras.eye.fps must be <= 240 Hz") for line, m in found), found


def test_profile_shape_errors(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_text("robot: x\nbase: {driver: roomba}\ncameras: [a]\nwheels: 4\n")
    with pytest.raises(InputError) as info:
        load_profile(path)
    messages = sorted((d.line, d.message) for d in info.value.diagnostics)
    assert messages == [
        (3, "cameras: input should be a valid dictionary, got a list of 1"),
        (4, "unknown key 'wheels' (allowed: base, cameras, description, ptu, robot, safety)"),
    ]
    path.write_text("robot: x\nbase: {driver: pionner}\n")
    with pytest.raises(InputError) as info:
        load_profile(path)
    assert [(d.line, d.message) for d in info.value.diagnostics] == [
        (2, "base: unknown base driver 'pionner'; did you mean 'pioneer'? (known: pioneer)")]


def test_driver_settings_are_checked_against_the_opener_declaration(tmp_path, monkeypatch):
    from pydantic import BaseModel, ConfigDict, Field

    from missions import profiles

    class ToySettings(BaseModel):
        model_config = ConfigDict(extra="forbid", strict=True)
        port: str
        baud: int = Field(9600, ge=1200, le=115200)

    opened = []

    def open_toy(settings: ToySettings, *, clock=None):
        opened.append(settings)
        from drivers.fake import FakeBase

        return FakeBase()

    open_toy.__annotations__ = {"settings": ToySettings}  # resolved, as in a driver module
    module = type(sys)("toy_driver")
    module.ToySettings, module.open_toy = ToySettings, open_toy
    monkeypatch.setitem(sys.modules, "toy_driver", module)
    monkeypatch.setitem(profiles.DRIVERS, "base", {"toy": "toy_driver:open_toy"})
    path = tmp_path / "robot.yaml"
    path.write_text("base:\n  driver: toy\n  port: /dev/null\n  baud: 3\n  stopbits: 2\n")
    with pytest.raises(InputError) as info:
        load_profile(path)
    assert sorted((d.line, d.message) for d in info.value.diagnostics) == [
        (4, "base.baud must be >= 1200, got 3"),
        (5, "unknown key 'stopbits' in base (allowed: baud, port)"),
    ]
    path.write_text("base: {driver: toy, port: /dev/null}\n")
    robot = profiles.open_robot(path)
    assert opened == [ToySettings(port="/dev/null")] and robot.name == "robot"


def test_explore_validates_against_a_robot_with_a_stereo_pair_on_its_pan_tilt_unit(capsys):
    stereo = PROFILES / "p3dx-ptu-stereo.yaml"
    assert main(["validate", "explore", "--robot", str(stereo)]) == 0
    assert "ok (explore" in capsys.readouterr().out
    # the oracle needs the simulator's landmarks camera, which no robot has
    assert main(["validate", "explore", "--robot", str(stereo), "--set", "localisation=landmarks"]) == 2
    assert "uses camera(s) landmarks, which robot 'p3dx-ptu-stereo'" in capsys.readouterr().err
    assert main(["validate", "explore", "--robot", str(PROFILES / "p3dx-omni.yaml")]) == 2
    err = capsys.readouterr().err
    assert "uses camera(s) stereo" in err and "reads or drives the pan-tilt unit" in err


def test_validate_against_an_invalid_profile_reports_the_profile(tmp_path, capsys):
    path = tmp_path / "robot.yaml"
    path.write_text("base: {driver: roomba}\n")
    assert main(["validate", "square", "--robot", str(path)]) == 2
    assert "unknown base driver 'roomba'" in capsys.readouterr().err


def test_the_safety_section_is_checked_with_located_errors(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_text("base: {driver: pioneer, port: /dev/ttyUSB0}\nsafety:\n  stop_margin: -1\n"
                    "  stop_zone: [[1, 1], [2, 1], [2, 2]]\n  crawl_sped: 0.1\n")
    with pytest.raises(InputError) as info:
        load_profile(path)
    found = sorted((d.line, d.col, d.message.split(";")[0]) for d in info.value.diagnostics)
    assert found == [(3, 16, "safety.stop_margin must be >= 0 m, got -1"),
                     (4, 14, "safety.stop_zone: the polygon must contain the robot's centre (0, 0)"),
                     (5, 3, "unknown key 'crawl_sped' in safety")]


def test_the_monitor_of_a_robot_grows_its_footprint_and_refuses_a_zone_that_leaves_it_out(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_text("base: {driver: pioneer, port: /dev/ttyUSB0}\nsafety: {stop_margin: 0.2}\n")
    config = robot_safety(path, Robot(base=FakeBase()))  # a base that does not say its model: a P3-DX's box
    assert config.zones[0].polygon[:, 0].max() == pytest.approx(0.41)
    path.write_text("base: {driver: pioneer, port: /dev/ttyUSB0}\n"
                    "safety:\n  stop_zone: [[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.1, -0.1]]\n")
    with pytest.raises(InputError) as info:
        robot_safety(path, Robot(base=FakeBase()))
    assert [(d.line, d.message) for d in info.value.diagnostics] == [
        (3, "safety: the stop_zone must contain the whole footprint")]
