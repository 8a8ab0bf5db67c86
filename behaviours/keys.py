"""The blackboard keys: namespaces, value types and which part of the tree may write each.

Namespaces follow DESIGN.md: ``/robot``, ``/ptu``, ``/perception``, ``/map``, ``/mission``.
Every key has one writer role: ``sense`` keys are written only by the data-gathering branch
(drivers' readings, perception), ``task`` keys by the mission's task tree. ``/mission/...`` is free
for missions to use with any value. Plugins declare their own keys with :func:`register_key`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from drivers.interfaces import PanTiltCommand, PanTiltState, VelocityCommand
from perception.frame import Frame
from perception.geometry import Pose2D
from perception.observation import Observation

Writer = Literal["sense", "task", "any"]
NAMESPACES = ("/robot", "/ptu", "/perception", "/map", "/mission")


@dataclass(frozen=True, slots=True)
class KeySpec:
    """A documented blackboard key: its absolute path, value type and writer role."""

    path: str
    type: Any
    writer: Writer
    doc: str


_KEYS: dict[str, KeySpec] = {}


def register_key(spec: KeySpec) -> KeySpec:
    """Declare a key; declaring the same path twice with a different spec is an error."""
    if not spec.path.startswith("/") or spec.path.count("/") < 2:
        raise ValueError(f"blackboard key {spec.path!r} must be absolute, like /map/goal")
    if spec.path.split("/")[1] not in {ns.strip("/") for ns in NAMESPACES}:
        raise ValueError(f"blackboard key {spec.path!r} is outside the namespaces {', '.join(NAMESPACES)}")
    old = _KEYS.get(spec.path)
    if old is not None and old != spec:
        raise ValueError(f"blackboard key {spec.path!r} is already declared differently")
    _KEYS[spec.path] = spec
    return spec


def key_spec(path: str) -> KeySpec | None:
    """The spec of a key (``/mission/...`` keys are implicitly ``any``), or None if unknown."""
    base = path.split(".", 1)[0]
    spec = _KEYS.get(base)
    if spec is None and base.startswith("/mission/") and base.count("/") >= 2 and len(base) > 9:
        return KeySpec(base, object, "any", "mission variable")
    return spec


def all_keys() -> list[KeySpec]:
    return sorted(_KEYS.values(), key=lambda k: k.path)


for _spec in (
    KeySpec("/robot/odometry", Pose2D, "sense", "odometry pose of the base (drifts)"),
    KeySpec("/robot/stalled", bool, "sense", "a wheel is stalled (collision)"),
    KeySpec("/robot/command", VelocityCommand, "task", "velocity for this tick; cleared before every tick"),
    KeySpec("/ptu/state", PanTiltState, "sense", "pan/tilt position and motion"),
    KeySpec("/ptu/command", PanTiltCommand, "task", "pan/tilt target; cleared before every tick"),
    KeySpec("/perception/frames", dict, "sense", "latest Frame of each camera, by camera name"),
    KeySpec("/perception/frame", Frame, "sense", "latest Frame of the primary camera"),
    KeySpec("/perception/observation", Observation, "sense", "features and unit bearings of the latest frame"),
    KeySpec("/perception/motion", object, "sense", "latest Z-infinity motion estimate"),
    KeySpec("/perception/heading", float, "sense", "filtered heading correction (rad)"),
    KeySpec("/map/goal", Pose2D, "task", "the current goal pose in the odometry frame"),
    KeySpec("/map/ltmap", object, "task", "the Landmark-Tree map"),
    KeySpec("/map/roadmap", object, "task", "the target roadmap"),
    KeySpec("/map/room", object, "task", "the room estimate"),
    KeySpec("/map/coverage", object, "task", "the coverage grid"),
    KeySpec("/map/exploration", object, "task", "the exploration map"),
    KeySpec("/map/route_progress", object, "task", "progress along a taught route"),
):
    register_key(_spec)
