"""An ideal robot in a simulated world, for testing roadmap behaviours alone with BehaviourHarness.

The harness owns the blackboard and the manual clock; :meth:`FakeWorld.step` (the harness's
``between``) plays the drivers and the data-gathering branch: it moves the odometry exactly as
commanded (no slip: odometry is the truth, in the frame of ``start``), refuses a move into an
obstacle (the stall flag, as the simulator does), refuses without a stall a move that ``hold``
names (the collision monitor stopping the robot before something it senses), levels the pan-tilt
head at once when told, and while the robot is at rest writes the images its cameras see,
rendered by the simulator at the true pose. Rendering only at rest keeps tests fast: a behaviour
takes images at rest anyway.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

from behaviours.roadmap.values import TargetImages, TargetView
from behaviours.roadmap.vision import describe
from behaviours.testing import BehaviourHarness
from drivers.interfaces import STOP, PanTiltCommand, PanTiltState
from drivers.sim.simulation import Simulation
from perception.frame import Frame
from perception.geometry import Pose2D, wrap_angle


class FakeWorld:
    """Odometry, stall flag, pan-tilt state and camera frames for one behaviour under test."""

    def __init__(self, world: str = "lab", start: Pose2D | None = None, cameras: tuple[str, ...] = ("front",),
                 *, pan: float = 0.0, turn_gain: float = 1.0,
                 hold: Callable[[Pose2D, Pose2D], bool] | None = None) -> None:
        self.sim = Simulation.load(world, seed=0, noise=False)
        self.start = start if start is not None else Pose2D(2.0, 2.0, 0.0)
        self.cameras = cameras
        self.turn_gain = turn_gain  # true turn / turn the odometry counts (1: odometry is the truth)
        self.hold = hold  # (true pose, next true pose) -> the move is refused without a stall (a monitor's stop)
        self.odometry = Pose2D()
        self.true = self.start
        self.head = PanTiltState(pan, 0.0, False)
        self.radius = self.sim.world.robot_radius
        self.contacts = 0
        self.renders = 0

    def true_pose(self) -> Pose2D:
        return self.true

    def blackboard(self, **extra: Any) -> dict[str, Any]:
        """The sensed keys at the start (plus ``extra``, keys with '/' written as '__')."""
        values: dict[str, Any] = {"/robot/odometry": self.odometry, "/robot/stalled": False, "/ptu/state": self.head}
        values.update({k.replace("__", "/"): v for k, v in extra.items()})
        return values

    def frames_now(self, stamp: float) -> dict[str, Frame]:
        """What the cameras see from the true pose, stamped ``stamp``."""
        self.renders += 1
        pose = self.true_pose()
        return {name: dataclasses.replace(self.sim.snapshot(pose, name, pan=self.head.pan, tilt=self.head.tilt),
                                          stamp=stamp) for name in self.cameras}

    def step(self, harness: BehaviourHarness, dt: float = 0.1) -> None:
        """One tick of the world after the behaviour ticked (use as ``tick_until(between=world.step)``)."""
        command = harness.read("/robot/command") or STOP
        head = harness.read("/ptu/command")
        if isinstance(head, PanTiltCommand):
            self.head = PanTiltState(head.pan, head.tilt, False)
        pose, here = self.odometry, self.true
        moved = _step(pose, command.v, command.w, dt)
        true = _step(here, command.v, command.w * self.turn_gain, dt)
        clearance = self.sim.scene.clearance(true.x, true.y)  # the simulator's rule: no closer once touching
        blocked = clearance < self.radius and clearance < self.sim.scene.clearance(here.x, here.y) - 1e-12
        stalled = blocked
        if blocked:
            self.contacts += 1
            moved, true = pose, here
        elif self.hold is not None and self.hold(here, true):
            moved, true = pose, here
        self.true = true
        at_rest = (moved.x, moved.y, moved.theta) == (pose.x, pose.y, pose.theta)
        self.odometry = Pose2D(moved.x, moved.y, moved.theta, harness.clock.now() + dt)
        harness.write("/robot/odometry", self.odometry)
        harness.write("/robot/stalled", stalled)
        harness.write("/ptu/state", self.head)
        if at_rest:
            harness.write("/perception/frames", self.frames_now(harness.clock.now() + dt))


def _step(pose: Pose2D, v: float, w: float, dt: float) -> Pose2D:
    return Pose2D(pose.x + v * dt * math.cos(pose.theta), pose.y + v * dt * math.sin(pose.theta),
                  wrap_angle(pose.theta + w * dt))


def error_to(world: FakeWorld, truth: Pose2D) -> tuple[float, float]:
    """(m, deg) between the robot's true pose and ``truth``."""
    pose = world.true_pose()
    return pose.distance_to(truth), abs(math.degrees(wrap_angle(pose.theta - truth.theta)))


def target_images(world: FakeWorld, poses: dict[str, Pose2D], camera: str = "front") -> TargetImages:
    """Target images taken by ``camera`` at true poses, as ``LoadTargetImages`` would describe them."""
    views = []
    for name, pose in poses.items():
        image = world.sim.snapshot(pose, camera, pan=0.0, tilt=0.0).image
        views.append(TargetView(name, image, describe(image), None, f"{name}.png"))
    return TargetImages(tuple(views))


def rope(x: float, y: float, half_width: float = 0.05) -> Callable[[Pose2D, Pose2D], bool]:
    """A ``hold`` that refuses every move of the robot's centre across the line y = ``y`` within
    ``half_width`` of ``x``: something only a drive along x = ``x`` meets, the monitor holding the
    robot before it."""
    def crosses(here: Pose2D, there: Pose2D) -> bool:
        return (here.y - y) * (there.y - y) <= 0.0 and here.y != there.y and abs(here.x - x) < half_width
    return crosses
