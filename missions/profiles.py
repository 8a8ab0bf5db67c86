"""Robot profiles: which drivers a real robot uses, on which ports (``--robot ROBOT.yaml``).

A profile names a driver for the base, optionally the pan-tilt unit and cameras::

    robot: lab-pioneer
    base: {driver: pioneer, port: /dev/ttyUSB0, model: p3dx}
    ptu: {driver: ptu_d46, port: /dev/ttyUSB1}
    cameras:
      omni: {driver: opencv, device: 0, calibration: omni.yaml}

Drivers are looked up in :data:`DRIVERS` (``module:function``); each opener takes the entry's
settings and returns the device. Nothing is opened until the whole profile is valid, and a
device that fails to open closes the ones already open.
"""

from __future__ import annotations

import contextlib
import importlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from drivers.interfaces import Robot
from maps.store import Diagnostic, InputError, YamlMap, load_yaml

PROFILES = Path(__file__).resolve().parent.parent / "drivers" / "profiles"
DRIVERS: dict[str, dict[str, str]] = {
    # role -> driver name -> "module:opener"; the hardware drivers register here as they land
    "base": {"pioneer": "drivers.pioneer:open_base"},
    "ptu": {"ptu_d46": "drivers.ptu_d46:open_ptu"},
    "camera": {"opencv": "drivers.cameras:open_opencv_camera"},
}
TOP_KEYS = ("robot", "description", "base", "ptu", "cameras")


@dataclass(frozen=True)
class DeviceEntry:
    role: str
    name: str
    driver: str
    settings: dict[str, Any]
    opener: Callable[..., Any]


def load_profile(path: str | Path) -> tuple[str, list[DeviceEntry]]:
    """Validate a profile and resolve its drivers; raise :class:`InputError` with every problem."""
    file = str(path)
    doc = load_yaml(path)
    problems: list[Diagnostic] = []

    def error(mark: Any, message: str) -> None:
        problems.append(Diagnostic(file, mark.line, mark.col, message))

    if not isinstance(doc, YamlMap):
        raise InputError([Diagnostic(file, 1, 1, "a robot profile is a mapping with at least 'base:'")])
    for key in doc:
        if key not in TOP_KEYS:
            error(doc.mark_of(key), f"unknown profile entry {key!r} (entries: {', '.join(TOP_KEYS)})")
    entries: list[DeviceEntry] = []
    sections: list[tuple[str, str, Any, Any]] = []
    if "base" not in doc:
        error(doc.mark, "the profile has no 'base:' driver")
    else:
        sections.append(("base", "base", doc["base"], doc.value_mark_of("base")))
    if doc.get("ptu") is not None:
        sections.append(("ptu", "ptu", doc["ptu"], doc.value_mark_of("ptu")))
    cameras = doc.get("cameras")
    if cameras is not None:
        if not isinstance(cameras, YamlMap):
            error(doc.value_mark_of("cameras"), "'cameras:' maps camera names to driver settings")
        else:
            sections.extend(("camera", str(n), c, cameras.value_mark_of(n)) for n, c in cameras.items())
    for role, name, entry, mark in sections:
        if not isinstance(entry, YamlMap) or not isinstance(entry.get("driver"), str):
            error(mark, f"{name}: expected a mapping with 'driver:' ({', '.join(DRIVERS[role])})")
            continue
        driver = entry["driver"]
        target = DRIVERS[role].get(driver)
        if target is None:
            error(entry.value_mark_of("driver"), f"{name}: unknown {role} driver {driver!r} "
                  f"(known: {', '.join(DRIVERS[role])})")
            continue
        module_name, _, function = target.partition(":")
        try:
            opener = getattr(importlib.import_module(module_name), function)
        except (ModuleNotFoundError, AttributeError):
            error(entry.value_mark_of("driver"), f"{name}: the {driver!r} driver is not part of this version "
                  "of bearings yet; run in the simulator with --sim")
            continue
        settings = {k: v for k, v in entry.items() if k != "driver"}
        entries.append(DeviceEntry(role, name, driver, settings, opener))
    if problems:
        raise InputError(problems)
    return str(doc.get("robot", Path(file).stem)), entries


def open_robot(path: str | Path) -> Robot:
    """Open every device of a valid profile; on any failure close what was opened and re-raise."""
    name, entries = load_profile(path)
    opened: list[Any] = []
    try:
        base, ptu, cameras = None, None, {}
        for entry in entries:
            device = entry.opener(**entry.settings)
            opened.append(device)
            if entry.role == "base":
                base = device
            elif entry.role == "ptu":
                ptu = device
            else:
                cameras[entry.name] = device
        return Robot(base=base, ptu=ptu, cameras=cameras, name=name)
    except BaseException:
        for device in reversed(opened):
            with contextlib.suppress(Exception):  # already failing; close the rest
                device.close()
        raise
