"""Robot profiles: validated like missions; drivers not in this version are a clear input error."""

from __future__ import annotations

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
        (2, "base: unknown base driver 'roomba' (known: pioneer)"),
        (3, "'cameras:' maps camera names to driver settings"),
        (4, "unknown profile entry 'wheels' (entries: robot, description, base, ptu, cameras)"),
    ]
