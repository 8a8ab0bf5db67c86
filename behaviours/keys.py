"""The blackboard keys the framework itself reads or writes, outside any mission node.

Namespaces follow docs/design.md: ``/robot``, ``/ptu``, ``/perception``, ``/map``, ``/mission``. Node
types declare the keys they read and write as ports (:mod:`behaviours.ports`); this module lists
only the framework's own ends of the data flow, which the loader's data-flow check adds to what
the mission's nodes declare:

- the runner *reads* the command keys after every tick and sends them to the drivers (so a node
  writing ``/robot/command`` must write a :class:`~drivers.interfaces.VelocityCommand`);
- the runner *writes* every top-level mission input as ``/mission/<input>`` before the first
  tick, so nodes can read inputs at run time (``{/mission/speed}``) as well as at load time
  (``${speed}``);
- the data-gathering branch writes the sensed keys (its nodes' output ports,
  :data:`behaviours.sense.SENSE_NODES`); those the framework itself reads as well are declared
  here (:data:`SENSED_KEYS`: the range sensors, which the collision monitor reads every tick);
- the runner *writes* the collision monitor's verdict on the command it sent at the end of the
  previous tick (:data:`RUNNER_KEYS`: ``/robot/safety``, clear before the first), so a behaviour
  can tell that the robot is being slowed or stopped, and why;
- the runner *writes* the robot's footprint before the first tick (``/robot/footprint``: the
  collision monitor's, from the robot itself), so that nodes that plan round obstacles plan with
  the robot's own outline rather than a number in a mission.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from drivers.interfaces import PanTiltCommand, VelocityCommand
from perception.collision_monitor import SafetyState
from perception.ranges import RangeScan

MISSION_NAMESPACE = "/mission"


@dataclass(frozen=True, slots=True)
class KeySpec:
    """A key the framework reads: its absolute path, value type and meaning."""

    path: str
    type: Any
    doc: str


COMMAND_KEYS = (
    KeySpec("/robot/command", VelocityCommand, "velocity for this tick; cleared before every tick"),
    KeySpec("/ptu/command", PanTiltCommand, "pan/tilt target; cleared before every tick"),
)

SAFETY_KEY = KeySpec("/robot/safety", SafetyState, "the collision monitor on the last command sent: clear, slowed "
                     "or stopped, by which action and zone, and why")
FOOTPRINT_KEY = KeySpec("/robot/footprint", np.ndarray, "the robot's outline, a convex polygon [[x, y], ...] in the "
                        "base frame (m): the collision monitor's (a Pioneer's model as it reports it, the "
                        "simulator's disc, or the profile's safety.footprint)")
RUNNER_KEYS = (SAFETY_KEY, FOOTPRINT_KEY)
"""Keys the runner writes every tick (besides the mission inputs)."""


RANGES_KEY = KeySpec("/robot/ranges", RangeScan,
                     "range sensors and bumpers around the base (sonar ring, bumpers), newest reading")
SENSED_KEYS = (RANGES_KEY,)
"""Sensed keys (written by the data-gathering branch only) that the framework reads too."""


def input_key(name: str) -> str:
    """The blackboard key a mission input is published under."""
    return f"{MISSION_NAMESPACE}/{name}"
