"""The data-gathering branch: driver readings onto the blackboard, once per tick.

These are the only behaviours that touch a driver, and only through the interfaces of the
:class:`~drivers.interfaces.Robot` handed to the tree at setup (``setup(robot=...)``). The
runner puts them first in every tree (:data:`SENSE_NODES`); they are not in the registry, so a
mission cannot add a second writer of the keys they own (the loader checks sensed keys keep a
single writer).
"""

from __future__ import annotations

from typing import Any

from py_trees.common import Status

from behaviours.base import BearingsBehaviour, NotSetUp
from behaviours.keys import RANGES_KEY
from behaviours.ports import OutputPort
from drivers.interfaces import PanTiltState, Robot
from perception.frame import Frame, LandmarkBearings
from perception.geometry import Pose2D
from perception.ranges import RangeScan


class _Sensor(BearingsBehaviour):
    def setup(self, **kwargs: Any) -> None:
        super().setup(**kwargs)
        self._robot: Robot | None = kwargs.get("robot", getattr(self, "_robot", None))

    @property
    def robot(self) -> Robot:
        robot = getattr(self, "_robot", None)
        if robot is None:
            raise NotSetUp(f"{self.name}: no robot; set the tree up with setup(robot=...)")
        return robot


class ReadOdometry(_Sensor):
    """Copy the base's odometry and stall flag to ``/robot``."""

    ODOMETRY = OutputPort("odometry", Pose2D, "/robot/odometry", doc="odometry pose of the base (drifts)")
    STALLED = OutputPort("stalled", bool, "/robot/stalled", doc="a wheel is stalled (collision)")
    PORTS = (ODOMETRY, STALLED)

    def update(self) -> Status:
        base = self.robot.base
        self.set_output(self.ODOMETRY, base.odometry())
        self.set_output(self.STALLED, bool(base.stalled()))  # a driver may answer with a numpy bool
        return Status.SUCCESS


class ReadPanTilt(_Sensor):
    """Copy the pan-tilt unit's state to ``/ptu/state`` (SUCCESS without doing anything if none)."""

    STATE = OutputPort("state", PanTiltState, "/ptu/state", doc="pan/tilt position and motion")
    PORTS = (STATE,)

    def update(self) -> Status:
        if self.robot.ptu is not None:
            self.set_output(self.STATE, self.robot.ptu.state())
        return Status.SUCCESS


class ReadRanges(_Sensor):
    """Copy the newest reading of the range sensors and bumpers to ``/robot/ranges``.

    Writes nothing when the robot has no range source, or before its first reading (a sonar
    ring that has not fired yet): readers take the key's absence as "no data".
    """

    RANGES = OutputPort("ranges", RangeScan, RANGES_KEY.path, doc=RANGES_KEY.doc)
    PORTS = (RANGES,)

    def update(self) -> Status:
        source = self.robot.ranges
        scan = source.read() if source is not None else None
        if scan is not None:
            self.set_output(self.RANGES, scan)
        return Status.SUCCESS


class GrabFrames(_Sensor):
    """Grab one frame per camera into ``/perception/frames``; the first camera's also into ``frame``.

    ``cameras`` limits grabbing to the named cameras (a mission's ``cameras:``), so unused
    cameras cost neither bandwidth nor, in the simulator, rendering. A dropped frame keeps the
    previous one (its stamp tells how old it is).
    """

    FRAMES = OutputPort("frames", dict, "/perception/frames", doc="latest frame of each camera, by camera name")
    FRAME: OutputPort[Frame | LandmarkBearings] = OutputPort("frame", Frame | LandmarkBearings, "/perception/frame",
                                                             doc="latest frame of the first camera")
    PORTS = (FRAMES, FRAME)

    def __init__(self, name: str | None = None, *, cameras: tuple[str, ...] | None = None) -> None:
        super().__init__(name=name)
        self.only = cameras

    def setup(self, **kwargs: Any) -> None:
        super().setup(**kwargs)
        robot = getattr(self, "_robot", None)
        if self.only is not None and robot is not None:
            missing = robot.missing_cameras(self.only)
            if missing:
                have = ", ".join(robot.cameras) or "none"
                raise KeyError(f"the robot has no camera {', '.join(missing)} (it has: {have})")

    def update(self) -> Status:
        cameras = self.robot.cameras
        if self.only is not None:
            cameras = {name: cameras[name] for name in self.only}
        if not cameras:
            return Status.SUCCESS
        try:
            frames = dict(self.bb.get(self.output_key(self.FRAMES)))  # what it wrote last tick
        except KeyError:
            frames = {}
        for name, camera in cameras.items():
            frame = camera.grab()
            if frame is not None:
                frames[name] = frame
        self.set_output(self.FRAMES, frames)
        primary = next(iter(cameras))
        if primary in frames:
            self.set_output(self.FRAME, frames[primary])
        return Status.SUCCESS


SENSE_NODES = (ReadOdometry, ReadRanges, ReadPanTilt, GrabFrames)
"""The runner's own data-gathering nodes, first in every tree."""
