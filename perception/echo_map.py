"""Echoes of the last tens of seconds, kept until a newer reading sees through them.

The collision monitor and the detour judge the echoes of the last second
(:mod:`perception.obstacle_memory`): as the robot turns, a desk it faced a few seconds ago drops
out of that memory, and a way round a cluster of people and furniture cannot be planned from
it. This memory keeps every echo for ``keep`` seconds where odometry put it, and forgets it
sooner where a newer reading says the space is empty: a transducer that hears an echo at range
``r`` heard nothing nearer along the middle of its cone, so the echoes kept there nearer than
``r`` less :data:`SEE_THROUGH` are gone (a person who walked away). This is a costmap's
raytrace clearing (Nav2's range sensor layer clears the cone the same way), with the points kept
as points, not cells.

Only a reading with an echo clears: a sonar that hears nothing may have missed a wall met at a
grazing angle (a specular reflection), and the middle :data:`CLEAR_CONE` of the cone only, where
an echo's bearing is surest. Stereo points (``RangeScan.extra``) are kept and age, and clear
nothing.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from perception.geometry import Pose2D, frame_to_parent, parent_to_frame, wrap_angles
from perception.ranges import RangeScan

SEE_THROUGH = 0.15  # m: an echo kept this much nearer than a new reading along its cone is seen through
CLEAR_CONE = 0.5  # fraction of a cone's width, about its axis, that clears
RESOLUTION = 0.02  # m: kept points closer than this are one (the newest stands)
REACH = 4.0  # m: echoes farther than this from the robot are dropped (planning looks nearer)


@dataclass(frozen=True, slots=True)
class EchoMap:
    """Echoes (odometry frame, ``points`` N x 2) and when each was heard (``stamps``), not older
    than ``keep`` seconds and not seen through since."""

    keep: float = 20.0
    points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    stamps: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def added(self, scan: RangeScan, pose: Pose2D) -> EchoMap:
        """With ``scan`` (taken at odometry ``pose``) added: what its echoes see through is dropped,
        then its points kept; older than ``keep`` and farther than :data:`REACH` dropped too."""
        points, stamps = self.points, self.stamps
        alive = (stamps > scan.stamp - self.keep) & (np.hypot(points[:, 0] - pose.x, points[:, 1] - pose.y) <= REACH)
        points, stamps = points[alive], stamps[alive]
        if len(points):
            points, stamps = _cleared(points, stamps, scan, pose)
        new = scan.points()
        if len(new):
            points = np.vstack((points, frame_to_parent(pose, new)))
            stamps = np.concatenate((stamps, np.full(len(new), scan.stamp)))
        return EchoMap(self.keep, *_one_per_cell(points, stamps))

    def around(self, pose: Pose2D) -> np.ndarray:
        """Every kept echo in the base frame of ``pose`` (N x 2)."""
        return parent_to_frame(pose, self.points) if len(self.points) else np.zeros((0, 2))


def _cleared(points: np.ndarray, stamps: np.ndarray, scan: RangeScan, pose: Pose2D
             ) -> tuple[np.ndarray, np.ndarray]:
    """The kept echoes no reading of ``scan`` sees through (module docstring)."""
    base = parent_to_frame(pose, points)
    gone = np.zeros(len(points), dtype=bool)
    for sensor, reading in zip(scan.sensors, np.asarray(scan.ranges, dtype=float), strict=True):
        if not np.isfinite(reading):  # no echo, or not read yet: clears nothing
            continue
        dx, dy = base[:, 0] - sensor.x, base[:, 1] - sensor.y
        off = np.abs(wrap_angles(np.arctan2(dy, dx) - sensor.heading))
        gone |= (off <= CLEAR_CONE * sensor.fov / 2.0) & (np.hypot(dx, dy) < reading - SEE_THROUGH)
    return points[~gone], stamps[~gone]


def _one_per_cell(points: np.ndarray, stamps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One point per :data:`RESOLUTION` cell, the newest (a transducer's reading repeats until it
    fires again)."""
    if len(points) < 2:
        return points, stamps
    keys = np.round(points / RESOLUTION).astype(np.int64)
    newest_first = np.argsort(-stamps, kind="stable")
    _, first = np.unique(keys[newest_first], axis=0, return_index=True)
    keep = np.sort(newest_first[first])
    return points[keep], stamps[keep]
