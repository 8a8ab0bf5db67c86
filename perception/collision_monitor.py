"""The collision monitor's algorithm: limit one velocity command against one range scan.

Between the mission tree's velocity command and the base sits a monitor that no mission can
leave out (the runner wraps the base in it: :mod:`drivers.safety.guarded_base`). Its shape is
Nav2's collision monitor: the *source* (a :class:`~perception.ranges.RangeScan`: sonar echoes,
extra points) gives points in the base frame; *shapes* each have one action; the most
restrictive action of all wins. Here:

- a **stop zone** (polygon): a point inside it that the footprint would touch following the
  command's arc (within :data:`SWEEP_LENGTH` of travel or :data:`SWEEP_ANGLE` of turn) stops the
  command;
- a **slow-down zone** (polygon, ratio): such a point scales the command by the ratio;
- **approach** (Nav2's approach action): the command is scaled so that, at the new speed, the
  footprint would touch the nearest point on its arc no sooner than ``time_before_collision``
  (eq. 3: ``ratio = t_contact / time_before_collision`` when ``t_contact`` is shorter; straight
  ahead with a gap ``g`` this is ``v' = g / time_before_collision``). A point that closes on the
  robot by itself at ``u`` m/s (a walker: :mod:`perception.closing`) meets it sooner, and the
  ratio allows for it: ``ratio = t_contact / time_before_collision - u / |v|`` (eq. 3'; straight
  ahead ``v' = g / time_before_collision - u``);
- a **pressed bumper** stops a command that moves towards it (front: ``v > 0``; rear: ``v < 0``);
- **no data** (no scan, a scan older than ``source_timeout``, every sensor silent): the command is
  limited to a crawl (``crawl_speed``, ``crawl_turn_rate``) and the state says why.

The points judged are the scan's and, given by the caller, the echoes of the last ``memory``
seconds where odometry put them (:mod:`perception.obstacle_memory`; the guarded base keeps them,
and passes on only those in the ring's blind gaps: where a transducer looks now, its reading rules).
A sonar ring has blind gaps beside the robot (between its 50 and 90 degree cones) and places an
echo on its cone's axis: a desk corner the robot passes slips out of the front cones into the gap
and, judged on the current scan alone, no longer lies on the sweep; the lab's roadmap learning
drove into one twice (docs/failure.md). ARIA keeps such a cumulative buffer besides the current
readings for the same reason (``ArRangeDevice``'s cumulative readings, ``ArRobot::
checkRangeDevicesCumulativeBox``).

Every action is a ratio in [0, 1] applied to ``v`` and ``w`` alike, so the command keeps its arc,
is never amplified and never reversed. Zones act only on points the command's sweep reaches
(unlike Nav2's fixed polygons, which stop every motion while a point is inside): backing away
from a wall, or turning in place when the footprint's sweep is clear, stays allowed, so the
monitor can never trap the robot. Pure: no I/O, no clock of its own (``now`` is passed in).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from perception.arc_sweep import contact_times
from perception.polygons import contains, distance
from perception.ranges import RangeScan

SWEEP_LENGTH = 1.0  # m: a zone's point counts when the footprint reaches it within this much travel
SWEEP_ANGLE = math.pi  # rad: ... or within half a turn

State = Literal["clear", "slowed", "stopped"]
Action = Literal["", "stop", "slowdown", "approach", "crawl", "bumper"]


@dataclass(frozen=True, slots=True)
class Zone:
    """A polygon in the base frame with one action: ``stop``, or ``slowdown`` to ``ratio`` of the speed."""

    name: str
    polygon: np.ndarray
    action: Literal["stop", "slowdown"]
    ratio: float = 0.0


@dataclass(frozen=True, slots=True)
class MonitorConfig:
    """The footprint, the zones and the limits of one robot (built from the profile's ``safety:``)."""

    footprint: np.ndarray
    zones: tuple[Zone, ...] = ()
    time_before_collision: float = 1.0  # s; 0: no approach action
    source_timeout: float = 1.0  # s: an older scan is no data
    crawl_speed: float = 0.1  # m/s without data
    crawl_turn_rate: float = math.radians(20.0)  # rad/s without data
    memory: float = 1.0  # s: echoes this recent are judged with the scan (the guarded base keeps them); 0: none
    closing: bool = True  # echoes that close by themselves are judged where they are now (the guarded base)


@dataclass(frozen=True, slots=True)
class SafetyState:
    """What the monitor did to this tick's command, and why (``/robot/safety`` on the blackboard).

    ``state``: ``clear`` (passed unchanged), ``slowed`` (scaled down) or ``stopped``; ``action``
    and ``zone`` name the shape that decided; ``ratio`` is the scale applied; ``nearest_m`` the
    distance from the footprint to the nearest sensed point (``inf``: none); ``bumped`` whether
    a bumper is pressed.
    """

    state: State = "clear"
    action: Action = ""
    zone: str = ""
    reason: str = ""
    ratio: float = 1.0
    nearest_m: float = math.inf
    bumped: bool = False
    stamp: float = 0.0

    @property
    def limited(self) -> bool:
        return self.state != "clear"


@dataclass(frozen=True, slots=True)
class Verdict:
    """The command to send and the state that explains it."""

    v: float
    w: float
    state: SafetyState = field(default_factory=SafetyState)


@dataclass(frozen=True, slots=True)
class _Limit:
    ratio: float
    action: Action
    zone: str
    reason: str


class CollisionMonitor:
    """Limits commands against scans with one robot's :class:`MonitorConfig`."""

    def __init__(self, config: MonitorConfig) -> None:
        self.config = config

    def check(self, v: float, w: float, scan: RangeScan | None, now: float,
              remembered: np.ndarray | None = None, closing: np.ndarray | None = None) -> Verdict:
        """The command ``(v, w)`` limited against ``scan`` at time ``now`` (the scan's clock) and
        the ``remembered`` echoes of earlier scans (base frame, N x 2), judged alike while the scan is
        fresh; ``closing``: how fast each of the scan's points closes on the robot by itself (m/s,
        ``RangeScan.points`` order; None: none does)."""
        bumped = scan is not None and bool(np.any(scan.pressed))
        fresh = self._data_problem(scan, now)
        points = scan.points() if fresh is None and scan is not None else np.zeros((0, 2))
        speeds = np.zeros(len(points)) if closing is None else np.asarray(closing, dtype=float)[:len(points)]
        if fresh is None and remembered is not None and len(remembered):
            points = np.vstack((points, np.asarray(remembered, dtype=float).reshape(-1, 2)))
        speeds = np.concatenate((speeds, np.zeros(len(points) - len(speeds))))
        gaps = distance(self.config.footprint, points)
        nearest = float(gaps.min()) if len(points) else math.inf
        limits: list[_Limit] = []
        if v != 0.0 or w != 0.0:
            limits += self._bumpers(v, scan)
            limits += self._crawl(v, w, fresh) if fresh is not None else self._shapes(v, w, points, gaps, speeds)
        decisive = min(limits, key=lambda lim: lim.ratio, default=None)
        if decisive is None or decisive.ratio >= 1.0:
            return Verdict(v, w, SafetyState(nearest_m=nearest, bumped=bumped, stamp=now))
        ratio = max(0.0, decisive.ratio)
        state: State = "stopped" if ratio == 0.0 else "slowed"
        return Verdict(v * ratio, w * ratio, SafetyState(state, decisive.action, decisive.zone, decisive.reason,
                                                         ratio, nearest, bumped, now))

    # -- the shapes ----------------------------------------------------------------------------------
    def _data_problem(self, scan: RangeScan | None, now: float) -> str | None:
        """Why the scan cannot be used (no reading, too old, every sensor silent), or None."""
        if scan is None:
            return "no range reading yet"
        age = now - scan.stamp
        if age > self.config.source_timeout:
            return f"the newest range reading is {age:.2f} s old (limit {self.config.source_timeout:g} s)"
        if len(scan.sensors) and bool(np.all(np.isnan(np.asarray(scan.ranges, dtype=float)))):
            return f"none of the {len(scan.sensors)} range sensors has a reading"
        return None

    def _bumpers(self, v: float, scan: RangeScan | None) -> list[_Limit]:
        if scan is None or v == 0.0:
            return []
        facing = 1 if v > 0 else -1
        if not scan.bumped(facing):
            return []
        side = "front" if facing > 0 else "rear"
        return [_Limit(0.0, "bumper", f"{side} bumper", f"{side} bumper pressed: no motion towards it")]

    def _crawl(self, v: float, w: float, problem: str) -> list[_Limit]:
        config = self.config
        ratio = min(1.0, config.crawl_speed / abs(v) if v else 1.0, config.crawl_turn_rate / abs(w) if w else 1.0)
        return [_Limit(ratio, "crawl", "", f"{problem}: crawling")]

    def _shapes(self, v: float, w: float, points: np.ndarray, gaps: np.ndarray, closing: np.ndarray) -> list[_Limit]:
        if len(points) == 0:
            return []
        times = contact_times(self.config.footprint, points, v, w)
        horizon = min(SWEEP_LENGTH / abs(v) if v else math.inf, SWEEP_ANGLE / abs(w) if w else math.inf)
        limits = [lim for zone in self.config.zones if (lim := _zone_limit(zone, points, times, gaps, horizon))]
        approach = self.config.time_before_collision
        if approach <= 0.0:
            return limits
        ratios = times / approach - (closing / abs(v) if v else 0.0)  # eq. 3 (eq. 3' for a closing point)
        decisive = int(np.argmin(ratios))
        if ratios[decisive] < 1.0:
            walking = f", closing at {closing[decisive]:.2f} m/s by itself" if closing[decisive] > 0.0 and v else ""
            limits.append(_Limit(float(ratios[decisive]), "approach", "",
                                 f"obstacle {gaps[decisive]:.2f} m away, {times[decisive]:.2f} s ahead on the "
                                 f"command's arc{walking} (keeping {approach:g} s)"))
        return limits


def _zone_limit(zone: Zone, points: np.ndarray, times: np.ndarray, gaps: np.ndarray, horizon: float) -> _Limit | None:
    """The zone's action when a point inside it lies on the command's sweep, else None."""
    hit = contains(zone.polygon, points) & (times <= horizon)
    if not hit.any():
        return None
    gap = float(gaps[hit].min())
    where = f"obstacle {gap:.2f} m from the footprint in the {zone.action} zone '{zone.name}'"
    if zone.action == "stop":
        return _Limit(0.0, "stop", zone.name, where)
    return _Limit(zone.ratio, "slowdown", zone.name, f"{where}: speed x{zone.ratio:g}")
