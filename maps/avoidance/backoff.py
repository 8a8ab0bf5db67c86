"""Backing away along the robot's own trail when no direction will do.

A robot that has driven into a corner (a desk beside it, a person ahead and another to the side)
can find every direction of the histogram (:mod:`maps.avoidance.directions`, +-``spread`` of the
heading) blocked within a few centimetres, and turning on the spot changes nothing: it stands
there until the avoidance gives up, and again after every recovery, since no command moves it.
Mobile robots back away then (Nav2's ``BackUp`` recovery, ARIA's actions): here, along the way
the robot came, which it has just driven and so knows to have been free.

- The **trail**: the odometry positions of the last ``keep`` metres driven forwards, one every
  :data:`STEP` (:class:`Trail`). Backing does not add to it: a back-off uses the trail up, so the
  next one goes farther back, not forwards again.
- The **target**: the first trail point, walking back from the newest, at least ``distance``
  from the robot (the oldest when the trail is shorter; none nearer than :data:`MIN_BACK`: no
  trail, no back-off).
- The **command** (eq. 7): backwards at ``speed`` along the arc through the target,

  κ = 2 y / (x² + y²),  v = −speed,  w = v κ, clipped to ±``turn_rate``,

  the target at (x, y) in the base frame (behind: x < 0; a target not behind is backed to
  straight). The arc is taken only while the footprint, grown by the margin, goes along it
  backwards for the braking distance and horizon of the back-off's speed (eq. 1) before it
  touches a sensed point; else straight back, judged the same way; else none (held). The
  collision monitor judges the command as it judges every other.

Pure: no clock, no I/O; :class:`maps.avoidance.detour.Avoidance` decides when to back away.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maps.avoidance.sweep import AvoidSettings, Surroundings, needed_distance
from perception.geometry import Pose2D, parent_to_frame

STEP = 0.02  # m between the trail's points
MIN_BACK = 0.10  # m: a trail whose farthest point is nearer than this gives no back-off


@dataclass(frozen=True, slots=True)
class BackoffSettings:
    """How far and how fast the robot backs away, and how much trail it keeps."""

    distance: float = 0.4  # m backed per back-off (0: never back away)
    speed: float = 0.1  # m/s backwards
    keep: float = 2.0  # m of trail kept


@dataclass(frozen=True, slots=True)
class Trail:
    """Odometry positions of the last ``keep`` metres driven, oldest first (module docstring)."""

    points: tuple[tuple[float, float], ...] = ()
    keep: float = 2.0

    def added(self, pose: Pose2D) -> Trail:
        """With ``pose`` appended when it lies :data:`STEP` or more from the newest point; the
        oldest points beyond ``keep`` metres of path dropped."""
        if self.points and math.hypot(pose.x - self.points[-1][0], pose.y - self.points[-1][1]) < STEP:
            return self
        points = [*self.points, (pose.x, pose.y)]
        length, first = 0.0, 0
        for i in range(len(points) - 1, 0, -1):
            length += math.hypot(points[i][0] - points[i - 1][0], points[i][1] - points[i - 1][1])
            if length > self.keep:
                first = i
                break
        return Trail(tuple(points[first:]), self.keep)

    def target(self, pose: Pose2D, distance: float) -> tuple[tuple[float, float] | None, Trail]:
        """The point to back to (odometry), and the trail left once the robot is there (up to and
        with it); ``None`` when no trail point lies :data:`MIN_BACK` or more away."""
        nearer: tuple[float, float] | None = None  # the last point walked, and how far it lies
        gap = 0.0
        for i in range(len(self.points) - 1, -1, -1):
            (x, y), previous = self.points[i], gap
            gap = math.hypot(x - pose.x, y - pose.y)
            if gap >= distance:  # between this point and the nearer one: as far as asked
                f = 1.0 if nearer is None else (distance - previous) / (gap - previous)
                ex, ey = (x, y) if nearer is None else nearer
                point = (ex + f * (x - ex), ey + f * (y - ey))
                return point, Trail((*self.points[:i if nearer is None else i + 1], point), self.keep)
            nearer = (x, y)
        if gap < MIN_BACK:
            return None, self
        return self.points[0], Trail(self.points[:1], self.keep)


def back_command(target: tuple[float, float], pose: Pose2D, around: Surroundings, avoid: AvoidSettings,
                 settings: BackoffSettings) -> tuple[float, float] | None:
    """The command backing towards ``target`` (odometry) from ``pose`` (eq. 7), or straight back when
    that arc is not free, or ``None`` when neither is (module docstring)."""
    x, y = (float(c) for c in parent_to_frame(pose, np.array([target]))[0])
    v = -settings.speed
    w = 0.0
    if x < 0.0:
        w = float(np.clip(v * 2.0 * y / (x * x + y * y), -avoid.turn_rate, avoid.turn_rate))  # eq. 7
    need = needed_distance(settings.speed, avoid)  # eq. 1, for the back-off's speed
    for command in ((v, w), (v, 0.0)):
        if around.free(*command) >= need:
            return command
    return None

