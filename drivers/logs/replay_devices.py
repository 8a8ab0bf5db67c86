"""The replay's cameras and range source: logged frames and ranges handed over as the run asks.

A :class:`ReplayCamera` keeps the newest frame logged since the last grab, decoded only when
grabbed (a frame the run never grabs costs no decoding), with its model from the logged
``CameraInfo`` or, when the topic map names one, that model. A stereo pair's frame needs its
left and right images with the same stamp (as ROS's exact-time pairing). A
:class:`ReplayRanges` rebuilds the :class:`~perception.ranges.RangeScan` the run saw from the
``sensor_msgs/Range`` readings and where ``/tf_static`` puts each sensor: every sensor's newest
range (``nan`` before its first), every bumper's newest state.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from drivers.logs import camera_codec, codec
from drivers.logs import messages as msg
from drivers.logs.source import LogError, LogMessage
from drivers.logs.topics import CameraSource, Topics
from perception.frame import Frame, LandmarkBearings
from perception.ranges import RangeScan, RangeSensor

_RANGE_FRAME = re.compile(r"^range_\d+$")
_BUMPER_FRAME = re.compile(r"^bumper_\d+$")


class Replay(Protocol):
    """What the devices need of the replay they belong to (:class:`drivers.logs.replay.Replay`)."""

    path: Path
    topics: Topics

    def stamp_seconds(self, message: LogMessage) -> float: ...

    def log_seconds(self, log_ns: int) -> float: ...


class ReplayCamera:
    """One camera of the log."""

    def __init__(self, replay: Replay, source: CameraSource, available: dict[str, str]) -> None:
        self.name = source.name
        self.source = source
        self._replay = replay
        self._kind = msg.type_name(available[source.image])
        self._pending: LogMessage | None = None
        self._rights: dict[float, LogMessage] = {}  # right images by stamp, the newest few
        self._info: dict[str, Any] | None = None
        self._right_info: dict[str, Any] | None = None
        self._model: tuple[Any, Any] | None = None  # (the info it was made from, the model)
        self.delivered = 0

    def handlers(self) -> dict[str, Callable[[LogMessage], None]]:
        source = self.source
        table: dict[str, Callable[[LogMessage], None]] = {source.image: self._on_image}
        if source.info:
            table[source.info] = self._on_info
        if source.right:
            table[source.right] = self._on_right
        if source.right_info:
            table[source.right_info] = self._on_right_info
        return table

    def _on_image(self, message: LogMessage) -> None:
        self._pending = message

    def _on_right(self, message: LogMessage) -> None:
        self._rights[self._replay.stamp_seconds(message)] = message
        while len(self._rights) > 8:
            del self._rights[next(iter(self._rights))]

    def _on_info(self, message: LogMessage) -> None:
        self._info = message.message

    def _on_right_info(self, message: LogMessage) -> None:
        self._right_info = message.message

    def grab(self) -> Frame | LandmarkBearings | None:
        """The newest frame logged since the last grab, or None (none came in: a drop)."""
        pending = self._pending
        if pending is None:
            return None
        replay = self._replay
        stamp = replay.stamp_seconds(pending)
        right = None
        if self.source.right:
            right = self._rights.get(stamp)
            if right is None:
                return None  # its right image has not come in (yet)
        self._pending = None
        try:
            frame = self._decode(pending, stamp, right)
        except (ValueError, KeyError, TypeError, IndexError) as exc:
            raise LogError(f"{replay.path}: {pending.topic} at {replay.log_seconds(pending.log_ns):.3f} s: "
                           f"{describe_problem(exc)}") from None
        self.delivered += 1
        return frame

    def _decode(self, message: LogMessage, stamp: float, right: LogMessage | None) -> Frame | LandmarkBearings:
        if self._kind == msg.POINT_CLOUD:
            return camera_codec.bearings_from_cloud(message.message, stamp, self.name)
        image = self._pixels(message)
        model = self.model()
        return Frame(image=image, camera=model, stamp=stamp, camera_name=self.name,
                     right=self._pixels(right) if right is not None else None)

    def _pixels(self, message: LogMessage) -> np.ndarray:
        if self._kind == msg.COMPRESSED_IMAGE:
            return camera_codec.image_from_compressed(message.message)
        return camera_codec.image_from_raw(message.message)

    def model(self) -> Any:
        """The camera model: the topic map's, else the newest CameraInfo's (ValueError: none)."""
        if self.source.model is not None:
            return self.source.model
        info = self._info
        if info is None:
            raise ValueError(f"camera {self.name} has no model: no CameraInfo on "
                             f"{self.source.info or '(no info topic)'}, and the topic map gives none (model:)")
        if self._model is None or self._model[0] != (info, self._right_info):
            self._model = ((info, self._right_info), camera_codec.camera_from_info(info, self._right_info))
        return self._model[1]

    def close(self) -> None:
        pass


class ReplayRanges:
    """The logged range sensors and bumpers as a range source."""

    def __init__(self, replay: Replay) -> None:
        self._replay = replay
        self._transforms: dict[str, codec.StaticTransform] = {}  # every /tf_static message's, newest wins
        self._mountings: dict[str, codec.Mounting] = {}
        self._ranges: dict[str, tuple[RangeSensor, float]] = {}
        self._bumpers: dict[str, bool] = {}
        self._fired: dict[str, float] = {}  # frame -> the header stamp of its newest reading
        self._stamp: float | None = None
        self._scan: RangeScan | None = None

    def on_mounting(self, message: LogMessage) -> None:
        self._transforms.update(codec.static_transforms(message.message))
        self._mountings = codec.mountings_on_base(self._transforms)
        for frame in self._mountings:
            if _RANGE_FRAME.match(frame) and frame not in self._ranges:
                self._ranges[frame] = (_sensor(self._mountings[frame], None), float("nan"))
            elif _BUMPER_FRAME.match(frame) and frame not in self._bumpers:
                self._bumpers[frame] = False
        self._scan = None

    def on_range(self, message: LogMessage) -> None:
        frame = self._frame(message)
        self._ranges[frame] = (_sensor(self._mountings[frame], message.message), codec.range_value(message.message))
        self._fired[frame] = self._heard(message)

    def on_bumper(self, message: LogMessage) -> None:
        frame = self._frame(message)
        self._bumpers[frame] = codec.pressed(message.message)
        self._heard(message)

    def _frame(self, message: LogMessage) -> str:
        frame = str(message.message["header"]["frame_id"]).lstrip("/")
        if frame not in self._mountings:
            raise ValueError(f"frame {frame!r} has no transform from the base on {self._replay.topics.tf_static} "
                             "(where does the sensor sit?)")
        return frame

    def _heard(self, message: LogMessage) -> float:
        """The message's stamp (seconds on the replay's clock), now the newest reading's if later."""
        stamp = self._replay.stamp_seconds(message)
        self._stamp = stamp if self._stamp is None else max(self._stamp, stamp)
        self._scan = None
        return stamp

    def read(self) -> RangeScan | None:
        """Every sensor's newest range and every bumper's newest state (None before the first)."""
        if self._stamp is None:
            return None
        if self._scan is None:
            sensors = [sensor for sensor, _ in self._ranges.values()]
            bumpers = [codec.bumper(self._mountings[frame]) for frame in self._bumpers]
            fired = np.array([self._fired.get(frame, self._stamp) for frame in self._ranges], dtype=float)
            self._scan = RangeScan(tuple(sensors), np.array([value for _, value in self._ranges.values()], float),
                                   self._stamp, tuple(bumpers), np.array(list(self._bumpers.values()), dtype=bool),
                                   fired=fired)
        return self._scan

    def describe(self) -> str:
        return f"replayed ranges: {len(self._ranges)} sensors, {len(self._bumpers)} bumpers"

    def close(self) -> None:
        pass


def _sensor(mounting: codec.Mounting, message: dict[str, Any] | None) -> RangeSensor:
    if message is None:
        return RangeSensor(mounting.x, mounting.y, mounting.heading)
    return codec.range_sensor(mounting, message)


def describe_problem(exc: Exception) -> str:
    """What is wrong with a message, in words (a missing field says which)."""
    return f"the message has no field {exc}" if isinstance(exc, KeyError) else str(exc)
