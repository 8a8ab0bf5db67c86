"""Fake drivers for tests: they record what they are told and report what the test sets."""

from __future__ import annotations

from dataclasses import dataclass, field

from drivers.interfaces import PanTiltState, Robot
from perception.frame import Frame
from perception.geometry import Pose2D


@dataclass
class FakeBase:
    """A base that records every drive() call; odometry and stall are set by the test."""

    pose: Pose2D = field(default_factory=Pose2D)
    is_stalled: bool = False
    commands: list[tuple[float, float]] = field(default_factory=list)
    closed: bool = False
    fail_on_odometry: Exception | None = None

    def drive(self, v: float, w: float) -> None:
        self.commands.append((float(v), float(w)))

    def stop(self) -> None:
        self.drive(0.0, 0.0)

    def odometry(self) -> Pose2D:
        if self.fail_on_odometry is not None:
            raise self.fail_on_odometry
        return self.pose

    def stalled(self) -> bool:
        return self.is_stalled

    def close(self) -> None:
        self.closed = True


@dataclass
class FakePanTilt:
    """A pan-tilt unit that jumps to its target at once and records the calls."""

    current: PanTiltState = field(default_factory=PanTiltState)
    moves: list[tuple[float, float, float]] = field(default_factory=list)
    halts: int = 0
    closed: bool = False

    def move(self, pan: float, tilt: float, speed: float) -> None:
        self.moves.append((pan, tilt, speed))
        self.current = PanTiltState(pan, tilt, False, self.current.stamp)

    def halt(self) -> None:
        self.halts += 1

    def state(self) -> PanTiltState:
        return self.current

    def close(self) -> None:
        self.closed = True


@dataclass
class FakeCamera:
    """A camera that returns the frames queued by the test, then None (dropped frames)."""

    name: str = "camera"
    frames: list[Frame] = field(default_factory=list)
    closed: bool = False

    def grab(self) -> Frame | None:
        return self.frames.pop(0) if self.frames else None

    def close(self) -> None:
        self.closed = True


def fake_robot(*, ptu: bool = False, cameras: tuple[str, ...] = ()) -> Robot:
    """A Robot of fakes."""
    return Robot(
        base=FakeBase(),
        ptu=FakePanTilt() if ptu else None,
        cameras={name: FakeCamera(name=name) for name in cameras},
        name="fake",
    )


@dataclass
class FakeKeys:
    """A keyboard for tests: each ``read()`` returns the next batch the test queued (then none)."""

    batches: list[list[str]] = field(default_factory=list)
    closed: bool = False

    def read(self) -> list[str]:
        return self.batches.pop(0) if self.batches else []

    def close(self) -> None:
        self.closed = True
