"""How fast what each range sensor hears closes on the robot by itself: a walker, not a wall.

A sonar ring fires one transducer at a time; each is read again only a ring's cycle later (0.32 s
on a Pioneer 3). A wall stays where it was heard, but a person walking at the robot comes 0.35 m
nearer in that time when both move (0.8 m/s and 0.3 m/s): a reading the collision monitor judges
as clear can be the whole slow-down zone stale, and the robot, braking at 0.3 m/s^2, needs 0.15 m
to stop from 0.3 m/s. The library's roadmap learning drove into a walker that way (docs/obstacles-
measured.md, "Closing echoes (stop 49)").

So each transducer's two last readings are compared. A sonar hears the nearest surface anywhere
in its cone, so the first echo lies somewhere on the arc of its range across the cone; put where
the robot's odometry says, a thing standing there would be heard from the sensor's new place at
no less than

    r_still = min_k | p_k - s_1 |   (eq. C1: p_k on the first echo's arc and inside the cone now,
                                     s_1 the sensor now, odometry frame)

and what came nearer than that came by itself, at

    u = (r_still - r_1) / (t_1 - t_0)   (eq. C2).

A speed ``u`` counts only between :data:`MIN_CLOSING` (below it: the readings' noise, 0.02 m
each in the simulator gives 0.09 m/s of spread at 0.32 s) and :data:`MAX_CLOSING` (above it: a new
thing in the cone, not one that walked there), from readings no more than :data:`MAX_INTERVAL`
apart, with the robot turned less than :data:`MAX_TURN` between them (the cone looking at the
same thing), and only for a sensor the robot did not carry away from where it looks (a rear
transducer while driving forwards): a wall seen at a grazing angle is heard at the same range all
along it, and from a sensor moving away that reads as a thing following the robot (what lies
behind a robot driving forwards is not on its way). In the lab's showcase, with no people, 99
echoes closed in 34 s judged on the cone's axis without this rule, 32 with the arc and the rule,
none of them on the robot's way. A thing that recedes, or closes more slowly, is a standing thing: speed 0.

Until the transducer fires again, its closing echo is judged where it is now, the reading moved
nearer by ``u`` times its age (eq. C3, :meth:`ClosingEchoes.judged`), and the monitor's approach
action allows for ``u`` (``perception.collision_monitor``, eq. 3'). A sonar hears only along its
cone's axis, so a person walking across the cone gives no speed (or a small one): only the range
closes. Pure: no I/O, no clock.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from perception.geometry import Pose2D, frame_to_parent, wrap_angles
from perception.ranges import RangeScan

MIN_CLOSING = 0.25  # m/s: slower is noise (or a standing thing)
MAX_CLOSING = 1.5  # m/s: faster is a new thing in the cone, not one that walked there (a brisk walk)
MAX_INTERVAL = 0.6  # s: readings farther apart are not one transducer's successive firings
ARC_SAMPLES = 7  # points across the cone where the first echo may have come from
MAX_TURN = math.radians(7.5)  # rad: the robot turned more between two readings: the cone looks elsewhere
AWAY_TOLERANCE = 0.01  # m: a sensor carried farther than this away from where it looks is not judged (below)


@dataclass(frozen=True, slots=True)
class ClosingEchoes:
    """Each sensor's newest reading (when, how far, from where in the odometry frame) and the speed
    ``speeds[i]`` (m/s, 0: not closing) at which what it hears closes on the robot by itself."""

    fired: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    ranges: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    origins: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 2)))
    headings: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    speeds: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))

    def added(self, scan: RangeScan, pose: Pose2D) -> ClosingEchoes:
        """With ``scan``'s new readings (those fired since the last), read at odometry ``pose``."""
        n = len(scan.sensors)
        last = self if len(self.fired) == n else ClosingEchoes(  # the first scan, or another ring (the model said)
            np.full(n, np.nan), np.full(n, np.nan), np.zeros((n, 2)), np.zeros(n), np.zeros(n))
        fired = scan.fired_at()
        ranges = np.asarray(scan.ranges, dtype=float)
        new = ~np.isnan(ranges) & ~(fired <= last.fired)  # a reading not seen before (nan <= x is False)
        if not new.any():
            return last
        mounts = np.array([(s.x, s.y) for s in scan.sensors]).reshape(-1, 2)
        origins = frame_to_parent(pose, mounts)
        headings = np.array([s.heading for s in scan.sensors]) + pose.theta
        fov = np.array([s.fov for s in scan.sensors])
        speeds = _closing(last, fired, ranges, origins, headings, fov)
        return ClosingEchoes(np.where(new, fired, last.fired), np.where(new, ranges, last.ranges),
                             np.where(new[:, None], origins, last.origins), np.where(new, headings, last.headings),
                             np.where(new, speeds, last.speeds))

    def judged(self, scan: RangeScan, now: float) -> tuple[RangeScan, np.ndarray]:
        """``scan`` with each closing echo moved nearer by its speed times its age (eq. C3), and the
        closing speed of each of the scan's points (``RangeScan.points`` order; extra points: 0)."""
        ranges = np.asarray(scan.ranges, dtype=float)
        speeds = self.speeds if len(self.speeds) == len(ranges) else np.zeros(len(ranges))
        closing = np.isfinite(ranges) & (speeds > 0.0)
        if closing.any():
            age = np.maximum(now - scan.fired_at(), 0.0)
            least = np.array([s.min_range for s in scan.sensors])
            ranges = np.where(closing, np.maximum(ranges - speeds * age, least), ranges)  # eq. C3
            scan = dataclasses.replace(scan, ranges=ranges)
        per_point = np.concatenate((speeds[np.isfinite(ranges)], np.zeros(len(np.asarray(scan.extra).reshape(-1, 2)))))
        return scan, per_point


def _closing(last: ClosingEchoes, fired: np.ndarray, ranges: np.ndarray, origins: np.ndarray,
             headings: np.ndarray, fov: np.ndarray) -> np.ndarray:
    """Eq. C1-C2 for every sensor against its previous reading; 0 where it does not count."""
    interval = fired - last.fired
    offsets = np.linspace(-0.5, 0.5, ARC_SAMPLES)[None, :] * fov[:, None]  # (N, K) across the cone
    bearing = last.headings[:, None] + offsets
    with np.errstate(invalid="ignore", divide="ignore"):  # no echo (inf) or none yet (nan): not judged, below
        arc = last.origins[:, None, :] + last.ranges[:, None, None] * np.stack((np.cos(bearing), np.sin(bearing)), -1)
        seen = arc - origins[:, None, :]
        distance = np.hypot(seen[..., 0], seen[..., 1])
        inside = np.abs(wrap_angles(np.arctan2(seen[..., 1], seen[..., 0]) - headings[:, None])) <= fov[:, None] / 2
        still = np.where(inside, distance, np.inf).min(axis=1)  # eq. C1, the nearest the first echo can read now
        speed = (still - ranges) / interval  # eq. C2
    travel = origins - last.origins
    towards = travel[:, 0] * np.cos(headings) + travel[:, 1] * np.sin(headings) >= -AWAY_TOLERANCE
    valid = (np.isfinite(last.ranges) & np.isfinite(ranges) & np.isfinite(still) & (interval > 0.0)
             & (interval <= MAX_INTERVAL) & (np.abs(wrap_angles(headings - last.headings)) <= MAX_TURN) & towards)
    counts = valid & (speed >= MIN_CLOSING) & (speed <= MAX_CLOSING)
    return np.where(counts, speed, 0.0)
