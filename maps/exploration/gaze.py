"""Where the stereo pair on the pan-tilt unit looks while the robot drives (algorithm 3, eq. 3-5).

The cameras watch interest edges (:mod:`maps.exploration.interest`, eq. 2): they pan to keep an
edge's closer point in view, up to 90 degrees off the heading; when the point leaves the view
(eq. 3) the head turns back (eq. 4: towards the front, or to the remembered point ``P_A`` on the
other side); the cameras are lifted so that the watched point stays in the image while seeing as
much floor as possible (eq. 5); and the robot slows down when the pan rate needed would exceed
what the unit can do. Everything here is pure; :func:`next_gaze` is the whole per-tick decision,
and :class:`Gaze` the little state it carries between ticks.

The paper's equations, as written, and how this module reads their symbols (the paper names them
loosely; each reading is this module's choice):

- eq. 3: ``a = b cos(beta) / cos(alpha)``: where the closer point leaves the view. ``b`` is the
  point's plan range from the pan axis now and ``beta`` its angle off the *beam* (the robot's
  sideways direction on the point's side); ``alpha`` is the angle behind the beam at which it
  leaves the image when the head is at its pan limit (``max_pan + phi/2 - 90 deg``, ``phi`` the
  horizontal field of view: ``phi/2`` with the paper's 90 degrees); ``a`` is the point's range at
  that moment. Driving straight keeps the point's distance from the line of travel,
  ``b cos(beta) = a cos(alpha)``, which is eq. 3. The robot has driven
  ``b sin(beta) + a sin(alpha)`` (``beta`` positive ahead of the beam) when the point leaves:
  while that is positive the point is followed (the pan held at ``max_pan`` once the point is
  abeam). :func:`leave_range`, :func:`distance_to_leave`.
- eq. 4: ``delta = phi/2 - atan(b/a)``: the turn back. With nothing left to watch the head turns
  back towards the front only so far (``delta`` off the heading, on the side it watched) that a
  point ``a`` ahead and ``b`` across on the other side stays on the image's edge: the far edge of
  the robot's own path (``b`` its radius, ``a`` = ``keep_ahead``), so the floor the robot drives
  onto stays in view while the rest of the image keeps looking to the side that was interesting.
  :func:`turn_back`.
- eq. 5: ``alpha = atan((h - l) / d) - beta / 2``, with ``h`` the height of the point to keep in
  view, ``l`` the lens height, ``d`` the plan distance and ``beta`` the vertical field of view: the
  tilt (positive up) that puts the point on the top row of the image, so that everything below
  it, down to the floor in front of and behind the occluding edge, gets the rest of the image.
  Reading ``h`` as the point's height is this module's choice; clipped to the unit's tilt limits.
  :func:`camera_lift`.

The earlier rules stay selectable (``GazeParams.leave = "pan_limit"``: a point is retired as soon
as its bearing passes ``max_pan``; ``GazeParams.turn_back = "front"``: the head turns back to
straight ahead); docs/exploration.md compares them.

Not one of the paper's numbered equations, ours: the speed at which the pan keeps up. For a point
at plan range ``rho`` and bearing ``gamma`` off the heading, the robot driving at ``v`` and turning
at ``w``, the bearing changes at ``d gamma / dt = v sin(gamma) / rho - w``; keeping that within
``omega`` (the unit's rate, with a margin) bounds ``v <= rho (omega + sign(gamma) w) / |sin gamma|``.
With a PTU-D46 this binds only for points nearer than ~0.3 m at 1.2 m/s; it matters for slow units.

Choices where the paper is vague:

- Which edge: a *watch now* edge (eq. 2), nearest first; once chosen it is followed until it
  leaves the view (eq. 3) or becomes *never*, even when it stops being *watch now* (it leaves the
  pi/6 cone by being followed: that is the point of following it).
- Alternating sides: with *watch now* edges on both sides, the head watches one for ``dwell``
  seconds, remembers it as ``P_A`` and swings to the best edge on the other side; after the next
  ``dwell`` it swings back to ``P_A``, remembering the one it left. A target that leaves the view
  is retired for good (``Gaze.watched``); the head then goes to ``P_A`` when that is still in
  reach, else picks anew preferring the side not watched last, else turns back (eq. 4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from maps.exploration.grid import ExplorationMap
from maps.exploration.head import StereoHead
from maps.exploration.interest import Interest, closer_points
from perception.geometry import Pose2D, wrap_angles


def pan_to_point(robot: Pose2D, axis_xy: np.ndarray, point_xy: np.ndarray) -> np.ndarray:
    """Bearing (rad, left positive) of points off the robot's heading, seen from the pan axis: the pan
    that centres them."""
    p = np.asarray(point_xy, dtype=np.float64).reshape(-1, 2)
    return wrap_angles(np.arctan2(p[:, 1] - axis_xy[1], p[:, 0] - axis_xy[0]) - robot.theta)


def leave_angle(max_pan: float, horizontal_fov: float) -> float:
    """``alpha`` of eq. 3: the angle behind the beam at which a point followed to the pan limit leaves
    the image (its rear edge is half the field beyond the pan axis; negative: ahead of the beam, for a
    unit that cannot pan to 90 degrees less half the field)."""
    return max_pan + horizontal_fov / 2.0 - math.pi / 2.0


def leave_range(b: float, beta: float, alpha: float) -> float:
    """``a = b cos(beta) / cos(alpha)`` (eq. 3): the range at which a point now at range ``b`` and
    ``beta`` off the beam leaves the view, ``alpha`` behind it, the robot driving straight."""
    return b * math.cos(beta) / math.cos(alpha)  # eq. 3


def distance_to_leave(b: np.ndarray, beta: np.ndarray, alpha: float) -> np.ndarray:
    """How far the robot drives straight on before points at range ``b`` and ``beta`` off the beam
    (positive ahead of it) leave the view: from ``b sin(beta)`` ahead of the pan axis to
    ``a sin(alpha)`` behind it, ``a`` by eq. 3 (<= 0: out of view already)."""
    b, beta = np.asarray(b, dtype=np.float64), np.asarray(beta, dtype=np.float64)
    a = b * np.cos(beta) / math.cos(alpha)  # eq. 3
    return b * np.sin(beta) + a * math.sin(alpha)


def turn_back(phi: float, a: float, b: float) -> float:
    """``delta = phi/2 - atan(b/a)`` (eq. 4): how far off the heading (towards the side watched) the
    head may stay while a point ``a`` ahead and ``b`` across on the other side is still in the image
    of horizontal field ``phi``; negative: it must turn past the heading."""
    return phi / 2.0 - math.atan2(b, a)  # eq. 4


def pan_rate_needed(rho: float, gamma: float, v: float, w: float = 0.0) -> float:
    """How fast (rad/s) the pan must turn to stay on a fixed point: ``v sin(gamma) / rho - w``."""
    return v * math.sin(gamma) / rho - w


def speed_limit(rho: float, gamma: float, pan_rate: float, w: float = 0.0) -> float:
    """The top forward speed (m/s, >= 0; inf: no limit) at which the pan keeps up with a point at
    plan range ``rho`` and bearing ``gamma``: ``rho (pan_rate + sign(gamma) w) / |sin gamma|``."""
    s = math.sin(gamma)
    if abs(s) < 1e-9:
        return math.inf
    return max(0.0, rho * (pan_rate + math.copysign(1.0, s) * w) / abs(s))


def camera_lift(h: float, l: float, d: float, beta: float) -> float:
    """Tilt (rad, up positive) putting a point of height ``h`` at plan distance ``d`` on the image's top
    row, for a lens at height ``l`` and a vertical field of view ``beta`` (eq. 5)."""
    return math.atan2(h - l, d) - beta / 2.0  # eq. 5


@dataclass(frozen=True, slots=True)
class GazeParams:
    """Limits and habits of the gaze control."""

    head: StereoHead = StereoHead()
    max_pan: float = math.pi / 2.0  # follow a point up to this far off the heading
    pan_rate: float = math.radians(300.0)  # the unit's top slew rate (rad/s)
    rate_margin: float = 0.8  # plan with this fraction of it (the speed limit)
    pan_limits: tuple[float, float] = (math.radians(-159.0), math.radians(159.0))
    tilt_limits: tuple[float, float] = (math.radians(-47.0), math.radians(31.0))
    home_tilt: float = math.radians(-15.0)  # where the cameras look with nothing to watch
    dwell: float = 1.5  # s: how long one side is watched while the other side has an edge too
    leave: str = "eq3"  # eq3: follow a point until it leaves the image; pan_limit: until it passes max_pan
    turn_back: str = "eq4"  # eq4: turn back to delta off the heading; front: straight ahead
    keep_ahead: float = 1.0  # m: eq. 4's a, how far ahead the far edge of the path stays in view
    keep_across: float = 0.26  # m: eq. 4's b, the far edge of the path (the robot's radius)

    def __post_init__(self) -> None:
        if self.leave not in LEAVE_RULES or self.turn_back not in TURN_BACK_RULES:
            raise ValueError(f"leave is one of {LEAVE_RULES} and turn_back one of {TURN_BACK_RULES}, "
                             f"got {self.leave!r}, {self.turn_back!r}")
        if self.leave == "eq3" and not abs(leave_angle(self.max_pan, self.head.horizontal_fov)) < math.pi / 2:
            raise ValueError("eq. 3 needs max_pan + horizontal_fov / 2 below 180 degrees")

    def within(self, pan_limits: tuple[float, float], tilt_limits: tuple[float, float], pan_rate: float) -> GazeParams:
        """These parameters kept inside what a unit reports: its ranges and its top rate."""
        pan = (max(self.pan_limits[0], pan_limits[0]), min(self.pan_limits[1], pan_limits[1]))
        tilt = (max(self.tilt_limits[0], tilt_limits[0]), min(self.tilt_limits[1], tilt_limits[1]))
        if pan[0] >= pan[1] or tilt[0] >= tilt[1]:
            raise ValueError(f"the unit's limits (pan {np.degrees(pan_limits).round(2).tolist()}, tilt "
                             f"{np.degrees(tilt_limits).round(2).tolist()} deg) leave nothing of the ones asked for")
        return replace(self, pan_limits=pan, tilt_limits=tilt, pan_rate=min(self.pan_rate, pan_rate),
                       max_pan=min(self.max_pan, -pan[0], pan[1]))


LEAVE_RULES = ("eq3", "pan_limit")
TURN_BACK_RULES = ("eq4", "front")


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
    if params.leave == "eq3":  # followed until it leaves the image, the pan held at max_pan (eq. 3)
        beta = np.where(np.isfinite(bearing), math.pi / 2.0 - np.abs(bearing), -math.pi / 2.0)
        reach = distance_to_leave(np.where(np.isfinite(rho), rho, 0.0), beta,
                                  leave_angle(params.max_pan, params.head.horizontal_fov)) > 0.0
    else:
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
        return state, GazeCommand(home_pan(state, params), params.home_tilt, math.inf, None)
    point = sight.closer[state.target]
    gamma, rho = float(sight.bearing[state.target]), float(sight.rho[state.target])
    pan = float(np.clip(gamma, -params.max_pan, params.max_pan))
    lift = camera_lift(float(point[2]), params.head.lens_height, rho, params.head.vertical_fov)  # eq. 5
    tilt = float(np.clip(lift, *params.tilt_limits))
    v_max = speed_limit(rho, gamma, params.pan_rate * params.rate_margin, turn_rate)
    return state, GazeCommand(pan, tilt, v_max, point.copy())


def home_pan(gaze: Gaze, params: GazeParams) -> float:
    """The pan with nothing to watch: straight ahead, or (``turn_back = "eq4"``, once a side was
    watched) turned back only to eq. 4's ``delta`` on that side (never past the heading)."""
    if params.turn_back == "front" or gaze.side == 0:
        return 0.0
    delta = turn_back(params.head.horizontal_fov, params.keep_ahead, params.keep_across)  # eq. 4
    return gaze.side * float(np.clip(delta, 0.0, params.max_pan))


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
