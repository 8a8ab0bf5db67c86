"""How far a homing's sidestep may go by what the range sensors show, judged before it starts.

A homing measures its way: a sidestep of known length for the third image
(:mod:`behaviours.roadmap.homing`). Started blind, a sidestep towards a desk a few decimetres away
is held by the avoidance (``AvoidObstacles``: it waits, then drives a detour, which cannot help a
measured step) or stopped by the collision monitor, and the homing and the detour fight: beside
a desk, a navigation took minutes. So the homing judges the step against the echoes around the
base first (:func:`straight_reach`), and takes the other side or a shorter step.

The rule mirrors the collision monitor's stop zone (docs/failure.md): a sensed point counts when
the robot's disc, driving straight on, would touch it within the move plus the monitor's sweep
(:data:`perception.collision_monitor.SWEEP_LENGTH`); the move may go as far as the disc grown by
``clearance`` goes before it meets such a point. A point beside the way, which the disc passes
however near, counts for nothing.
"""

from __future__ import annotations

import math

import numpy as np

from perception.arc_sweep import contact_times
from perception.collision_monitor import SWEEP_LENGTH
from perception.polygons import disc

CLEARANCE = 0.10  # m: kept ahead of a move; the collision monitor's default stop margin (footprint grown by 0.10 m)


def straight_reach(points: np.ndarray, radius: float, direction: float, length: float,
                   clearance: float = CLEARANCE) -> float:
    """Metres a disc robot of ``radius`` may drive straight in ``direction`` (rad in the base frame,
    0 ahead, left positive; backwards is ``pi``) on a move of ``length`` metres, before a sensed point
    (``points``, base frame, N x 2) would hold it (module docstring); ``inf`` when nothing does."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    c, s = math.cos(direction), math.sin(direction)
    if len(pts) == 0:
        return math.inf
    along = np.column_stack((c * pts[:, 0] + s * pts[:, 1], -s * pts[:, 0] + c * pts[:, 1]))  # the move along +x
    touched = contact_times(disc(radius), along, 1.0, 0.0) <= length + SWEEP_LENGTH  # at 1 m/s, seconds are metres
    if not touched.any():
        return math.inf
    return float(contact_times(disc(radius + clearance), along[touched], 1.0, 0.0).min())
