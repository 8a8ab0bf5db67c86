"""The robot's footprint as nodes that plan round obstacles read it: the robot's own, not a number.

The runner publishes the collision monitor's footprint before the first tick (``/robot/footprint``:
the box ARIA gives for the Pioneer model the base reports, the simulator's robot disc, or the
profile's ``safety.footprint``). A node that keeps the robot clear of obstacles (the avoidance's
sweeps, the exploration planner's disc) reads it through :data:`FOOTPRINT` so that a bigger robot
(a P3-AT, a world's ``robot: radius``) is planned for as it is; a mission may still set a radius
of its own. A node run without the runner (a unit test on a hand-set blackboard) gets
:data:`DEFAULT_FOOTPRINT`.
"""

from __future__ import annotations

import numpy as np

from behaviours.keys import FOOTPRINT_KEY
from behaviours.ports import InputPort, Ref
from perception.polygons import as_polygon, disc, enclosing_radius

DEFAULT_RADIUS = 0.26  # m: a Pioneer 3-DX's RobotRadius (ARIA's p3dx.p), the simulator's default disc
DEFAULT_FOOTPRINT = disc(DEFAULT_RADIUS)
FOOTPRINT = InputPort("footprint", np.ndarray, Ref(FOOTPRINT_KEY.path), unit="m", doc=FOOTPRINT_KEY.doc)


def footprint_of(node: object) -> np.ndarray:
    """The footprint ``node`` reads on its :data:`FOOTPRINT` port (:data:`DEFAULT_FOOTPRINT` when
    nothing published one), as a counter-clockwise polygon."""
    return as_polygon(node.get_input(FOOTPRINT, DEFAULT_FOOTPRINT))  # type: ignore[attr-defined]


def robot_radius(node: object, given: float) -> float:
    """``given`` when set (> 0), else the radius of the disc round the robot's own footprint
    (:data:`DEFAULT_RADIUS` when nothing published one)."""
    if given > 0.0:
        return given
    footprint = node.get_input(FOOTPRINT, None)  # type: ignore[attr-defined]
    return DEFAULT_RADIUS if footprint is None else enclosing_radius(as_polygon(footprint))
