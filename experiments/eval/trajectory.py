"""The robot's true trajectory in a run report: one reader for every evaluation (ground truth,
evaluation only: the behaviours never see it).

A report's ``ground_truth`` section holds the decimated ``trajectory`` (rows t, x, y, theta in the
world frame) and ``stops``, every stretch the robot stood still with its exact pose (rows
t_first, t_last, x, y, theta; see ``drivers.sim.simulation``). Between rows the pose is
interpolated, the heading along the shorter way round (the headings are unwrapped first).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cached_property
from typing import Any

import numpy as np

from perception.geometry import Pose2D, wrap_angle


class TrueTrajectory:
    """Where the robot truly was at any time of a run, from its report's ``ground_truth`` section.
    Before the first row or after the last, the first or last pose."""

    def __init__(self, ground_truth: Mapping[str, Any]) -> None:
        rows = np.asarray(ground_truth["trajectory"], dtype=np.float64).reshape(-1, 4)
        if not len(rows):
            raise ValueError("the ground truth has an empty trajectory")
        self.t, self.xy = rows[:, 0], rows[:, 1:3]
        self.theta = np.unwrap(rows[:, 3])
        self.stops = np.asarray(ground_truth.get("stops", []), dtype=np.float64).reshape(-1, 5)

    @cached_property
    def length(self) -> np.ndarray:
        """The true path length (m) driven up to each row."""
        steps = np.hypot(*np.diff(self.xy, axis=0).T) if len(self.t) > 1 else np.zeros(0)
        return np.concatenate(([0.0], np.cumsum(steps)))

    def position(self, t: float) -> np.ndarray:
        """(x, y) at time ``t`` (s of simulated time), interpolated between the rows."""
        return np.array([np.interp(t, self.t, self.xy[:, 0]), np.interp(t, self.t, self.xy[:, 1])])

    def interpolated(self, t: float) -> Pose2D:
        """The pose at time ``t`` interpolated between the rows, the heading continuous (not wrapped)."""
        x, y = (float(np.interp(t, self.t, self.xy[:, i])) for i in (0, 1))
        return Pose2D(x, y, float(np.interp(t, self.t, self.theta)))

    def at(self, t: float) -> Pose2D:
        """The true pose at time ``t``: exact within a stop (an image is taken standing still, and the
        decimated rows would blur a turn that starts right after it), else :meth:`interpolated`
        with the heading wrapped."""
        within = np.flatnonzero((self.stops[:, 0] <= t) & (t <= self.stops[:, 1]))
        if len(within):
            _, _, x, y, theta = self.stops[within[0]]
            return Pose2D(float(x), float(y), float(theta), stamp=t)
        pose = self.interpolated(t)
        return Pose2D(pose.x, pose.y, wrap_angle(pose.theta), stamp=t)

    def path_length(self, t: float) -> float:
        """The true path length (m) driven by time ``t``."""
        return float(np.interp(t, self.t, self.length))
