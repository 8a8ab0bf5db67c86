"""Which topics of a log are the robot's inputs: the names ``--record`` writes, and the topic map
that points a replay at the topics of any other log (``--topics MAP.yaml``).

A topic map is a small YAML file; every entry is optional and falls back to the name ``--record``
writes::

    odometry: /odom                 # nav_msgs/Odometry
    ptu: /ptu/joint_states          # sensor_msgs/JointState (joints: ptu_joints, default [pan, tilt])
    cameras:                        # added to the cameras found under /cameras/<name>/
      panorama:
        image: /camera/image_raw    # sensor_msgs/Image or CompressedImage (PointCloud2: ideal bearings)
        info: /camera/camera_info   # sensor_msgs/CameraInfo, optional with model:
        model: panorama.yaml        # a camera file (bearings calibrate writes one) or an inline mapping
    ranges: [/sonar]                # sensor_msgs/Range; where each sensor sits: tf_static
    bumpers: [/bumpers]
    keys: /operator/keys            # std_msgs/String: the operator's keys
    commands: /cmd_vel              # geometry_msgs/Twist: compared with the mission's in the report
    odometry_origin: first          # first: the first pose is the origin (a run's start); log: as logged

A model file's path is relative to the map file. Errors are located (``file:line:col``).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, Field

from drivers.logs import messages as msg
from maps.located import FILE_MODEL_CONFIG, validate
from maps.store import Diagnostic, InputError, YamlMap, load_yaml, mark_of
from perception.camera import camera_from_dict

CLOCK = "/clock"
ODOMETRY = "/odom"
STALLED = "/robot/stalled"
PTU_STATE = "/ptu/joint_states"
PTU_COMMAND = "/ptu/command"
RANGES = "/ranges"
BUMPERS = "/bumpers"
TF_STATIC = "/tf_static"
SENT_COMMAND = "/cmd_vel"  # what the base was sent (after the collision monitor)
TREE_COMMAND = "/tree/cmd_vel"  # what the tree asked for
KEYS = "/operator/keys"
_CAMERA = re.compile(r"^/cameras/([^/]+)/(image/compressed|image|bearings)$")


def camera_topics(name: str, kind: str) -> tuple[str, str, str, str]:
    """(image, info, right image, right info) topics of camera ``name``; ``kind``: ``compressed``,
    ``raw`` or ``bearings``."""
    base = f"/cameras/{topic_name(name)}"
    image = {"compressed": "image/compressed", "raw": "image", "bearings": "bearings"}[kind]
    return f"{base}/{image}", f"{base}/camera_info", f"{base}/right/{image}", f"{base}/right/camera_info"


def topic_name(name: str) -> str:
    """A camera's name as a ROS name token (letters, digits, underscores)."""
    token = re.sub(r"[^A-Za-z0-9_]", "_", name) or "camera"
    return token if not token[0].isdigit() else f"_{token}"


class CameraEntry(BaseModel):
    """One camera of a topic map."""

    model_config = FILE_MODEL_CONFIG

    image: str = Field(min_length=1, description="the image topic (Image, CompressedImage; PointCloud2: bearings)")
    info: str | None = Field(None, min_length=1, description="its sensor_msgs/CameraInfo topic")
    right: str | None = Field(None, min_length=1, description="a stereo pair's right image topic")
    right_info: str | None = Field(None, min_length=1, description="the right camera's CameraInfo topic")
    model: str | dict[str, Any] | None = Field(None, description="the camera model: a camera file (relative to "
                                               "the map) or an inline mapping; default: from CameraInfo")


class TopicMapFile(BaseModel):
    """A topic map file."""

    model_config = FILE_MODEL_CONFIG

    odometry: str | None = Field(None, min_length=1, description="nav_msgs/Odometry")
    stalled: str | None = Field(None, min_length=1, description="std_msgs/Bool: a wheel is stalled")
    ptu: str | None = Field(None, min_length=1, description="sensor_msgs/JointState of the pan-tilt unit")
    ptu_joints: list[str] | None = Field(None, min_length=2, max_length=2, description="[pan joint, tilt joint]")
    cameras: dict[str, CameraEntry] = Field(default_factory=dict, max_length=32, description="cameras by name")
    ranges: list[str] | None = Field(None, max_length=64, description="sensor_msgs/Range topics of range sensors")
    bumpers: list[str] | None = Field(None, max_length=64, description="sensor_msgs/Range topics of bumpers")
    keys: str | None = Field(None, min_length=1, description="std_msgs/String: the operator's keys")
    commands: str | None = Field(None, min_length=1, description="geometry_msgs/Twist the robot was sent")
    tf_static: str | None = Field(None, min_length=1, description="tf2_msgs/TFMessage: where sensors sit")
    odometry_origin: Literal["first", "log"] = Field("first", description="first: the first pose is the origin")


@dataclass(frozen=True)
class CameraSource:
    """Where one camera's frames are in a log, and its model when the log does not say."""

    name: str
    image: str
    info: str | None = None
    right: str | None = None
    right_info: str | None = None
    model: Any = None


@dataclass(frozen=True)
class Topics:
    """The topics a replay reads, by role."""

    odometry: str = ODOMETRY
    stalled: str = STALLED
    ptu: str = PTU_STATE
    ptu_joints: tuple[str, str] = ("pan", "tilt")
    cameras: dict[str, CameraSource] = field(default_factory=dict)
    ranges: tuple[str, ...] = (RANGES,)
    bumpers: tuple[str, ...] = (BUMPERS,)
    keys: str = KEYS
    commands: str = SENT_COMMAND
    tf_static: str = TF_STATIC
    rebase_odometry: bool = True

    def wanted(self) -> list[str]:
        """Every topic a replay reads."""
        names = [self.odometry, self.stalled, self.ptu, *self.ranges, *self.bumpers, self.keys, self.commands,
                 self.tf_static]
        for camera in self.cameras.values():
            names += [t for t in (camera.image, camera.info, camera.right, camera.right_info) if t]
        return list(dict.fromkeys(names))


def load_topic_map(path: str | Path) -> TopicMapFile:
    """Read and check a topic map; :class:`InputError` with every problem located."""
    doc = load_yaml(path)
    if doc is None:
        return TopicMapFile()
    if not isinstance(doc, YamlMap):
        raise InputError([Diagnostic(str(path), 1, 1, "a topic map is a mapping (odometry:, cameras:, ...)")])
    return validate(TopicMapFile, doc, file=str(path))


def resolve_topics(available: Mapping[str, str], given: TopicMapFile | None = None, *,
                   map_path: str | Path | None = None) -> Topics:
    """The topics to read from a log holding ``available`` (topic -> type): the map's entries, the
    names ``--record`` writes for the rest, and every camera found under ``/cameras/<name>/``."""
    given = given or TopicMapFile()
    cameras = {camera.name: camera for camera in discover_cameras(available)}
    folder = Path(map_path).parent if map_path is not None else Path(".")
    for name, entry in given.cameras.items():
        cameras[name] = CameraSource(name, entry.image, entry.info, entry.right, entry.right_info,
                                     _model(entry.model, folder, map_path, name))
    return Topics(
        odometry=given.odometry or ODOMETRY, stalled=given.stalled or STALLED, ptu=given.ptu or PTU_STATE,
        ptu_joints=(given.ptu_joints[0], given.ptu_joints[1]) if given.ptu_joints else ("pan", "tilt"),
        cameras=cameras, ranges=tuple(given.ranges) if given.ranges is not None else (RANGES,),
        bumpers=tuple(given.bumpers) if given.bumpers is not None else (BUMPERS,), keys=given.keys or KEYS,
        commands=given.commands or SENT_COMMAND, tf_static=given.tf_static or TF_STATIC,
        rebase_odometry=given.odometry_origin == "first")


def discover_cameras(available: Mapping[str, str]) -> list[CameraSource]:
    """The cameras a log written by ``--record`` holds (topics ``/cameras/<name>/...``)."""
    found = []
    for topic, type_name in sorted(available.items()):
        match = _CAMERA.match(topic)
        if match is None or msg.type_name(type_name) not in msg.IMAGE_TYPES:
            continue
        name, kind = match.group(1), match.group(2)
        image, info, right, right_info = camera_topics(name, {"image/compressed": "compressed", "image": "raw",
                                                              "bearings": "bearings"}[kind])
        stereo = right in available
        found.append(CameraSource(name, image, info if info in available and kind != "bearings" else None,
                                  right if stereo else None, right_info if stereo and right_info in available
                                  else None))
    return found


def _model(model: str | dict[str, Any] | None, folder: Path, map_path: str | Path | None, camera: str) -> Any:
    """A camera model from a file (relative to the map) or an inline mapping; located errors."""
    if model is None:
        return None
    where = str(map_path or "topic map")
    if isinstance(model, str):
        path = Path(model) if Path(model).is_absolute() else folder / model
        doc = load_yaml(path)
        where, data = str(path), doc
    else:
        data = model
    try:
        return camera_from_dict(dict(data) if isinstance(data, dict) else data)
    except ValueError as exc:
        mark = mark_of(data)
        raise InputError([Diagnostic(where, mark.line, mark.col, f"cameras.{camera}.model: not a camera model: "
                                     f"{exc}")]) from None
