"""Robot profiles: validated like missions; drivers not in this version are a clear input error."""

from __future__ import annotations

import sys

import pytest

from maps.store import InputError
from missions.cli import main
from missions.profiles import PROFILES, load_profile


def test_shipped_profile_names_drivers_this_version_lacks(capsys):
    path = PROFILES / "pioneer-ptu.yaml"
    with pytest.raises(InputError) as info:
        load_profile(path)
    messages = [(d.line, d.message) for d in info.value.diagnostics]
    assert (5, "base: the 'pioneer' driver is not part of this version of bearings yet; run in the simulator "
               "with --sim") in messages
    assert len(messages) == 3  # base, ptu and camera
    assert main(["run", "square", "--robot", str(path), "--quiet"]) == 2
    assert "Traceback" not in capsys.readouterr().err


def test_profile_shape_errors(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_text("robot: x\nbase: {driver: roomba}\ncameras: [a]\nwheels: 4\n")
    with pytest.raises(InputError) as info:
        load_profile(path)
    messages = sorted((d.line, d.message) for d in info.value.diagnostics)
    assert messages == [
        (3, "cameras: input should be a valid dictionary, got a list of 1"),
        (4, "unknown key 'wheels' (allowed: base, cameras, description, ptu, robot)"),
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

    def open_toy(settings: ToySettings):
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
