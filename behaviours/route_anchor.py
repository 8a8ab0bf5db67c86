"""Where the route's places lie in the repeat's odometry frame: anchored at the last viewframe reached.

An LT-map taught with odometry keeps each viewframe's place (``LandmarkTree.place``, the teach's
odometry frame). The repeat's odometry has its own origin, so a place means nothing to the base
until the two frames are tied. A switch ties them: when :class:`~behaviours.route.ViewframeSwitch`
moves on from viewframe ``v``, the robot stands at ``v``'s place (within the switching radius),
and Z-infinity's rotation against ``v`` (the robot's heading in the viewframe's frame, which is
the teach's odometry frame: stored bearings are compensated by the teaching robot's heading) gives
the angle between the frames. From then on, a place ``p`` of the route lies in the repeat's
odometry at ``o + R(theta_o - heading) (p - place(v))``, ``o`` the odometry pose at the switch.

This is a departure from the paper, which follows by vision alone; bearnav drives along the taught
odometry and corrects the heading by vision. Here odometry only carries the robot on through the
route's places while too few landmarks match (people hiding the view), and only when asked
(``FollowRoute``'s ``odometry_reach``): measured, it got home no more often (docs/ltmap.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from perception.geometry import Pose2D


@dataclass(frozen=True, slots=True)
class RouteAnchor:
    """The tie between the teach's odometry frame and the repeat's, made at a switch.

    ``viewframe``: the viewframe reached; ``odometry``: the repeat's odometry pose then;
    ``heading``: the robot's heading then in the teach's frame (Z-infinity's rotation, rad).
    """

    viewframe: int
    odometry: Pose2D
    heading: float

    def to_odometry(self, reached_place: np.ndarray, place: np.ndarray) -> np.ndarray:
        """Where ``place`` (teach frame) lies in the repeat's odometry frame, given where the
        viewframe reached was taught (``reached_place``)."""
        turn = self.odometry.theta - self.heading  # teach frame -> repeat odometry frame
        c, s = math.cos(turn), math.sin(turn)
        dx, dy = np.asarray(place, dtype=float) - np.asarray(reached_place, dtype=float)
        return np.array([self.odometry.x + c * dx - s * dy, self.odometry.y + s * dx + c * dy])
