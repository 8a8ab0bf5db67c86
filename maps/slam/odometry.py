"""Odometry's turns calibrated against what the cameras see, for the stretches where they see nothing.

A Pioneer's odometry counts every turn a little wrong (a mis-calibrated axle: the simulator's counts
98 % of it), and exploration turns a lot. While the stereo pair tracks landmarks this does not
matter; when it loses them (a close wall with little texture, a turn towards bare floor) the
heading drifts by that error for as long as the loss lasts: 3 degrees in a 3-second turn, enough to
smear a door jamb into the doorway of the exploration map. So the SLAM learns the factor: over
consecutive frames that both corrected the pose, it compares the heading change the cameras gave
(``dv``) with the one odometry counted (``do``), and takes the least-squares slope through the origin

    s = sum(do dv) / sum(do^2)                                                             (O1)

once odometry has counted ``min_turn`` of turning in such pairs (before that, 1), kept within
``bounds``. The prediction then turns by ``s do`` (:func:`calibrated`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from perception.geometry import Pose2D


@dataclass(frozen=True, slots=True)
class TurnCalibration:
    """The running sums of (O1) and the factor they give."""

    scale: float = 1.0
    products: float = 0.0  # sum of do dv (rad^2)
    squares: float = 0.0  # sum of do^2 (rad^2)
    turned: float = 0.0  # sum of |do| (rad)
    min_turn: float = 2.0 * math.pi
    bounds: tuple[float, float] = (0.9, 1.1)

    def add(self, odometry_turn: float, visual_turn: float) -> TurnCalibration:
        """One more pair of heading changes (rad): odometry's and the cameras'."""
        products = self.products + odometry_turn * visual_turn
        squares = self.squares + odometry_turn**2
        turned = self.turned + abs(odometry_turn)
        scale = self.scale
        if turned >= self.min_turn and squares > 0.0:
            scale = min(max(products / squares, self.bounds[0]), self.bounds[1])  # (O1)
        return replace(self, scale=scale, products=products, squares=squares, turned=turned)


def calibrated(corrected: Pose2D, last: Pose2D, odometry: Pose2D, scale: float) -> Pose2D:
    """The calibrated odometry after the raw increment from ``last`` to ``odometry``: ``corrected``
    followed by that increment (in the robot's frame) with its turn multiplied by ``scale``."""
    step = odometry.relative_to(last)
    return corrected.compose(Pose2D(step.x, step.y, scale * step.theta, odometry.stamp))
