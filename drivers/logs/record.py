"""Record a run's sensed inputs and commands (``bearings run --record run.mcap``).

:meth:`SensorLog.wrap` puts a recording layer around each device of a
:class:`~drivers.interfaces.Robot`: what a driver delivers to the run is written as it is read
(odometry and the stall flag, each camera's frames and model, the pan-tilt state, the range
sensors and bumpers with where they sit, the operator's keys), and so is every command the
devices are sent (the base's velocity after the collision monitor, pan-tilt moves and halts). The
runner adds the tree's own command and the clock once per tick (:meth:`SensorLog.tick`). A
reading is written once: a device read twice in a tick with the same answer writes one message.

Each message's log time is the run's clock when the run read it; its header stamp is the stamp
the driver gave (a frame's capture time). A camera that dropped a frame writes nothing, so a
replay sees the same drops. Recording never fails a run: a message that cannot be written is
counted (the report's ``record`` section says how many and why) and the run goes on.
"""

from __future__ import annotations

import contextlib
import datetime
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from drivers.interfaces import (
    Base,
    Camera,
    KeyboardOpener,
    KeySource,
    PanTilt,
    PanTiltCommand,
    PanTiltState,
    RangeSource,
    Robot,
    VelocityCommand,
)
from drivers.logs import camera_codec, codec, topics
from drivers.logs import messages as msg
from drivers.logs.camera_codec import ImageFormat
from drivers.logs.source import FOOTPRINT, first_line
from drivers.logs.writer import LogWriter
from perception.frame import Frame, LandmarkBearings
from perception.geometry import Pose2D
from perception.ranges import RangeScan


class SensorLog:
    """The MCAP log of one run; wraps its robot's devices, written from :meth:`open` to :meth:`close`."""

    def __init__(self, path: str | Path, *, images: ImageFormat | None = None) -> None:
        self.path = Path(path)
        self.images = images or ImageFormat()
        self.clock: Callable[[], float] = lambda: 0.0
        self.writer: LogWriter | None = None
        self.errors = 0
        self.first_error = ""
        self._last: dict[str, Any] = {}  # topic -> the last value written (a reading is written once)

    # -- set-up ----------------------------------------------------------------------------------------
    def wrap(self, robot: Robot, clock: Callable[[], float]) -> Robot:
        """The same robot, each device recording what it delivers and what it is sent; ``clock`` is
        the run's (it times every message)."""
        self.clock = clock
        cameras: dict[str, Camera] = {name: RecordingCamera(camera, self) for name, camera in robot.cameras.items()}
        return Robot(base=RecordingBase(robot.base, self), ptu=RecordingPanTilt(robot.ptu, self) if robot.ptu else None,
                     cameras=cameras, ranges=RecordingRanges(robot.ranges, self) if robot.ranges else None,
                     name=robot.name)

    def wrap_keyboard(self, opener: KeyboardOpener) -> KeyboardOpener:
        """An opener whose keyboard records the keys it reads."""
        return lambda: RecordingKeys(opener(), self)

    def open(self, *, mission: str, timeline: str, rate_hz: float, footprint: np.ndarray | None = None) -> None:
        """Create the file (its metadata says what was run, when, how the images are compressed and,
        given the collision monitor's ``footprint`` polygon, the robot's outline, which a replay
        judges its safety with: :meth:`~drivers.logs.source.LogContents.footprint`)."""
        started = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
        metadata = {"mission": mission, "timeline": timeline, "rate_hz": f"{rate_hz:g}", "started_utc": started,
                    "images": str(self.images), "times": "seconds on the run's clock since its start"}
        if footprint is not None:
            metadata[FOOTPRINT] = json.dumps(np.round(np.asarray(footprint, dtype=float), 6).tolist())
        self.writer = LogWriter(self.path, metadata=metadata)

    def close(self) -> None:
        if self.writer is not None:
            with contextlib.suppress(Exception):  # the run's outcome matters more than the file
                self.writer.close()

    # -- what the runner adds ----------------------------------------------------------------------------
    def tick(self, asked: VelocityCommand) -> None:
        """Once per tick, after it: the clock and the command the tree asked for."""
        now = self.clock()
        self.write(topics.CLOCK, msg.CLOCK, codec.clock_message(now), now)
        self.write(topics.TREE_COMMAND, msg.TWIST, codec.twist_message(asked), now)

    # -- writing -----------------------------------------------------------------------------------------
    def write(self, topic: str, type_name: str, message: dict[str, Any], seconds: float | None = None) -> None:
        """One message, now unless ``seconds`` is given; a failure is counted, never raised."""
        if self.writer is None:
            return
        try:
            self.writer.write(topic, type_name, message, self.clock() if seconds is None else seconds)
        except Exception as exc:  # noqa: BLE001 - a recording problem must not stop the robot's run
            self.failed(topic, exc)

    def record_once(self, topic: str, value: Any, encode: Callable[[], list[tuple[str, str, dict[str, Any]]]]
                    ) -> None:
        """Write what ``encode`` makes of ``value`` unless ``topic`` last wrote this very value."""
        if self.writer is None or self._last.get(topic) == value:
            return
        self._last[topic] = value
        try:
            encoded = encode()
        except Exception as exc:  # noqa: BLE001 - an unencodable reading is counted, the run goes on
            self.failed(topic, exc)
            return
        now = self.clock()
        for name, type_name, message in encoded:
            self.write(name, type_name, message, now)

    def failed(self, topic: str, exc: Exception) -> None:
        self.errors += 1
        if not self.first_error:
            self.first_error = f"{topic}: {first_line(exc)}"

    def summary(self) -> dict[str, Any]:
        """The report's ``record`` section."""
        writer = self.writer
        out: dict[str, Any] = {"file": str(self.path), "images": str(self.images),
                               "messages": writer.messages if writer else 0,
                               "bytes": writer.size_bytes() if writer else 0, "errors": self.errors}
        if self.first_error:
            out["first_error"] = self.first_error
        return out

    # -- encoders for the devices ------------------------------------------------------------------------
    def frame_messages(self, name: str, frame: Frame | LandmarkBearings) -> list[tuple[str, str, dict[str, Any]]]:
        if isinstance(frame, LandmarkBearings):
            image, _, _, _ = topics.camera_topics(name, "bearings")
            return [(image, msg.POINT_CLOUD, camera_codec.bearings_message(frame))]
        image, info, right, right_info = topics.camera_topics(name, "compressed")
        # the model with every image, as ROS cameras publish it (a camera without one: images only)
        infos = camera_codec.camera_info_messages(frame.camera, frame.stamp, name) if frame.camera is not None else []
        out = [(info, msg.CAMERA_INFO, infos[0])] if infos else []
        out.append((image, msg.COMPRESSED_IMAGE,
                    camera_codec.compressed_image_message(frame.image, frame.stamp, name, self.images)))
        if frame.right is not None:
            out += [(right_info, msg.CAMERA_INFO, infos[-1])] if infos else []
            out.append((right, msg.COMPRESSED_IMAGE, camera_codec.compressed_image_message(
                frame.right, frame.stamp, f"{name}_right", self.images)))
        return out

    def scan_messages(self, scan: RangeScan) -> list[tuple[str, str, dict[str, Any]]]:
        geometry = (scan.sensors, scan.bumpers)
        out = []
        if self._last.get(topics.TF_STATIC) != geometry:  # where the sensors sit: once, and when it changes
            self._last[topics.TF_STATIC] = geometry
            out.append((topics.TF_STATIC, msg.TF, codec.mounting_message(scan, scan.stamp)))
        out += [(topics.RANGES, msg.RANGE, m) for m in codec.range_messages(scan)]
        out += [(topics.BUMPERS, msg.RANGE, m) for m in codec.bumper_messages(scan)]
        return out


class _Recording:
    """Forwards anything else to the wrapped device (``describe()``, ``report_sections()``...)."""

    def __init__(self, device: Any, log: SensorLog) -> None:
        self.device = device
        self.log = log

    def __getattr__(self, name: str) -> Any:
        return getattr(self.device, name)

    def close(self) -> None:
        self.device.close()


class RecordingBase(_Recording):
    """A base whose odometry, stall flag and commands are recorded."""

    device: Base

    def drive(self, v: float, w: float) -> None:
        self.device.drive(v, w)
        self.log.write(topics.SENT_COMMAND, msg.TWIST, codec.twist_message(VelocityCommand(float(v), float(w))))

    def stop(self) -> None:
        self.device.stop()
        self.log.write(topics.SENT_COMMAND, msg.TWIST, codec.twist_message(VelocityCommand()))

    def odometry(self) -> Pose2D:
        pose = self.device.odometry()
        self.log.record_once(topics.ODOMETRY, (self.log.clock(), pose),
                             lambda: [(topics.ODOMETRY, msg.ODOMETRY, codec.odometry_message(pose))])
        return pose

    def stalled(self) -> bool:
        stalled = self.device.stalled()
        self.log.record_once(topics.STALLED, (self.log.clock(), bool(stalled)),
                             lambda: [(topics.STALLED, msg.BOOL, codec.bool_message(bool(stalled)))])
        return stalled


class RecordingPanTilt(_Recording):
    """A pan-tilt unit whose state and commands are recorded."""

    device: PanTilt

    def move(self, pan: float, tilt: float, speed: float) -> None:
        self.device.move(pan, tilt, speed)
        now = self.log.clock()
        self.log.write(topics.PTU_COMMAND, msg.JOINT_STATE,
                       codec.ptu_command_message(PanTiltCommand(pan, tilt, speed), now), now)

    def halt(self) -> None:
        self.device.halt()
        now = self.log.clock()
        self.log.write(topics.PTU_COMMAND, msg.JOINT_STATE, codec.ptu_command_message(None, now), now)

    def state(self) -> PanTiltState:
        state = self.device.state()
        self.log.record_once(topics.PTU_STATE, (self.log.clock(), state),
                             lambda: [(topics.PTU_STATE, msg.JOINT_STATE, codec.ptu_state_message(state))])
        return state


class RecordingCamera(_Recording):
    """A camera whose frames (and model, with every image) are recorded as they are grabbed."""

    device: Camera

    def __init__(self, device: Camera, log: SensorLog) -> None:
        super().__init__(device, log)
        self.name = device.name
        self._last: Frame | LandmarkBearings | None = None

    def grab(self) -> Frame | LandmarkBearings | None:
        frame = self.device.grab()
        if frame is not None and frame is not self._last:  # a driver handing the same frame again: written once
            self._last = frame
            name = self.name
            try:
                encoded = self.log.frame_messages(name, frame)
            except Exception as exc:  # noqa: BLE001 - an unencodable frame is counted, the run goes on
                self.log.failed(f"camera {name}", exc)
            else:
                for topic, type_name, message in encoded:
                    self.log.write(topic, type_name, message)
        return frame


class RecordingRanges(_Recording):
    """A range source whose scans are recorded, each once (a scan is new when its stamp is)."""

    device: RangeSource

    def read(self) -> RangeScan | None:
        scan = self.device.read()
        if scan is not None:
            self.log.record_once(topics.RANGES, scan.stamp, lambda: self.log.scan_messages(scan))
        return scan


class RecordingKeys:
    """The operator's keyboard, recording the keys each read returns."""

    def __init__(self, keys: KeySource, log: SensorLog) -> None:
        self.keys = keys
        self.log = log

    def read(self) -> list[str]:
        keys = self.keys.read()
        if keys:
            self.log.write(topics.KEYS, msg.STRING, codec.keys_message(keys))
        return keys

    def close(self) -> None:
        self.keys.close()
