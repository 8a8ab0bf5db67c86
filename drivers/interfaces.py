"""The interfaces every driver implements, and the values that cross them.

Real hardware (Pioneer over ARCOS, PTU-D46) and the simulator implement the same protocols, so a
mission cannot tell them apart. Units are SI: metres, seconds, radians.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

from perception.frame import Frame, LandmarkBearings
from perception.geometry import Pose2D
from perception.ranges import RangeScan


@dataclass(frozen=True, slots=True)
class VelocityCommand:
    """A body-frame velocity request: ``v`` forward (m/s), ``w`` counter-clockwise (rad/s).

    ``reach``: how far (m) the node that asks means to go along this arc before it stops at its
    goal (``inf``: no goal in sight). Bases ignore it; the avoidance judges a wish no farther
    (``behaviours.avoidance``). Not part of equality: two requests of the same velocity are equal."""

    v: float = 0.0
    w: float = 0.0
    reach: float = field(default=math.inf, compare=False)

    @property
    def is_zero(self) -> bool:
        return self.v == 0.0 and self.w == 0.0


STOP = VelocityCommand(0.0, 0.0)


@dataclass(frozen=True, slots=True)
class PanTiltLimits:
    """What a pan-tilt unit reports it can do: the position range of each axis (rad), the size of
    one position step (rad; 0: continuous) and the slew speeds it takes (rad/s).

    A PTU-D46 reports +-3090 positions of 185.1428 arc-seconds (+-158.91 deg), not the +-159 deg of
    its data sheet: head behaviours clip their targets into what the unit reports (:meth:`clip`).
    """

    pan: tuple[float, float]
    tilt: tuple[float, float]
    pan_step: float = 0.0
    tilt_step: float = 0.0
    max_speed: float = math.inf
    min_speed: float = 0.0

    def clip(self, pan: float, tilt: float) -> tuple[float, float]:
        """``(pan, tilt)`` clipped into the ranges and rounded to the nearest position step (inside)."""
        return _snap(pan, self.pan, self.pan_step), _snap(tilt, self.tilt, self.tilt_step)

    def clip_speed(self, speed: float) -> float:
        """A slew speed the unit takes."""
        return min(max(speed, self.min_speed), self.max_speed)


def _snap(angle: float, bounds: tuple[float, float], step: float) -> float:
    low, high = bounds
    value = min(max(angle, low), high)
    if step > 0.0:
        value = round(value / step) * step
        value = min(max(value, math.ceil(low / step - 1e-9) * step), math.floor(high / step + 1e-9) * step)
    return value


@dataclass(frozen=True, slots=True)
class PanTiltState:
    """Where the pan-tilt unit points (rad), whether it is still moving, what it can do (``limits``;
    None when the driver does not say) and how many times it has re-homed since it was opened
    (``homings``: a unit that resets after a power dip finds its limits and stands at home)."""

    pan: float = 0.0
    tilt: float = 0.0
    moving: bool = False
    stamp: float = 0.0
    limits: PanTiltLimits | None = None
    homings: int = 0


@dataclass(frozen=True, slots=True)
class PanTiltCommand:
    """Absolute pan/tilt target (rad) and the slew speed (rad/s) to reach it with."""

    pan: float
    tilt: float
    speed: float = 1.0


@runtime_checkable
class Base(Protocol):
    """A differential-drive base."""

    def drive(self, v: float, w: float) -> None:
        """Request forward speed ``v`` (m/s) and turn rate ``w`` (rad/s) until the next call."""

    def stop(self) -> None:
        """Bring the base to rest now; must be safe to call at any time, repeatedly."""

    def odometry(self) -> Pose2D:
        """The latest odometry pose in the odometry frame (drifts; never ground truth)."""

    def stalled(self) -> bool:
        """True while a wheel is stalled (collision, obstacle)."""

    def close(self) -> None:
        """Release the device; the base must be stopped before."""


@runtime_checkable
class PanTilt(Protocol):
    """A pan-tilt unit carrying cameras."""

    def move(self, pan: float, tilt: float, speed: float) -> None:
        """Start moving to an absolute pan/tilt (rad) at ``speed`` (rad/s); returns at once."""

    def halt(self) -> None:
        """Stop moving where it is."""

    def state(self) -> PanTiltState:
        """Current position and motion flag."""

    def close(self) -> None:
        """Release the device."""


@runtime_checkable
class Camera(Protocol):
    """A camera (or rectified stereo pair) that yields frames."""

    name: str

    def grab(self) -> Frame | LandmarkBearings | None:
        """The newest frame (identified bearings from an ideal sensor), or None when the camera dropped it."""

    def close(self) -> None:
        """Release the device."""


@runtime_checkable
class RangeSource(Protocol):
    """Range sensors and bumpers around the base (a sonar ring, the simulator's model of one)."""

    def read(self) -> RangeScan | None:
        """The newest reading of every sensor and bumper, or None before the first."""

    def close(self) -> None:
        """Release the device."""


@runtime_checkable
class KeySource(Protocol):
    """Keys typed by an operator (teleoperation); ``read`` never blocks."""

    def read(self) -> list[str]:
        """The keys typed since the last call, oldest first (possibly none): ``up``, ``space``, ``q``, ..."""

    def close(self) -> None:
        """Give the input back (restore the terminal)."""


KeyboardOpener = Callable[[], KeySource]
"""Opens the operator's keyboard when a node first needs it (OSError: there is none). The runner
hands one to the tree at setup (``setup(keyboard=...)``), so nothing is opened unless a node that
drives by keys runs."""


@dataclass
class Robot:
    """The set of drivers one mission runs with, built by the runner from a profile."""

    base: Base
    ptu: PanTilt | None = None
    cameras: dict[str, Camera] = field(default_factory=dict)
    ranges: RangeSource | None = None
    name: str = "robot"

    def missing_cameras(self, names: Iterable[str]) -> list[str]:
        """The names among ``names`` that are not cameras of this robot."""
        return [name for name in names if name not in self.cameras]

    def stop_all(self) -> None:
        """Command every actuator to rest; never raises so it can run on any error path."""
        for stop in (self.base.stop, self.ptu.halt if self.ptu is not None else None):
            if stop is None:
                continue
            with contextlib.suppress(Exception):  # safety path: try every actuator regardless
                stop()

    def close(self) -> None:
        """Stop, then release every device (cameras, range sensors, pan-tilt, base last)."""
        self.stop_all()
        devices = [*self.cameras.values(), self.ranges, self.ptu, self.base]
        for device in devices:
            if device is None:
                continue
            with contextlib.suppress(Exception):  # keep closing the others
                device.close()
