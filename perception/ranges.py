"""Range readings around the base: where each range sensor sits, what it measured, the bumpers.

One value for the robot and the simulator alike: the Pioneer driver fills it from the SIP's sonar
readings and bumper bits with the ring's geometry of the robot's model, the simulator from its
model of the same ring. The runner's sensing branch writes it to ``/robot/ranges`` every tick;
the collision monitor (between the tree's command and the base) and the behaviours that get
around obstacles read it. Everything is in the base frame (REP-103: x forward, y left), metres
and radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from perception.geometry import wrap_angles


@dataclass(frozen=True, slots=True)
class RangeSensor:
    """One range sensor's mounting on the base and its cone (a sonar transducer, an IR sensor)."""

    x: float
    y: float
    heading: float  # rad, counter-clockwise from the base's +x
    fov: float = math.radians(30.0)  # rad, the whole cone
    max_range: float = 5.0  # m: farther echoes are not reported
    min_range: float = 0.1  # m: nearer objects read as this (the transducer's ringing)


@dataclass(frozen=True, slots=True)
class Bumper:
    """One bumper segment: where it touches (base frame) and which way it faces (+1 front, -1 rear)."""

    x: float
    y: float
    facing: int


@dataclass(frozen=True, slots=True)
class RangeScan:
    """One reading of every range sensor and bumper, stamped on the tree's clock.

    ``ranges[i]`` is sensor ``i``'s range in metres: ``inf`` when it heard no echo within its
    ``max_range``, ``nan`` when it has not read yet (a sonar ring fires in turn). ``pressed[j]`` is
    bumper ``j``. ``extra`` holds obstacle points from other sources (stereo depth), base frame.
    ``fired[i]`` is when sensor ``i`` took its reading, on the same clock (a ring fires in turn, so
    a reading can be up to a ring's cycle older than ``stamp``); None: every reading at ``stamp``.
    """

    sensors: tuple[RangeSensor, ...]
    ranges: np.ndarray
    stamp: float
    bumpers: tuple[Bumper, ...] = ()
    pressed: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    extra: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    fired: np.ndarray | None = None

    def __post_init__(self) -> None:
        if len(self.ranges) != len(self.sensors):
            raise ValueError(f"{len(self.ranges)} ranges for {len(self.sensors)} sensors")
        if self.fired is not None and len(self.fired) != len(self.sensors):
            raise ValueError(f"{len(self.fired)} firing times for {len(self.sensors)} sensors")
        if len(self.pressed) != len(self.bumpers):
            raise ValueError(f"{len(self.pressed)} bumper states for {len(self.bumpers)} bumpers")

    def points(self) -> np.ndarray:
        """Every echo (each sensor's range along its axis) and every extra point, base frame (N x 2)."""
        ranges = np.asarray(self.ranges, dtype=float)
        echo = np.isfinite(ranges)
        if not echo.any() or not self.sensors:
            return np.asarray(self.extra, dtype=float).reshape(-1, 2)
        x, y, heading = (np.array([getattr(s, a) for s in self.sensors]) for a in ("x", "y", "heading"))
        r = ranges[echo]
        echoes = np.column_stack((x[echo] + r * np.cos(heading[echo]), y[echo] + r * np.sin(heading[echo])))
        return np.vstack((echoes, np.asarray(self.extra, dtype=float).reshape(-1, 2)))

    def covers(self, points: np.ndarray) -> np.ndarray:
        """Which ``points`` (base frame, N x 2) lie inside the cone of a sensor that has a reading
        (within its ``max_range``): where this scan's own readings say what is there. The rest lie
        in the ring's blind gaps (or beyond its reach)."""
        points = np.asarray(points, dtype=float).reshape(-1, 2)
        covered = np.zeros(len(points), dtype=bool)
        for sensor, reading in zip(self.sensors, np.asarray(self.ranges, dtype=float), strict=True):
            if np.isnan(reading):
                continue
            dx, dy = points[:, 0] - sensor.x, points[:, 1] - sensor.y
            off = np.abs(wrap_angles(np.arctan2(dy, dx) - sensor.heading))
            covered |= (off <= sensor.fov / 2.0) & (np.hypot(dx, dy) <= sensor.max_range)
        return covered

    def fired_at(self) -> np.ndarray:
        """When each sensor took its reading (``stamp`` where the source does not say)."""
        if self.fired is None:
            return np.full(len(self.sensors), self.stamp)
        return np.asarray(self.fired, dtype=float)

    def bumped(self, facing: int) -> bool:
        """Is any bumper facing ``facing`` (+1 front, -1 rear) pressed?"""
        return any(p and b.facing == facing for b, p in zip(self.bumpers, self.pressed, strict=True))
