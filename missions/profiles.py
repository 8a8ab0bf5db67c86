"""Robot profiles: which drivers a real robot uses, with which settings (``--robot ROBOT.yaml``).

A profile names a driver for the base, optionally the pan-tilt unit and cameras::

    robot: lab-pioneer
    base: {driver: pioneer, port: /dev/ttyUSB0}
    ptu: {driver: ptu_d46, port: /dev/ttyUSB1}
    cameras:
      omni: {driver: opencv, device: 0, calibration: omni.yaml}
    safety: {stop_margin: 0.15}   # the collision monitor (optional; docs/hardware.md)

The profile's shape is the declared model :class:`RobotProfile`; each device's settings are the
declared model of its driver: the type of the ``settings`` argument of the driver's opener
(``open_base(settings: PioneerSettings)``), so a driver declares its settings (units, ranges)
once, where it is written. Both are checked with located errors (:mod:`maps.located`), like
missions and worlds. Nothing is opened until the whole profile is valid, and a device that fails
to open closes the ones already open. A base that offers ``range_source()`` (the Pioneer: its
sonar ring and bumpers) becomes the robot's :class:`~drivers.interfaces.RangeSource`, and
:func:`robot_safety` builds the collision monitor's configuration from the ``safety:`` section over
the footprint of the model the base reports (``body()``).
"""

from __future__ import annotations

import contextlib
import importlib
import types
import typing
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, create_model

from behaviours.ports import Ref
from drivers.interfaces import Robot
from drivers.pioneer_body import BODIES
from drivers.safety.settings import SafetySettings, monitor_config
from maps.located import FILE_MODEL_CONFIG, diagnose, suggest, validate
from maps.store import Diagnostic, InputError, YamlMap, load_yaml
from missions.language import MissionSpec
from perception.collision_monitor import MonitorConfig

PROFILES = Path(__file__).resolve().parent.parent / "drivers" / "profiles"
Role = Literal["base", "ptu", "camera"]
DRIVERS: dict[str, dict[str, str]] = {
    # role -> driver name -> "module:opener"; the opener's `settings` parameter declares the settings
    "base": {"pioneer": "drivers.pioneer:open_base"},
    "ptu": {"ptu_d46": "drivers.ptu_d46:open_ptu"},
    "camera": {"opencv": "drivers.cameras:open_opencv_camera", "http": "drivers.cameras:open_http_camera"},
}


class DeviceEntry(BaseModel):
    """One device: its driver's name, then that driver's own settings."""

    model_config = ConfigDict(extra="allow", strict=True, frozen=True)

    driver: str = Field(min_length=1, description="the driver (its settings follow)")


class RobotProfile(BaseModel):
    """A robot profile file."""

    model_config = FILE_MODEL_CONFIG

    robot: str | None = Field(None, min_length=1, max_length=200, description="the robot's name (default: the file "
                              "name)")
    description: str = Field("", max_length=20_000)
    base: DeviceEntry = Field(description="the differential-drive base")
    ptu: DeviceEntry | None = Field(None, description="the pan-tilt unit, if any")
    cameras: dict[str, DeviceEntry] = Field(default_factory=dict, max_length=32, description="cameras by name")
    safety: SafetySettings | None = Field(None, description="the collision monitor: footprint, zones, limits "
                                          "(default: the footprint of the model the base reports)")


@dataclass(frozen=True)
class Device:
    """A validated device of a profile: ready to open."""

    role: Role
    name: str
    driver: str
    settings: BaseModel
    opener: Callable[..., Any]


def load_profile(path: str | Path) -> tuple[str, list[Device]]:
    """Validate a profile and its devices' settings; raise :class:`InputError` with every problem."""
    file = str(path)
    doc = load_yaml(path)
    if not isinstance(doc, YamlMap):
        raise InputError([Diagnostic(file, 1, 1, "a robot profile is a mapping with at least 'base:'")])
    profile = validate(RobotProfile, doc, file=file)
    entries: list[tuple[Role, str, DeviceEntry, YamlMap]] = [("base", "base", profile.base, doc["base"])]
    if profile.ptu is not None:
        entries.append(("ptu", "ptu", profile.ptu, doc["ptu"]))
    entries += [("camera", name, entry, doc["cameras"][name]) for name, entry in profile.cameras.items()]
    devices: list[Device] = []
    problems: list[Diagnostic] = []
    for role, name, entry, raw in entries:
        try:
            devices.append(_device(role, name, entry, raw, file))
        except InputError as exc:
            problems += exc.diagnostics
    if problems:
        raise InputError(problems)
    return profile.robot or Path(file).stem, devices


def _device(role: Role, name: str, entry: DeviceEntry, raw: YamlMap, file: str) -> Device:
    mark = raw.value_mark_of("driver")
    known = DRIVERS[role]
    target = known.get(entry.driver)
    if target is None:
        raise InputError([Diagnostic(file, mark.line, mark.col, f"{name}: unknown {role} driver {entry.driver!r}"
                                     f"{suggest(entry.driver, known)} (known: {', '.join(known)})")])
    opener, settings_model = _opener(target)
    if opener is None or settings_model is None:
        raise InputError([Diagnostic(file, mark.line, mark.col, f"{name}: the {entry.driver!r} driver is not part "
                                     "of this version of bearings yet; run in the simulator with --sim")])
    settings = {k: v for k, v in raw.items() if k != "driver"}
    if role == "camera":
        settings.setdefault("name", name)  # frames carry the camera's name in the profile
    calibration = settings.get("calibration")
    if isinstance(calibration, str) and calibration and not Path(calibration).is_absolute():
        settings["calibration"] = str(Path(file).parent / calibration)  # relative to the profile, not the cwd
    located = YamlMap(settings)
    located.mark, located.key_marks, located.value_marks = raw.mark, raw.key_marks, raw.value_marks
    try:
        value = settings_model.model_validate(located, context={"folder": str(Path(file).parent)})
    except ValidationError as exc:
        path = ("cameras", name) if role == "camera" else (role,)
        raise InputError(diagnose(exc, located, file=file, model=settings_model, path=path)) from None
    return Device(role, name, entry.driver, value, opener)


def _opener(target: str) -> tuple[Callable[..., Any] | None, type[BaseModel] | None]:
    """A driver's opener and its declared settings model, or (None, None) when the driver is absent."""
    module_name, _, function = target.partition(":")
    try:
        opener = getattr(importlib.import_module(module_name), function)
    except (ModuleNotFoundError, AttributeError):
        return None, None
    hints = typing.get_type_hints(opener)
    declared = hints.get("settings")
    candidates = typing.get_args(declared) if typing.get_origin(declared) in (typing.Union, types.UnionType) else (
        declared,)
    models = [c for c in candidates if isinstance(c, type) and issubclass(c, BaseModel)]
    return opener, models[0] if models else None


PTU_KEYS = ("/ptu/state", "/ptu/command")  # a mission that reads or writes these drives a pan-tilt unit


def mission_problems(mission: MissionSpec, path: str | Path) -> list[Diagnostic]:
    """What ``mission`` needs that the robot of profile ``path`` lacks, without opening anything: a
    camera it grabs (its ``cameras:``), the pan-tilt unit it reads or commands. The profile itself
    must be valid (:class:`InputError` otherwise)."""
    name, devices = load_profile(path)
    cameras = [d.name for d in devices if d.role == "camera"]
    problems = []
    missing = [c for c in mission.cameras or () if c not in cameras]
    if missing:
        problems.append(Diagnostic(mission.file, 0, 0, f"the mission uses camera(s) {', '.join(missing)}, which "
                                   f"robot {name!r} ({path}) does not have (it has: {', '.join(cameras) or 'none'})"))
    nodes = [node for root in (*mission.sense, mission.tree) for node in root.walk()]
    uses_ptu = any(isinstance(v, Ref) and v.base in PTU_KEYS for n in nodes for v in n.inputs.values()) or any(
        key in PTU_KEYS for n in nodes for key in n.outputs.values())
    if uses_ptu and not any(d.role == "ptu" for d in devices):
        problems.append(Diagnostic(mission.file, 0, 0, f"the mission reads or drives the pan-tilt unit, which robot "
                                   f"{name!r} ({path}) does not have"))
    return problems


def open_robot(path: str | Path, *, clock: Callable[[], float] | None = None) -> Robot:
    """Open every device of a valid profile; on any failure close what was opened and re-raise.

    ``clock`` stamps the devices' readings: hand it the run's clock so that odometry and frame
    stamps are on the time axis the tree sees.
    """
    name, devices = load_profile(path)
    opened: list[Any] = []
    try:
        base, ptu, cameras = None, None, {}
        for device in devices:
            handle = device.opener(device.settings, clock=clock)
            opened.append(handle)
            if device.role == "base":
                base = handle
            elif device.role == "ptu":
                ptu = handle
            else:
                cameras[device.name] = handle
        source = getattr(base, "range_source", None)
        ranges = source() if callable(source) else None
        return Robot(base=base, ptu=ptu, cameras=cameras, ranges=ranges, name=name)  # type: ignore[arg-type]
    except BaseException:
        for handle in reversed(opened):
            with contextlib.suppress(Exception):  # already failing; close the rest
                handle.close()
        raise


def robot_safety(path: str | Path, robot: Robot) -> MonitorConfig:
    """The collision monitor of a robot opened from the profile at ``path``: its ``safety:`` section
    over the footprint of the model the base reports (``body()``; a P3-DX's for a base that does
    not say). :class:`InputError` located at the section when a zone leaves the footprint out."""
    file = str(path)
    doc = load_yaml(path)
    profile = validate(RobotProfile, doc, file=file)
    body = getattr(robot.base, "body", None)
    footprint = body().footprint if callable(body) else BODIES["p3dx"].footprint
    try:
        return monitor_config(profile.safety, footprint)
    except ValueError as exc:
        mark = doc.value_mark_of("safety") if isinstance(doc, YamlMap) and "safety" in doc else None
        line, col = (mark.line, mark.col) if mark is not None else (0, 0)
        raise InputError([Diagnostic(file, line, col, str(exc))]) from None


def profile_schema() -> dict[str, Any]:
    """JSON Schema of profiles: each role's entry is one of the installed drivers' settings models."""
    roles: dict[str, Any] = {}
    for role, drivers in DRIVERS.items():
        variants = []
        for driver, target in drivers.items():
            _, settings_model = _opener(target)
            if settings_model is not None:
                tag: Any = Literal[driver]
                variants.append(create_model(f"{settings_model.__name__}Entry", __base__=settings_model,
                                             driver=(tag, Field(description="the driver"))))
        roles[role] = typing.Union[tuple(variants)] if variants else DeviceEntry  # noqa: UP007 - built at run time
    base, ptu, camera = roles["base"], roles["ptu"], roles["camera"]
    model = create_model("RobotProfileSchema", __base__=RobotProfile, base=(base, ...), ptu=(ptu | None, None),
                         cameras=(dict[str, camera], {}))  # type: ignore[valid-type]
    schema = model.model_json_schema()
    schema["title"] = "bearings robot profile"
    return schema
