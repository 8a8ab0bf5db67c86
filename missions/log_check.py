"""Does a log hold what a mission reads? The check ``bearings log check`` prints and ``bearings run
--replay`` makes before anything ticks (exit 2 with what is missing), and the opening of a replay.

What a mission reads from the robot (:func:`mission_needs`): odometry always (the sensing branch
reads it every tick); the cameras it names (its ``cameras:``, else the ``camera`` inputs of its
nodes); the pan-tilt state when a node reads ``/ptu/state``; ranges when one reads
``/robot/ranges``; the operator's keys when it can drive by keys (a warning only: the keys may
never be needed). For each camera the first frame is decoded, so an image encoding or a camera
model we cannot read is found here rather than mid-run.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from behaviours.ports import Ref
from drivers.logs import camera_codec
from drivers.logs import messages as msg
from drivers.logs.reader import open_log
from drivers.logs.replay import Replay
from drivers.logs.source import LogContents, LogError, LogReader
from drivers.logs.topics import CameraSource, Topics, load_topic_map, resolve_topics
from maps.store import Diagnostic, InputError
from missions.language import MissionSpec

PTU_KEY = "/ptu/state"
RANGES_KEY = "/robot/ranges"


@dataclass(frozen=True)
class Needs:
    """What a mission reads from the robot."""

    cameras: tuple[str, ...] = ()
    ptu: bool = False
    ranges: bool = False
    keys: bool = False


@dataclass(frozen=True)
class Finding:
    """One line of the check: a role, whether the log fills it, and how (or what is missing)."""

    role: str
    ok: bool
    text: str
    required: bool = True

    def __str__(self) -> str:
        mark = "ok" if self.ok else "MISSING" if self.required else "warning"
        return f"{mark:8} {self.role}: {self.text}"


def mission_needs(mission: MissionSpec) -> Needs:
    """What ``mission`` reads from the robot, from its declaration and its nodes' inputs."""
    cameras: list[str] = list(mission.cameras or ())
    ptu = ranges = keys = False
    for spec in (node for root in (*mission.sense, mission.tree) for node in root.walk()):
        node_type = mission.registry.lookup(spec.type)
        keys = keys or spec.type == "KeyboardTeleop"
        optional = getattr(node_type.cls, "RANGES_OPTIONAL", False) if node_type else False  # works without them
        for port in node_type.inputs if node_type else ():
            value = spec.inputs.get(port.name)
            if isinstance(value, Ref):
                ptu = ptu or value.base == PTU_KEY
                ranges = ranges or (value.base == RANGES_KEY and not optional)
            elif port.name == "camera" and isinstance(value, str) and value and mission.cameras is None:
                cameras.append(value)
    return Needs(tuple(dict.fromkeys(cameras)), ptu, ranges, keys)


def open_topics(reader: LogReader, map_path: str | Path | None) -> Topics:
    """The topics to read from ``reader``'s log: the topic map's (InputError: a bad map), defaults."""
    given = load_topic_map(map_path) if map_path is not None else None
    return resolve_topics(reader.contents().types(), given, map_path=map_path)


def check_log(path: str | Path, topics: Topics, contents: LogContents, needs: Needs) -> list[Finding]:
    """Every finding of the check: required roles first, then what else the log offers."""
    findings = [_role(contents, "odometry", topics.odometry, (msg.ODOMETRY,))]
    for name in needs.cameras:
        findings.append(_camera(path, contents, topics, name))
    if needs.ptu or topics.ptu in contents.topics:
        findings.append(_role(contents, "pan-tilt", topics.ptu, (msg.JOINT_STATE,), required=needs.ptu))
    range_topics = [t for t in (*topics.ranges, *topics.bumpers) if t in contents.topics]
    if needs.ranges or range_topics:
        text = ", ".join(range_topics) + f" (where they sit: {topics.tf_static})" if range_topics else \
            f"none of {', '.join((*topics.ranges, *topics.bumpers))}"
        findings.append(Finding("ranges", bool(range_topics) and topics.tf_static in contents.topics, text,
                                required=needs.ranges))
    if needs.keys:
        keys = _role(contents, "keys", topics.keys, (msg.STRING,), required=False)
        findings.append(keys if keys.ok else Finding("keys", False, f"the mission can drive by keys; {keys.text}",
                                                     required=False))
    if contents.cut:
        findings.append(Finding("file", False, contents.cut + ": replayed up to the cut", required=False))
    return findings


def _role(contents: LogContents, role: str, topic: str, types: tuple[str, ...], *, required: bool = True
          ) -> Finding:
    info = contents.topics.get(topic)
    if info is None or info.count == 0:
        others = [t.name for t in contents.topics.values() if t.type in types and t.count]
        hint = f" (topics of that type: {', '.join(others)}; name one in the topic map)" if others else ""
        return Finding(role, False, f"no {types[0]} on {topic}{hint}", required)
    if info.problem or info.type not in types:
        return Finding(role, False, f"{topic} is {info.type or 'unknown'}"
                       f"{f' ({info.problem})' if info.problem else ''}; {role} reads {' or '.join(types)}", required)
    return Finding(role, True, f"{topic} ({info.type}, {info.count} messages{_rate(contents, info.count)})",
                   required)


def _camera(path: str | Path, contents: LogContents, topics: Topics, name: str) -> Finding:
    source = topics.cameras.get(name)
    if source is None:
        images = [t.name for t in contents.topics.values() if t.type in msg.IMAGE_TYPES]
        return Finding(f"camera {name}", False, "not in the log (image topics: "
                       f"{', '.join(images) or 'none'}; map one in the topic map: cameras: {{{name}: {{image: ...}}}})")
    found = _role(contents, f"camera {name}", source.image, msg.IMAGE_TYPES)
    if not found.ok:
        return found
    try:
        described = _first_frame(path, source, contents.types()[source.image])
    except (LogError, ValueError) as exc:
        return Finding(found.role, False, str(exc).removeprefix(f"{path}: "))
    return Finding(found.role, True, f"{found.text}, {described}")


def _first_frame(path: str | Path, source: CameraSource, kind: str) -> str:
    """Decode the camera's first frame and model: what they are, or ValueError/LogError why not."""
    with _opened(path) as reader:
        wanted = [t for t in (source.image, source.info) if t]
        image = info = None
        for message in reader.messages(wanted):
            if message.topic == source.info and info is None:
                info = message.message
            elif message.topic == source.image:
                image = message
            if image is not None and (info is not None or source.model is not None or not source.info
                                      or kind == msg.POINT_CLOUD):
                break
        if image is None:
            raise ValueError(f"no frame on {source.image}")
        where = f"{source.image} at {(image.log_ns - reader.contents().start_ns) / 1e9:.3f} s"
        try:
            if kind == msg.POINT_CLOUD:
                return f"landmark bearings ({len(camera_codec.bearings_from_cloud(image.message, 0.0, source.name))} "\
                       "in the first)"
            pixels = camera_codec.image_from_compressed(image.message) if kind == msg.COMPRESSED_IMAGE \
                else camera_codec.image_from_raw(image.message)
            model = source.model if source.model is not None else (
                camera_codec.camera_from_info(info) if info is not None else None)
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None
        if model is None:
            raise ValueError(f"no camera model: no CameraInfo on {source.info or '(no info topic)'}, and the topic "
                             "map gives none (cameras: {name: {model: FILE.yaml}})")
        shape = "x".join(str(n) for n in (pixels.shape[1], pixels.shape[0]))
        return f"{model.kind} model, {shape} {'colour' if pixels.ndim == 3 else 'grey'} images"


@contextlib.contextmanager
def _opened(path: str | Path) -> Iterator[LogReader]:
    reader = open_log(path)
    try:
        yield reader
    finally:
        reader.close()


def _rate(contents: LogContents, count: int) -> str:
    return f", {rate(contents, count):.1f} Hz" if rate(contents, count) else ""


def rate(contents: LogContents, count: int) -> float | None:
    """Messages per second of a topic with ``count`` messages over the log (None: fewer than two)."""
    return (count - 1) / contents.duration_s if contents.duration_s > 0 and count > 1 else None


def open_replay(path: str | Path, map_path: str | Path | None, mission: MissionSpec) -> Replay:
    """The replay of the log at ``path`` for ``mission``; :class:`InputError` with every missing
    input (and a bad log or topic map) before anything runs."""
    try:
        reader = open_log(path)
    except LogError as exc:
        raise InputError([Diagnostic(str(path), 0, 0, str(exc).removeprefix(f"{path}: "))]) from None
    try:
        topics = open_topics(reader, map_path)
        contents = reader.contents()
        missing = [f for f in check_log(path, topics, contents, mission_needs(mission)) if f.required and not f.ok]
        if missing:
            raise InputError([Diagnostic(str(path), 0, 0, f"{f.role}: {f.text} (the mission {mission.name} reads "
                                         "it)") for f in missing])
        return Replay(reader, topics)
    except LogError as exc:
        reader.close()
        raise InputError([Diagnostic(str(path), 0, 0, str(exc).removeprefix(f"{path}: "))]) from None
    except BaseException:
        reader.close()
        raise
