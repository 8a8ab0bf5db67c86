"""What is free around the base: how far the footprint can go along an arc or in a direction.

Given obstacle points around the base (sonar echoes, base frame), this module says

- how far a motion node commanding ``(v, w)`` means to go at least: its braking distance plus
  ``v`` times a short ``horizon`` (eq. 1, :func:`needed_distance`). A node that ramps its speed
  down as ``sqrt(2 a d)`` before its goal (``behaviours.motion.ramp``) asks, with ``decel`` equal
  to ``a``, for ``d`` plus the horizon's travel; a node that says where its goal is (the
  command's ``reach``) is judged no farther (:meth:`Surroundings.open` with ``goal``): an
  obstacle beyond its goal does not block it;
- how far the footprint, grown by a margin, travels along the arc ``(v, w)`` before it touches a
  point (:meth:`Surroundings.free`: the exact sweep of
  :func:`perception.arc_sweep.contact_times`, times the speed), and how far straight in a
  direction ``psi`` once it has turned on the spot to face it (:meth:`Surroundings.free_towards`:
  the same sweep with the points turned by ``-psi``);
- whether a motion grazes a point already nearer the footprint than the clearance within the
  collision monitor's sweep (:meth:`Surroundings.grazes`): the monitor would stop it, however far
  along the point is;
- whether turning on the spot to a direction sweeps a point (:meth:`Surroundings.turns`; a disc
  never does).

The margin is the clearance, or half the nearest gap when something is already nearer than that
(a doorway's jamb, a person just passed), so a robot close to something can still move along or
away from it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import overload

import numpy as np

from perception.arc_sweep import contact_times
from perception.collision_monitor import SWEEP_LENGTH
from perception.geometry import Pose2D
from perception.polygons import distance, grow


@dataclass(frozen=True, slots=True)
class AvoidSettings:
    """The robot's footprint, what it keeps clear and how a detour moves."""

    footprint: np.ndarray  # convex, counter-clockwise, base frame (m)
    clearance: float = 0.10  # m kept between the footprint and every point along a motion
    horizon: float = 0.5  # s of travel that must be free beyond the braking distance (eq. 1)
    decel: float = 0.25  # m/s^2: the braking the distance is computed with
    speed: float = 0.2  # m/s on a detour
    turn_rate: float = math.radians(45.0)  # rad/s on a detour
    spread: float = math.radians(120.0)  # rad: the directions judged reach this far to each side
    directions: int = 25  # directions judged, evenly spaced (odd: straight ahead is one)
    turn_first: float = math.radians(30.0)  # rad: a direction farther off the heading is turned to on the spot
    steer_time: float = 1.0  # s: a wish's turn rate times this is where it heads; a detour turns in this
    max_stray: float = 1.5  # m a detour may stray from the line it started on (eq. 3)


def needed_distance(v: float, settings: AvoidSettings) -> float:
    """How far (m) a command of forward speed ``v`` means to go at least (0 for ``v <= 0``)."""
    v = max(v, 0.0)
    return v * v / (2.0 * settings.decel) + v * settings.horizon  # eq. 1


def margin(footprint: np.ndarray, points: np.ndarray, clearance: float) -> float:
    """The margin motions are checked with: ``clearance``, or half the nearest gap when that is smaller."""
    if len(points) == 0:
        return clearance
    return float(min(clearance, 0.5 * float(distance(footprint, points).min())))


def free_distance(footprint: np.ndarray, points: np.ndarray, v: float, w: float) -> float:
    """Metres ``footprint`` travels along the arc ``(v, w)``, forwards or backwards (``v != 0``),
    before it touches a point (``inf``: never within a turn)."""
    if len(points) == 0:
        return math.inf
    return float(abs(v) * contact_times(footprint, points, v, w).min())


@dataclass(frozen=True, slots=True)
class Surroundings:
    """The points around the base (base frame) as motions are judged against them: the footprint
    grown by the margin, and the points already nearer the footprint than the clearance."""

    footprint: np.ndarray
    points: np.ndarray
    grown: np.ndarray
    near: np.ndarray
    turn_limits: tuple[float, float] = (math.inf, math.inf)  # rad the footprint turns right, left before a touch
    margin: float = 0.0  # m the footprint was grown by

    @classmethod
    def of(cls, points: np.ndarray, settings: AvoidSettings) -> Surroundings:
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        gaps = distance(settings.footprint, pts)
        kept = margin(settings.footprint, pts, settings.clearance)
        grown = grow(settings.footprint, kept)
        limits = (math.inf, math.inf)
        if len(pts):  # at 1 rad/s the contact time is the angle
            limits = (float(contact_times(settings.footprint, pts, 0.0, -1.0).min()),
                      float(contact_times(settings.footprint, pts, 0.0, 1.0).min()))
        return cls(settings.footprint, pts, grown, pts[gaps < settings.clearance], limits, kept)

    def free(self, v: float, w: float) -> float:
        """Metres the grown footprint goes along the arc ``(v, w)`` before it touches a point."""
        return free_distance(self.grown, self.points, v, w)

    def grazes(self, v: float, w: float, within: float = SWEEP_LENGTH) -> bool:
        """Does the footprint itself reach a point already within the clearance, within the collision
        monitor's sweep (:data:`perception.collision_monitor.SWEEP_LENGTH`), or ``within`` metres when
        that is shorter (a motion's goal)? The monitor stops such a command, however far off the point
        is along the arc."""
        return len(self.near) > 0 and free_distance(self.footprint, self.near, v, w) <= min(within, SWEEP_LENGTH)

    def open(self, v: float, w: float, needed: float, goal: float = math.inf) -> bool:
        """Is the arc free for ``needed`` metres, grazing nothing? With a ``goal`` metres on, where the
        motion ends, no farther: the footprint must not touch a point before the goal, and grown by
        the margin it must be free up to the margin short of it, so the clearance is kept along the
        way and the goal itself may lie nearer a point than that (a target taken beside a desk); a
        point beyond the goal counts for nothing, not even within the clearance (the monitor's stop,
        should it come, holds the motion all the same)."""
        if needed <= goal - self.margin:
            return self.free(v, w) >= needed and not self.grazes(v, w, goal)
        return free_distance(self.footprint, self.points, v, w) >= min(needed, goal) and \
            self.free(v, w) >= goal - self.margin

    def free_towards(self, psis: np.ndarray) -> np.ndarray:
        """Metres the grown footprint goes straight in each direction ``psis`` (rad from the heading,
        left positive) once turned to face it; 0 where that grazes a point already within the
        clearance. One sweep for all directions: the points turned by each, stacked."""
        psis = np.asarray(psis, dtype=float)
        if len(self.points) == 0:
            return np.full(len(psis), math.inf)
        free = _straight(self.grown, self.points, psis)
        if len(self.near):
            free[_straight(self.footprint, self.near, psis) <= SWEEP_LENGTH] = 0.0
        return free

    def goal_free(self, reach: float, radius: float) -> bool:
        """Is every point farther from the robot's centre than the goal is (``reach``) plus ``radius``
        (the footprint's farthest corner)? Then a straight drive to the goal, in whatever direction it
        lies, touches nothing: no detour is needed to get there (the goal may lie nearer something than
        the clearance, as a wish's goal may; the wish after the turn is judged with the clearance)."""
        if not math.isfinite(reach):
            return False
        nearest = float(np.min(np.hypot(*self.points.T))) if len(self.points) else math.inf
        return nearest > reach + radius

    def turns(self, psi: float) -> bool:
        """Can the footprint turn on the spot by ``psi`` (rad, left positive) without touching a point?
        (A disc always can.)"""
        return psi == 0.0 or abs(psi) <= self.turn_limits[1 if psi > 0 else 0]


def _straight(footprint: np.ndarray, points: np.ndarray, psis: np.ndarray) -> np.ndarray:
    """Per direction, metres ``footprint`` goes straight that way before it touches one of ``points``."""
    c, s = np.cos(psis)[:, None], np.sin(psis)[:, None]
    x = c * points[None, :, 0] + s * points[None, :, 1]
    y = -s * points[None, :, 0] + c * points[None, :, 1]
    times = contact_times(footprint, np.column_stack((x.ravel(), y.ravel())), 1.0, 0.0)
    return np.asarray(times.reshape(len(psis), len(points)).min(axis=1))


def arc_point(curvature: float, s: float) -> tuple[float, float]:
    """Where the base's centre is after ``s`` metres along an arc of ``curvature`` (eq. 2), base frame."""
    if abs(curvature) < 1e-9:
        return s, 0.0
    return math.sin(curvature * s) / curvature, (1.0 - math.cos(curvature * s)) / curvature  # eq. 2


@dataclass(frozen=True, slots=True)
class DetourLine:
    """The line a detour started on: where the robot was held first and its heading then (odometry)."""

    x: float
    y: float
    theta: float

    @classmethod
    def at(cls, pose: Pose2D) -> DetourLine:
        return cls(pose.x, pose.y, pose.theta)

    @overload
    def offset(self, x: float, y: float) -> float: ...

    @overload
    def offset(self, x: np.ndarray, y: np.ndarray) -> np.ndarray: ...

    def offset(self, x: float | np.ndarray, y: float | np.ndarray) -> float | np.ndarray:
        """Signed distance (m, left positive) of the odometry point (x, y) from the line (eq. 3); of
        each point, given arrays."""
        return -(x - self.x) * math.sin(self.theta) + (y - self.y) * math.cos(self.theta)  # eq. 3
