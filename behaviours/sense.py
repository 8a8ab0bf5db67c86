"""The data-gathering branch: driver readings onto the blackboard, once per tick.

These are the only behaviours that touch a driver, and only through the interfaces of the
:class:`~drivers.interfaces.Robot` handed to the tree at setup (``setup(robot=...)``). They are
the single writers of the ``sense`` keys of :mod:`behaviours.keys`.
"""

from __future__ import annotations

from typing import Any

from py_trees.common import Status

from behaviours.base import BearingsBehaviour, NotSetUp
from behaviours.registry import register
from drivers.interfaces import Robot


class _Sensor(BearingsBehaviour):
    def setup(self, **kwargs: Any) -> None:
        super().setup(**kwargs)
        self._robot: Robot | None = kwargs.get("robot", getattr(self, "_robot", None))

    @property
    def robot(self) -> Robot:
        if getattr(self, "_robot", None) is None:
            raise NotSetUp(f"{self.name}: no robot; set the tree up with setup(robot=...)")
        return self._robot


@register
class ReadOdometry(_Sensor):
    """Copy the base's odometry and stall flag to ``/robot``."""

    WRITES = ("/robot/odometry", "/robot/stalled")

    def update(self) -> Status:
        base = self.robot.base
        self.write("/robot/odometry", base.odometry())
        self.write("/robot/stalled", bool(base.stalled()))
        return Status.SUCCESS


@register
class ReadPanTilt(_Sensor):
    """Copy the pan-tilt unit's state to ``/ptu/state`` (SUCCESS without doing anything if none)."""

    WRITES = ("/ptu/state",)

    def update(self) -> Status:
        if self.robot.ptu is not None:
            self.write("/ptu/state", self.robot.ptu.state())
        return Status.SUCCESS


@register
class GrabFrames(_Sensor):
    """Grab one frame per camera into ``/perception/frames``; the first camera's also into ``frame``.

    ``cameras`` limits grabbing to the named cameras (a mission's ``cameras:``), so unused
    cameras cost neither bandwidth nor, in the simulator, rendering. A dropped frame keeps the
    previous one (its stamp tells how old it is).
    """

    WRITES = ("/perception/frames", "/perception/frame")

    def __init__(self, name: str | None = None, *, cameras: tuple[str, ...] | None = None) -> None:
        super().__init__(name=name)
        self.only = cameras

    def setup(self, **kwargs: Any) -> None:
        super().setup(**kwargs)
        if self.only is not None and getattr(self, "_robot", None) is not None:
            missing = self._robot.missing_cameras(self.only)
            if missing:
                have = ", ".join(self._robot.cameras) or "none"
                raise KeyError(f"the robot has no camera {', '.join(missing)} (it has: {have})")

    def update(self) -> Status:
        cameras = self.robot.cameras
        if self.only is not None:
            cameras = {name: cameras[name] for name in self.only}
        if not cameras:
            return Status.SUCCESS
        frames = dict(self.read("/perception/frames") or {})
        for name, camera in cameras.items():
            frame = camera.grab()
            if frame is not None:
                frames[name] = frame
        self.write("/perception/frames", frames)
        primary = next(iter(cameras))
        if primary in frames:
            self.write("/perception/frame", frames[primary])
        return Status.SUCCESS
