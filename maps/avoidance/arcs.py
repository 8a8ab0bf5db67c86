"""Which arcs are free, and the free one closest to what a motion node wished.

A differential-drive base commanded ``(v, w)`` with ``v > 0`` follows an arc of curvature
``kappa = w / v``. Given obstacle points around the base (sonar echoes, base frame), this module
says

- how far the footprint, grown by a margin, can travel along an arc before it touches one of them
  (:func:`free_distance`: the exact sweep of :func:`perception.arc_sweep.contact_times`, times
  the speed);
- how far a motion node commanding ``v`` means to go at least: its braking distance plus ``v``
  times a short ``horizon`` (eq. 1, :func:`needed_distance`). A node that ramps its speed down
  as ``sqrt(2 a d)`` before its goal (``behaviours.motion.ramp``) asks, with ``decel`` equal to
  ``a``, for ``d`` plus the horizon's travel: an obstacle beyond the goal does not block it;
- which arc of a fan to take when the wished one is not free (:func:`choose`): among the arcs
  free for their needed distance and not straying from the detour's line (eq. 3), the one whose
  curvature is closest to the wish (eq. 4); once a detour has passed the obstacle on one side it
  keeps that side, and the first choice between two equally close arcs goes to the side with more
  room.

It is the dynamic window approach (Fox, Burgard & Thrun, "The dynamic window approach to
collision avoidance", 1997) cut down to what a decorator needs: one speed (the detour's) rather
than the window of reachable ``(v, w)``, an objective of heading alone (the motion node under the
decorator steers back to its own path once the way is clear) and the free distance as a hard
constraint instead of DWA's weighted ``dist`` term. The margin shrinks to half the nearest gap
when something is already nearer than it (a doorway's jamb, a person just passed), so a robot
close to something can still move along or away from it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from perception.arc_sweep import contact_times
from perception.collision_monitor import SWEEP_LENGTH
from perception.geometry import Pose2D
from perception.polygons import distance, grow

OTHER_SIDE = 1000.0  # cost added to an arc on the other side of a detour's: taken only when nothing else is free


@dataclass(frozen=True, slots=True)
class ArcSettings:
    """The robot's footprint and how arcs are judged (module docstring)."""

    footprint: np.ndarray  # convex, counter-clockwise, base frame (m)
    clearance: float = 0.10  # m kept between the footprint and every point along an arc
    horizon: float = 0.5  # s of travel that must be free beyond the braking distance (eq. 1)
    decel: float = 0.25  # m/s^2: the braking the distance is computed with
    speed: float = 0.2  # m/s along a detour's arcs
    min_radius: float = 0.3  # m: the sharpest arc of the fan
    arcs: int = 21  # arcs in the fan, evenly spaced in curvature (odd: straight ahead is one)
    max_stray: float = 1.5  # m a detour may stray from the line it started on (eq. 3)

    @property
    def max_curvature(self) -> float:
        return 1.0 / self.min_radius


def needed_distance(v: float, settings: ArcSettings) -> float:
    """How far (m) a command of forward speed ``v`` means to go at least (0 for ``v <= 0``)."""
    v = max(v, 0.0)
    return v * v / (2.0 * settings.decel) + v * settings.horizon  # eq. 1


def margin(footprint: np.ndarray, points: np.ndarray, clearance: float) -> float:
    """The margin arcs are checked with: ``clearance``, or half the nearest gap when that is smaller."""
    if len(points) == 0:
        return clearance
    return float(min(clearance, 0.5 * float(distance(footprint, points).min())))


def free_distance(footprint: np.ndarray, points: np.ndarray, v: float, w: float) -> float:
    """Metres ``footprint`` travels along the arc ``(v, w)``, ``v > 0``, before it touches a point
    (``inf``: never within a turn)."""
    if len(points) == 0:
        return math.inf
    return float(v * contact_times(footprint, points, v, w).min())


@dataclass(frozen=True, slots=True)
class Surroundings:
    """The points around the base (base frame) as arcs are judged against them: the footprint grown
    by the margin, and the points already nearer the footprint than the clearance."""

    footprint: np.ndarray
    points: np.ndarray
    grown: np.ndarray
    near: np.ndarray

    @classmethod
    def of(cls, points: np.ndarray, settings: ArcSettings) -> Surroundings:
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        gaps = distance(settings.footprint, pts)
        grown = grow(settings.footprint, margin(settings.footprint, pts, settings.clearance))
        return cls(settings.footprint, pts, grown, pts[gaps < settings.clearance])

    def free(self, v: float, w: float) -> float:
        """Metres the grown footprint goes along the arc ``(v, w)`` before it touches a point."""
        return free_distance(self.grown, self.points, v, w)

    def grazes(self, v: float, w: float) -> bool:
        """Does the footprint itself reach a point already within the clearance, within the collision
        monitor's sweep (:data:`perception.collision_monitor.SWEEP_LENGTH`)? The monitor stops such a
        command, however far off the point is along the arc."""
        return len(self.near) > 0 and free_distance(self.footprint, self.near, v, w) <= SWEEP_LENGTH

    def open(self, v: float, w: float, needed: float) -> bool:
        """Is the arc free for ``needed`` metres, grazing nothing?"""
        return self.free(v, w) >= needed and not self.grazes(v, w)


def arc_point(curvature: float, s: float) -> tuple[float, float]:
    """Where the base's centre is after ``s`` metres along an arc of ``curvature`` (eq. 2), base frame."""
    if abs(curvature) < 1e-9:
        return s, 0.0
    return math.sin(curvature * s) / curvature, (1.0 - math.cos(curvature * s)) / curvature  # eq. 2


def arc_points(curvature: float, s: float, n: int = 12) -> np.ndarray:
    """``n`` points along the first ``s`` metres of an arc (eq. 2), base frame (n x 2), for drawings."""
    return np.array([arc_point(curvature, t) for t in np.linspace(0.0, s, n)])


@dataclass(frozen=True, slots=True)
class DetourLine:
    """The line a detour started on: where the robot was held first and its heading then (odometry)."""

    x: float
    y: float
    theta: float

    @classmethod
    def at(cls, pose: Pose2D) -> DetourLine:
        return cls(pose.x, pose.y, pose.theta)

    def offset(self, x: float, y: float) -> float:
        """Signed distance (m, left positive) of the odometry point (x, y) from the line (eq. 3)."""
        return -(x - self.x) * math.sin(self.theta) + (y - self.y) * math.cos(self.theta)  # eq. 3


@dataclass(frozen=True, slots=True)
class Arc:
    """One arc of the fan: its curvature, how far it is free (m, uncapped), whether it grazes a point
    already within the clearance (:meth:`Surroundings.grazes`) and whether it strays."""

    curvature: float
    free: float
    grazes: bool = False
    strays: bool = False

    def will_do(self, reach: float) -> bool:
        return self.free >= reach and not self.grazes and not self.strays


@dataclass(frozen=True, slots=True)
class Choice:
    """The fan judged for one wish: the arcs, the one chosen (None: no arc will do), the wished
    curvature (clipped to the fan) and the distance every arc had to be free for."""

    arcs: tuple[Arc, ...]
    chosen: int | None
    wish: float
    reach: float

    @property
    def arc(self) -> Arc | None:
        return None if self.chosen is None else self.arcs[self.chosen]

    @property
    def side(self) -> int:
        """+1 when the chosen arc turns left of the wish, -1 right, 0 on it or when none is chosen."""
        arc = self.arc
        return 0 if arc is None else int(np.sign(arc.curvature - self.wish))

    @property
    def only_straying(self) -> bool:
        """Arcs are free, but every one of them strays too far: the bound, not an obstacle, holds the robot."""
        return self.chosen is None and any(a.free >= self.reach and not a.grazes and a.strays for a in self.arcs)


def curvatures(settings: ArcSettings) -> np.ndarray:
    """The fan: ``arcs`` curvatures from the sharpest right to the sharpest left (1/m)."""
    return np.linspace(-settings.max_curvature, settings.max_curvature, settings.arcs)


def wished_curvature(v: float, w: float, settings: ArcSettings) -> float:
    """The curvature a command asks for, clipped to the fan; a turn on the spot asks for the sharpest."""
    k = settings.max_curvature
    if v <= 0.0:
        return math.copysign(k, w) if w else 0.0
    return float(np.clip(w / v, -k, k))


def choose(around: Surroundings, wish: float, settings: ArcSettings, *, reach: float | None = None, side: int = 0,
           pose: Pose2D | None = None, line: DetourLine | None = None) -> Choice:
    """Judge the fan against the points ``around`` the base and choose the arc for the curvature ``wish``.

    An arc will do when it is free for ``reach`` (default: its needed distance, eq. 1 at
    ``settings.speed``), grazes no point already within the clearance and, with
    a detour ``line`` and the robot's odometry ``pose``, its end does not lie farther than
    ``max_stray`` from the line unless it comes back towards it. Of those, the one closest to the
    wish (eq. 4); ``side`` (+1 left, -1 right of the wish) keeps a detour on the side it took, and
    with no side yet, a tie goes to the side with more free arcs.
    """
    reach = needed_distance(settings.speed, settings) if reach is None else reach
    fan = curvatures(settings)
    v = settings.speed
    arcs = tuple(Arc(float(k), around.free(v, float(k) * v), around.grazes(v, float(k) * v),
                     _strays(float(k), reach, settings.max_stray, pose, line)) for k in fan)
    usable = [i for i, a in enumerate(arcs) if a.will_do(reach)]
    if not usable:
        return Choice(arcs, None, wish, reach)
    step = float(fan[1] - fan[0]) if len(fan) > 1 else 1.0
    room = {s: _room(arcs, wish, s, reach) for s in (-1, 1)}

    def cost(i: int) -> float:
        arc_side = int(np.sign(arcs[i].curvature - wish))
        off = abs(arcs[i].curvature - wish) / step  # eq. 4, in steps of the fan
        if side and arc_side == -side:
            return off + OTHER_SIDE
        return off - (0.5 * room[arc_side] if not side and arc_side else 0.0)

    return Choice(arcs, min(usable, key=cost), wish, reach)


def _room(arcs: tuple[Arc, ...], wish: float, side: int, reach: float) -> float:
    """The fraction of the arcs on ``side`` of the wish that are free for ``reach``."""
    there = [a for a in arcs if np.sign(a.curvature - wish) == side]
    return sum(a.free >= reach and not a.grazes for a in there) / len(there) if there else 0.0


def _strays(curvature: float, reach: float, max_stray: float, pose: Pose2D | None, line: DetourLine | None) -> bool:
    """Whether the arc's end (after ``reach``) lies farther than ``max_stray`` from the detour's line
    and farther than the robot is now."""
    if pose is None or line is None:
        return False
    x, y = arc_point(curvature, reach)
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    end = abs(line.offset(pose.x + c * x - s * y, pose.y + s * x + c * y))
    return end > max_stray and end > abs(line.offset(pose.x, pose.y))
