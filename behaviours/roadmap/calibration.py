"""Calibrating the odometry's turns with the camera (``CalibrateTurns``, ``CorrectOdometry``).

Why: a target's pose relative to the reference, and every edge, is a trip measured by odometry
between two homed poses. A differential base whose odometry counts turns a few percent short
(the simulator's base: 2 %, a real one's wheel base is never exactly known) turns that into an
error of the trip's heading of 2 % of its net turn, up to 3.6 degrees for a target facing away
from the reference, and the target's position rotates with it about the reference: 0.2-0.35 m
for a target 6 m away, more than the rest of the errors together (measured in the lab: the
homing ends within 1.2 cm; the turn estimate of the planar essential matrix is good to 0.1 deg).

How: ``CalibrateTurns`` takes an image, turns a full circle on the spot by the raw odometry,
takes another and compares the two (planar essential matrix, :mod:`behaviours.roadmap.vision`):
the camera is back where it was, so the images differ by the turn odometry missed, measured to
about 0.1 degree; the scale ``true turn / counted turn`` goes to ``/robot/turn_scale``.
``CorrectOdometry`` (in a mission's ``sense:``) integrates the base's odometry with its turns
scaled by that factor into ``/robot/calibrated_odometry``, which the roadmap nodes of the
library missions read instead of the raw odometry. The learned edges are then in calibrated
units, so ``goto_target`` calibrates too before it replays them.

Distances are not calibrated (1 % in the simulator: 6 cm over 6 m, along the trip).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.motion import ODOMETRY
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.roadmap.routine import ROUTINE_PORTS, Failed, RoutineBehaviour, Step
from behaviours.roadmap.vision import compare, describe
from behaviours.telemetry import Figure
from perception.geometry import Pose2D, wrap_angle

MAX_ERROR = 0.1  # a scale further than 10 % from 1 is not odometry miscounting: refuse it
ATTEMPTS = 4  # headings 90 degrees apart to try when the images do not match


@register
class CalibrateTurns(RoutineBehaviour):
    """Turn a full circle on the spot and compare the images before and after: the odometry's turn scale.

    Writes ``true turn / counted turn`` to ``turn_scale`` (read by ``CorrectOdometry``). Where the
    two images do not match (a bare wall), it faces another way, a quarter turn on, and tries again,
    up to four headings; matched on another, it turns back to the heading it started at (by the scale
    just measured), so that what follows (the room estimation's dodecagon, laid out to the robot's
    left) starts where the robot was put down. FAILURE when no heading matches or the scale is
    implausible (more than 10 % from 1).
    """

    TURN_SCALE = OutputPort("turn_scale", float, "/robot/turn_scale", doc="true turn / turn counted by the odometry")
    PORTS = (*ROUTINE_PORTS, TURN_SCALE)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.scale: float | None = None

    def routine(self) -> Step[None]:
        inliers = 0
        for attempt in range(ATTEMPTS):
            if attempt:  # too little to see this way (a bare wall): another heading
                yield from self.rotate(math.pi / 2.0, "facing another way")
            before, _ = yield from self.capture()
            features = describe(before.image)
            yield from self.rotate(2.0 * math.pi, "turning a full circle")
            after, _ = yield from self.capture()
            found = compare(describe(after.image), after.camera, features, before.camera)
            inliers = max(inliers, found.inliers)
            if found.matched():
                # planar.theta: the turn from the image after to the one before, i.e. minus what odometry missed
                scale = 1.0 - found.planar.theta / (2.0 * math.pi)
                yield from self._write(scale)
                if attempt:  # back to the heading it started at: what follows is laid out from there
                    counted = attempt * (math.pi / 2.0 + 2.0 * math.pi) + 2.0 * math.pi  # the odometry's turns
                    yield from self.rotate(-wrap_angle(scale * counted) / scale, "facing the start heading again")
                return
        raise Failed(f"the images before and after a full turn never matched ({inliers} inliers at best)")

    def _write(self, scale: float) -> Step[None]:
        if abs(scale - 1.0) > MAX_ERROR:
            raise Failed(f"implausible turn scale {scale:.3f}")
        self.scale = scale
        self.set_output(self.TURN_SCALE, scale)
        self.feedback_message = f"turn scale {scale:.4f}: the odometry counts {100 * (1 / scale - 1):+.2f} % of a turn"
        yield

    def figures(self) -> Iterator[Figure]:
        if self.scale is not None:
            yield Figure("roadmap", "turn_scale", round(self.scale, 5))


@register
class CorrectOdometry(BearingsBehaviour):
    """Integrate the base's odometry with its turns scaled by ``turn_scale`` (before calibration: 1).

    Belongs under the mission's ``sense:``: it must see every odometry reading.
    """

    TURN_SCALE = InputPort("turn_scale", float, Ref("/robot/turn_scale"), doc="true turn / counted turn (unset: 1)")
    CALIBRATED = OutputPort("calibrated", Pose2D, "/robot/calibrated_odometry", doc="odometry with calibrated turns")
    PORTS = (ODOMETRY, TURN_SCALE, CALIBRATED)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.raw: Pose2D | None = None
        self.pose = Pose2D()

    def update(self) -> Status:
        raw = self.get_input(ODOMETRY, None)
        if raw is None:
            return Status.SUCCESS
        if self.raw is not None:
            step = raw.relative_to(self.raw)  # this tick's motion in the robot frame
            scale = self.get_input(self.TURN_SCALE, 1.0) or 1.0
            self.pose = self.pose.compose(Pose2D(step.x, step.y, scale * step.theta))
        else:
            self.pose = Pose2D(raw.x, raw.y, raw.theta)
        self.raw = raw
        self.pose = Pose2D(self.pose.x, self.pose.y, self.pose.theta, raw.stamp)
        self.set_output(self.CALIBRATED, self.pose)
        return Status.SUCCESS
