"""Obstacle points of the last second, kept in the odometry frame.

A sonar ring sees little at a time: sixteen cones 30 degrees wide, with gaps beside the robot
(between the 50 and 90 degree transducers), each fired in turn. A person the robot is passing
slips out of one cone before the next one hears them, and an arc chosen on the last scan alone
would turn into them. So the echoes of the last ``keep`` seconds are remembered where odometry
says they were (odometry drifts little in a second) and all of them are judged together. Moving
people leave a short trail of old echoes behind them: ``keep`` is the price of that.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from perception.geometry import Pose2D, frame_to_parent, parent_to_frame

RESOLUTION = 0.01  # m: remembered points closer than this are one


@dataclass(frozen=True, slots=True)
class ObstacleMemory:
    """The echoes of scans not older than ``keep`` seconds (odometry frame), newest last."""

    keep: float = 1.0
    stamps: tuple[float, ...] = ()
    scans: tuple[np.ndarray, ...] = ()

    def added(self, points: np.ndarray, pose: Pose2D, stamp: float) -> ObstacleMemory:
        """With one more scan's points (base frame, taken at ``pose``), older ones dropped. A scan
        already added (same stamp) changes nothing."""
        if self.stamps and stamp == self.stamps[-1]:
            return self
        kept = [(t, p) for t, p in zip(self.stamps, self.scans, strict=True) if t > stamp - self.keep]
        kept.append((stamp, frame_to_parent(pose, points)))
        return ObstacleMemory(self.keep, tuple(t for t, _ in kept), tuple(p for _, p in kept))

    def around(self, pose: Pose2D, now: float) -> np.ndarray:
        """The points of the scans not older than ``keep`` at ``now``, in the base frame of ``pose`` (N x 2)."""
        recent = [p for t, p in zip(self.stamps, self.scans, strict=True) if t >= now - self.keep]
        if not recent:
            return np.zeros((0, 2))
        points = np.vstack(recent)  # a transducer's reading repeats until it fires again: keep one of each
        _, first = np.unique(np.round(points / RESOLUTION).astype(np.int64), axis=0, return_index=True)
        return parent_to_frame(pose, points[np.sort(first)])
