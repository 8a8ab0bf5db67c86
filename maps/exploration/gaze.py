"""Where the stereo pair on the pan-tilt unit looks while the robot drives (algorithm 3, eq. 3-5).

The cameras watch interest edges (:mod:`maps.exploration.interest`, eq. 2): they pan to keep an edge's
closer point in view, up to 90 degrees off the heading (eq. 3); the robot slows down when the pan
rate needed would exceed what the unit can do (eq. 4); when the point leaves that range the head
turns back (to the front, or to the remembered point ``P_A`` on the other side); and the cameras
are lifted so that the watched point stays in the image while seeing as much floor as possible
(eq. 5). Everything here is pure; :func:`next_gaze` is the whole per-tick decision, and
:class:`Gaze` the little state it carries between ticks.

Geometry, for a point at plan range ``rho`` from the pan axis and bearing ``gamma`` off the
heading, the robot driving at ``v`` and turning at ``w``:

- eq. 3: pan = gamma (clipped to +-90 degrees); it changes at ``d gamma / dt = v sin(gamma) / rho - w``.
- eq. 4: keeping ``|d gamma / dt| <= omega`` (the unit's rate, with a margin) bounds the speed:
  ``v <= rho (omega + sign(gamma) w) / |sin gamma|``. With a PTU-D46 (300 deg/s, 0.8 of it
  planned) this binds only for points nearer than ~0.3 m at 1.2 m/s; it matters for slow units.
- eq. 5: ``alpha = atan((h - l) / d) - beta / 2``, with ``h`` the height of the point to keep in
  view, ``l`` the lens height, ``d`` the plan distance and ``beta`` the vertical field of view: the
  tilt (positive up) that puts the point on the top row of the image, so that everything below
  it, down to the floor in front of and behind the occluding edge, gets the rest of the image.
  Reading ``h`` as the point's height is this module's choice (the paper names the symbols
  loosely); clipped to the unit's tilt limits.

Choices where the paper is vague:

- Which edge: a *watch now* edge (eq. 2), nearest first; once chosen it is followed while its
  bearing stays within 90 degrees and it is not *never*, even when it stops being *watch now*
  (it leaves the pi/6 cone by being followed: that is the point of following it).
- Alternating sides: with *watch now* edges on both sides, the head watches one for ``dwell``
  seconds, remembers it as ``P_A`` and swings to the best edge on the other side; after the next
  ``dwell`` it swings back to ``P_A``, remembering the one it left. A target that leaves the view
  is retired for good (``Gaze.watched``); the head then goes to ``P_A`` when that is still in
  reach, else picks anew preferring the side not watched last, else turns back to the front.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from maps.exploration.grid import ExplorationMap
from maps.exploration.head import StereoHead
from maps.exploration.interest import Interest, closer_points
from perception.geometry import Pose2D, wrap_angles


def pan_to_point(robot: Pose2D, axis_xy: np.ndarray, point_xy: np.ndarray) -> np.ndarray:
    """Bearing (rad, left positive) of points off the robot's heading, seen from the pan axis (eq. 3)."""
    p = np.asarray(point_xy, dtype=np.float64).reshape(-1, 2)
    return wrap_angles(np.arctan2(p[:, 1] - axis_xy[1], p[:, 0] - axis_xy[0]) - robot.theta)  # eq. 3


def pan_rate_needed(rho: float, gamma: float, v: float, w: float = 0.0) -> float:
    """How fast (rad/s) the pan must turn to stay on a fixed point: ``v sin(gamma) / rho - w`` (eq. 3)."""
    return v * math.sin(gamma) / rho - w  # eq. 3


def speed_limit(rho: float, gamma: float, pan_rate: float, w: float = 0.0) -> float:
    """The top forward speed (m/s, >= 0; inf: no limit) at which the pan keeps up (eq. 4)."""
    s = math.sin(gamma)
    if abs(s) < 1e-9:
        return math.inf
    return max(0.0, rho * (pan_rate + math.copysign(1.0, s) * w) / abs(s))  # eq. 4


def camera_lift(h: float, l: float, d: float, beta: float) -> float:
    """Tilt (rad, up positive) putting a point of height ``h`` at plan distance ``d`` on the image's top
    row, for a lens at height ``l`` and a vertical field of view ``beta`` (eq. 5)."""
    return math.atan2(h - l, d) - beta / 2.0  # eq. 5


@dataclass(frozen=True, slots=True)
class GazeParams:
    """Limits and habits of the gaze control."""

    head: StereoHead = StereoHead()
    max_pan: float = math.pi / 2.0  # follow a point up to this far off the heading (eq. 3)
    pan_rate: float = math.radians(300.0)  # the unit's top slew rate (rad/s)
    rate_margin: float = 0.8  # plan with this fraction of it (eq. 4)
    pan_limits: tuple[float, float] = (math.radians(-159.0), math.radians(159.0))
    tilt_limits: tuple[float, float] = (math.radians(-47.0), math.radians(31.0))
    home_tilt: float = math.radians(-15.0)  # where the cameras look with nothing to watch
    dwell: float = 1.5  # s: how long one side is watched while the other side has an edge too


@dataclass(frozen=True, slots=True)
class Gaze:
    """The gaze control's state: the edge watched (index into the map's edges), since when, the
    remembered edge ``P_A`` on the other side, the side last watched (+1 left, -1 right, 0 none) and
    the edges already followed out of view (never watched again)."""

    target: int | None = None
    since: float = 0.0
    remembered: int | None = None
    side: int = 0
    watched: frozenset[int] = field(default_factory=frozenset)


@dataclass(frozen=True, slots=True)
class GazeCommand:
    """What to do this tick: pan/tilt targets (rad), the forward speed limit (m/s, inf: none) and the
    point watched (x, y, z; None when looking ahead)."""

    pan: float
    tilt: float
    max_speed: float
    point: np.ndarray | None


def _side(bearing: float) -> int:
    return 1 if bearing >= 0.0 else -1


@dataclass(frozen=True, slots=True)
class _Sight:
    """Every edge's closer point as seen from the pan axis this tick, and which ones may be watched."""

    closer: np.ndarray  # (M, 3)
    bearing: np.ndarray  # (M,) rad off the heading
    rho: np.ndarray  # (M,) plan range from the pan axis
    reach: np.ndarray  # (M,) may be followed: not NEVER, within max_pan, not watched yet
    candidate: np.ndarray  # (M,) may be started: reach and WATCH_NOW

    def pick(self, side: int, exclude: int | None = None) -> int | None:
        """The nearest candidate on ``side`` (+1 left, -1 right, 0 either)."""
        ok = self.candidate.copy()
        if side:
            ok &= np.where(self.bearing >= 0.0, 1, -1) == side
        if exclude is not None:
            ok[exclude] = False
        return int(np.argmin(np.where(ok, self.rho, np.inf))) if ok.any() else None


def _sight(gaze: Gaze, m: ExplorationMap, robot: Pose2D, params: GazeParams) -> _Sight:
    """Only edges that are not *never* are looked at (most of a map's edges end up never: the
    geometry of the others is not computed, their bearing is inf)."""
    axis = params.head.axis_xy(robot)
    n = len(m.edges)
    live = np.flatnonzero(m.interest != Interest.NEVER)
    closer, bearing, rho = np.zeros((n, 3)), np.full(n, np.inf), np.full(n, np.inf)
    if len(live):
        closer[live] = closer_points(m, np.array([*axis, params.head.lens_height]), live)
        bearing[live] = pan_to_point(robot, axis, closer[live, :2])
        rho[live] = np.hypot(closer[live, 0] - axis[0], closer[live, 1] - axis[1])
    reach = np.abs(bearing) <= params.max_pan
    if gaze.watched:
        reach[np.fromiter(gaze.watched, dtype=np.int64)] = False
    return _Sight(closer, bearing, rho, reach, reach & (m.interest == Interest.WATCH_NOW))


def _choose(gaze: Gaze, sight: _Sight, now: float, dwell: float) -> Gaze:
    """The next gaze state: keep, retire, alternate or pick the watched edge (module docstring)."""
    target, remembered, since, watched = gaze.target, gaze.remembered, gaze.since, gaze.watched
    if target is not None and not sight.reach[target]:  # left the view (or never interesting again)
        watched, target = watched | {target}, None
    if remembered is not None and not sight.reach[remembered]:
        remembered = None
    if target is not None and now - since >= dwell:  # alternate sides
        other = remembered if remembered is not None else sight.pick(-_side(sight.bearing[target]))
        if other is not None:
            target, remembered, since = other, target, now
    if target is None:  # back to P_A, else a new one, preferably on the side not watched last
        target, remembered, since = remembered, None, now
        if target is None and gaze.side:
            target = sight.pick(-gaze.side)
        if target is None:
            target = sight.pick(0)
    if target is not None and remembered is None:
        remembered = sight.pick(-_side(sight.bearing[target]), exclude=target)
    side = _side(sight.bearing[target]) if target is not None else gaze.side
    return Gaze(target, since, remembered, side, watched)


def next_gaze(
    gaze: Gaze,
    m: ExplorationMap,
    robot: Pose2D,
    now: float,
    params: GazeParams = GazeParams(),
    *,
    turn_rate: float = 0.0,
) -> tuple[Gaze, GazeCommand]:
    """The gaze state and command for this tick.

    ``robot``: odometry pose; ``now``: the tree's clock (s); ``turn_rate``: the robot's commanded
    turn rate (rad/s), which eq. 4 takes into account.
    """
    sight = _sight(gaze, m, robot, params)
    state = _choose(gaze, sight, now, params.dwell)
    if state.target is None:
        return state, GazeCommand(0.0, params.home_tilt, math.inf, None)
    point = sight.closer[state.target]
    gamma, rho = float(sight.bearing[state.target]), float(sight.rho[state.target])
    pan = float(np.clip(gamma, -params.max_pan, params.max_pan))  # eq. 3
    lift = camera_lift(float(point[2]), params.head.lens_height, rho, params.head.vertical_fov)  # eq. 5
    tilt = float(np.clip(lift, *params.tilt_limits))
    v_max = speed_limit(rho, gamma, params.pan_rate * params.rate_margin, turn_rate)  # eq. 4
    return state, GazeCommand(pan, tilt, v_max, point.copy())


def survey(params: GazeParams = GazeParams(), overlap: float = 0.15) -> np.ndarray:
    """Pan/tilt poses (K x 2, rad) that look all around as far as the pan limits allow.

    Rows of tilts from the lowest limit (the floor nearest the robot) up, each field of view
    overlapping the last by ``overlap``, until the top of the image is above the horizon (far
    points); along each row, pans spaced by the horizontal field of view (with the same overlap)
    from one pan limit to the other, every other row backwards so the head never swings back
    empty-handed. For a start (the floor next to the robot joins its footprint) or a look-around.
    """
    head = params.head
    lo, hi = params.tilt_limits
    tilts = [lo]
    while tilts[-1] + head.vertical_fov / 2.0 < 0.0 and tilts[-1] < hi:
        tilts.append(min(tilts[-1] + head.vertical_fov * (1.0 - overlap), hi))
    p0, p1 = params.pan_limits
    n = int(math.ceil((p1 - p0) / (head.horizontal_fov * (1.0 - overlap)))) + 1
    pans = np.linspace(p0, p1, n)
    rows = [np.column_stack((pans if i % 2 == 0 else pans[::-1], np.full(n, t))) for i, t in enumerate(tilts)]
    return np.concatenate(rows)
