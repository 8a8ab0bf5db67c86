"""Our values to ROS 2 message dictionaries and back: odometry, the pan-tilt unit, ranges and
bumpers, commands, the clock, the operator's keys. Pure functions, no I/O.

A message is a plain ``dict`` as ``mcap_ros2``'s writer takes it (fields left out take their
defaults); the readers hand decoded messages back as the same dicts. Times are seconds on the
run's clock, written as ``builtin_interfaces/Time`` (whole nanoseconds). Frames follow REP-105:
odometry is ``odom`` -> ``base_link``, each range sensor and bumper is a frame whose mounting on
``base_link`` a ``tf2_msgs/TFMessage`` on ``/tf_static`` gives.

Choices where ROS has no exact counterpart (docs/recorded-data.md):

- the pan-tilt unit's ``moving`` flag is its ``JointState`` velocity: ``[0, 0]`` at rest, unknown
  (``NaN``) while it moves, since the unit reports no speed; a velocity that is not zero (or NaN)
  reads as moving;
- a bumper is a fixed-distance ``sensor_msgs/Range`` (``min_range == max_range == 0``): ``-inf``
  when pressed, ``+inf`` when not, as ``sensor_msgs/Range`` defines a detection and its absence;
- a range sensor that has not read yet (``nan`` in a :class:`~perception.ranges.RangeScan`) is not
  written; ``inf`` (no echo) is written as ``+inf``. ``sensor_msgs/Range`` holds float32: a read
  range is the written one to float32 precision.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from drivers.interfaces import PanTiltCommand, PanTiltState, VelocityCommand
from perception.geometry import Pose2D, wrap_angle
from perception.ranges import Bumper, RangeScan, RangeSensor

NS = 1_000_000_000
BASE_FRAME = "base_link"
ODOM_FRAME = "odom"
PTU_JOINTS = ("pan", "tilt")
ULTRASOUND, INFRARED = 0, 1  # sensor_msgs/Range radiation types


# -- time --------------------------------------------------------------------------------------------
def nanoseconds(seconds: float) -> int:
    """Seconds on the run's clock as whole nanoseconds (the MCAP log time)."""
    return round(seconds * NS)


def time_message(seconds: float) -> dict[str, int]:
    """A ``builtin_interfaces/Time``."""
    ns = nanoseconds(seconds)
    return {"sec": ns // NS, "nanosec": ns % NS}


def time_ns(message: Mapping[str, Any]) -> int:
    """A ``builtin_interfaces/Time`` as nanoseconds."""
    return int(message["sec"]) * NS + int(message["nanosec"])


def header(seconds: float, frame_id: str) -> dict[str, Any]:
    """A ``std_msgs/Header``."""
    return {"stamp": time_message(seconds), "frame_id": frame_id}


def clock_message(seconds: float) -> dict[str, Any]:
    """A ``rosgraph_msgs/Clock``: the run's clock at a tick."""
    return {"clock": time_message(seconds)}


# -- odometry ------------------------------------------------------------------------------------------
def yaw_quaternion(theta: float) -> dict[str, float]:
    """The rotation by ``theta`` about z as a ``geometry_msgs/Quaternion``."""
    return {"x": 0.0, "y": 0.0, "z": math.sin(theta / 2.0), "w": math.cos(theta / 2.0)}


def quaternion_yaw(q: Mapping[str, Any]) -> float:
    """The heading (rad, in [-pi, pi]) of a quaternion: its rotation about z."""
    x, y, z, w = (float(q[k]) for k in ("x", "y", "z", "w"))
    if x == 0.0 and y == 0.0:  # a pure yaw: the exact inverse of yaw_quaternion
        return wrap_angle(2.0 * math.atan2(z, w))
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def odometry_message(pose: Pose2D) -> dict[str, Any]:
    """A ``nav_msgs/Odometry`` of an odometry pose (stamped with the pose's time; no twist)."""
    return {"header": header(pose.stamp, ODOM_FRAME), "child_frame_id": BASE_FRAME,
            "pose": {"pose": {"position": {"x": pose.x, "y": pose.y, "z": 0.0},
                              "orientation": yaw_quaternion(pose.theta)}}}


def pose_from_odometry(message: Mapping[str, Any], stamp: float) -> Pose2D:
    """The planar pose of a ``nav_msgs/Odometry``, stamped ``stamp`` (seconds on the replay's clock)."""
    pose = message["pose"]["pose"]
    return Pose2D(float(pose["position"]["x"]), float(pose["position"]["y"]), quaternion_yaw(pose["orientation"]),
                  stamp)


# -- flags, text, commands -----------------------------------------------------------------------------
def bool_message(value: bool) -> dict[str, Any]:
    """A ``std_msgs/Bool``."""
    return {"data": bool(value)}


def keys_message(keys: Sequence[str]) -> dict[str, Any]:
    """A ``std_msgs/String`` of the keys one read returned, oldest first, separated by spaces."""
    return {"data": " ".join(keys)}


def keys_from(message: Mapping[str, Any]) -> list[str]:
    """The keys of a ``std_msgs/String`` written by :func:`keys_message`."""
    return str(message["data"]).split()


def twist_message(command: VelocityCommand) -> dict[str, Any]:
    """A ``geometry_msgs/Twist``: ``v`` along x, ``w`` about z."""
    return {"linear": {"x": command.v, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": command.w}}


def command_from_twist(message: Mapping[str, Any]) -> VelocityCommand:
    """The body-frame velocity of a ``geometry_msgs/Twist``."""
    return VelocityCommand(float(message["linear"]["x"]), float(message["angular"]["z"]))


# -- the pan-tilt unit ---------------------------------------------------------------------------------
def ptu_state_message(state: PanTiltState) -> dict[str, Any]:
    """A ``sensor_msgs/JointState``: positions [pan, tilt]; velocity zero at rest, NaN (unknown) moving."""
    speed = math.nan if state.moving else 0.0
    return {"header": header(state.stamp, BASE_FRAME), "name": list(PTU_JOINTS),
            "position": [state.pan, state.tilt], "velocity": [speed, speed], "effort": []}


def ptu_state_from(message: Mapping[str, Any], stamp: float, joints: Sequence[str] = PTU_JOINTS) -> PanTiltState:
    """The pan-tilt state of a ``sensor_msgs/JointState``; ``joints`` names the pan and tilt joints
    (a message without names is [pan, tilt] in that order). ValueError when a joint is missing."""
    names = [str(n) for n in message.get("name", [])]
    positions = [float(p) for p in message.get("position", [])]
    velocities = [float(v) for v in message.get("velocity", [])]
    index = [names.index(j) if j in names else -1 for j in joints] if names else [0, 1]
    if min(index) < 0 or max(index) >= len(positions):
        raise ValueError(f"the joint state has no position for {' and '.join(joints)} (joints: "
                         f"{', '.join(names) or 'unnamed'})")
    moving = any(i < len(velocities) and (math.isnan(velocities[i]) or velocities[i] != 0.0) for i in index)
    return PanTiltState(positions[index[0]], positions[index[1]], moving, stamp)


def ptu_command_message(command: PanTiltCommand | None, seconds: float) -> dict[str, Any]:
    """A ``sensor_msgs/JointState`` command: target positions at the slew speed, or (None) a halt:
    no position, zero velocity."""
    if command is None:
        return {"header": header(seconds, BASE_FRAME), "name": list(PTU_JOINTS), "position": [],
                "velocity": [0.0, 0.0], "effort": []}
    return {"header": header(seconds, BASE_FRAME), "name": list(PTU_JOINTS), "position": [command.pan, command.tilt],
            "velocity": [command.speed, command.speed], "effort": []}


# -- ranges and bumpers --------------------------------------------------------------------------------
def range_frame(index: int) -> str:
    return f"range_{index:02d}"


def bumper_frame(index: int) -> str:
    return f"bumper_{index:02d}"


def mounting_message(scan: RangeScan, seconds: float) -> dict[str, Any]:
    """A ``tf2_msgs/TFMessage``: where each range sensor and bumper of ``scan`` sits on ``base_link``
    (a bumper facing the rear is turned by pi)."""
    transforms = [_transform(range_frame(i), s.x, s.y, s.heading, seconds) for i, s in enumerate(scan.sensors)]
    transforms += [_transform(bumper_frame(j), b.x, b.y, 0.0 if b.facing > 0 else math.pi, seconds)
                   for j, b in enumerate(scan.bumpers)]
    return {"transforms": transforms}


def _transform(child: str, x: float, y: float, yaw: float, seconds: float) -> dict[str, Any]:
    return {"header": header(seconds, BASE_FRAME), "child_frame_id": child,
            "transform": {"translation": {"x": x, "y": y, "z": 0.0}, "rotation": yaw_quaternion(yaw)}}


@dataclass(frozen=True, slots=True)
class Mounting:
    """Where a sensor sits on the base: position (m) and heading (rad)."""

    x: float
    y: float
    heading: float


@dataclass(frozen=True, slots=True)
class StaticTransform:
    """One ``/tf_static`` transform: where a child frame sits in its parent (metres; quaternion x, y, z, w)."""

    parent: str
    translation: tuple[float, float, float]
    rotation: tuple[float, float, float, float]


def static_transforms(message: Mapping[str, Any]) -> dict[str, StaticTransform]:
    """The transforms of a ``tf2_msgs/TFMessage``, by child frame (leading slashes dropped)."""
    out = {}
    for transform in message.get("transforms", []):
        t, q = transform["transform"]["translation"], transform["transform"]["rotation"]
        out[str(transform["child_frame_id"]).lstrip("/")] = StaticTransform(
            str(transform["header"]["frame_id"]).lstrip("/"), (float(t["x"]), float(t["y"]), float(t.get("z", 0.0))),
            (float(q["x"]), float(q["y"]), float(q["z"]), float(q["w"])))
    return out


def mountings_on_base(transforms: Mapping[str, StaticTransform],
                      base_frames: Sequence[str] = (BASE_FRAME, "base_footprint")) -> dict[str, Mounting]:
    """Where each frame sits on the base, following chains of transforms (a camera mast, a sonar
    board) up to a base frame; a frame whose chain ends elsewhere or loops is not on the base. The
    heading is that of the frame's x axis seen from above."""
    out = {}
    for frame in transforms:
        chain: list[StaticTransform] = []
        parent = frame
        while parent not in base_frames and parent in transforms and len(chain) <= len(transforms):
            chain.append(transforms[parent])
            parent = transforms[parent].parent
        if parent not in base_frames:
            continue
        position, rotation = np.zeros(3), Rotation.identity()
        for step in chain:  # from the frame up: p_parent = R p_child + t
            turn = Rotation.from_quat(step.rotation)
            position, rotation = turn.apply(position) + step.translation, turn * rotation
        axis = rotation.apply([1.0, 0.0, 0.0])
        out[frame] = Mounting(float(position[0]), float(position[1]), math.atan2(axis[1], axis[0]))
    return out


def mountings_from(message: Mapping[str, Any], base_frames: Sequence[str] = (BASE_FRAME, "base_footprint")
                   ) -> dict[str, Mounting]:
    """The frames one ``tf2_msgs/TFMessage`` places on the base, by name (chains within it followed)."""
    return mountings_on_base(static_transforms(message), base_frames)


def range_messages(scan: RangeScan) -> list[dict[str, Any]]:
    """One ``sensor_msgs/Range`` per sensor that has read (``nan``: not yet, not written), stamped
    when it read (``RangeScan.fired``)."""
    out = []
    fired = scan.fired_at()
    for i, (sensor, value) in enumerate(zip(scan.sensors, scan.ranges, strict=True)):
        if math.isnan(float(value)):
            continue
        out.append({"header": header(float(fired[i]), range_frame(i)), "radiation_type": ULTRASOUND,
                    "field_of_view": sensor.fov, "min_range": sensor.min_range, "max_range": sensor.max_range,
                    "range": float(value)})
    return out


def bumper_messages(scan: RangeScan) -> list[dict[str, Any]]:
    """One fixed-distance ``sensor_msgs/Range`` per bumper: ``-inf`` pressed, ``+inf`` free."""
    return [{"header": header(scan.stamp, bumper_frame(j)), "radiation_type": INFRARED, "field_of_view": 0.0,
             "min_range": 0.0, "max_range": 0.0, "range": -math.inf if pressed else math.inf}
            for j, pressed in enumerate(scan.pressed)]


def range_sensor(mounting: Mounting, message: Mapping[str, Any]) -> RangeSensor:
    """The range sensor a ``sensor_msgs/Range`` comes from, at its mounting."""
    return RangeSensor(mounting.x, mounting.y, mounting.heading, fov=float(message["field_of_view"]),
                       max_range=float(message["max_range"]), min_range=float(message["min_range"]))


def bumper(mounting: Mounting) -> Bumper:
    """A bumper at its mounting: facing the front when its frame looks forward."""
    return Bumper(mounting.x, mounting.y, 1 if math.cos(mounting.heading) >= 0.0 else -1)


def range_value(message: Mapping[str, Any]) -> float:
    """The range of a ``sensor_msgs/Range``: ``inf`` for no echo; NaN (invalid) stays NaN."""
    return float(message["range"])


def pressed(message: Mapping[str, Any]) -> bool:
    """Is the fixed-distance ranger (a bumper) detecting: ``-inf``, or a range within its distance."""
    value = float(message["range"])
    return value == -math.inf or (math.isfinite(value) and value <= float(message["max_range"]))
