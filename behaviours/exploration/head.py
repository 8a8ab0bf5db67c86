"""The pan-tilt head as the exploration's head behaviours see it: its ports, and what the unit reports.

The ports (:data:`HEAD_PORTS`) say what a mission asks for: the pan and tilt ranges, the slew rate,
the stereo pair's fields of view and where it sits. The unit has the last word: a PTU-D46 reports
+-3090 positions of 185.1428 arc-seconds (+-158.91 deg, not the data sheet's 159) and a top speed
of 2902 positions/s (149 deg/s); the simulator's unit reports the world file's. :func:`unit_params`
keeps the asked-for ranges within those the unit reports in ``/ptu/state``
(:class:`~drivers.interfaces.PanTiltLimits`) and the rate within its top speed, and
:func:`head_command` clips every target into them, rounded to the unit's position step. A driver that
reports no limits (``limits`` None) leaves the ports as they are.
"""

from __future__ import annotations

import functools
import math
from typing import Any

from behaviours.base import BearingsBehaviour
from behaviours.exploration.ports import CAMERA_POSITION, PTU_POSITION, xyz
from behaviours.ports import InputPort, OutputPort, Ref
from drivers.interfaces import PanTiltCommand, PanTiltLimits, PanTiltState
from maps.exploration.gaze import GazeParams
from maps.exploration.head import StereoHead

# The simulator's default stereo pair: 640 x 480, f = 525 px.
VERTICAL_FOV = InputPort("vertical_fov", float, math.degrees(2.0 * math.atan(240.0 / 525.0)), unit="deg",
                         minimum=1.0, maximum=179.0, literal_only=True, doc="the stereo camera's vertical field")
HORIZONTAL_FOV = InputPort("horizontal_fov", float, math.degrees(2.0 * math.atan(320.0 / 525.0)), unit="deg",
                           minimum=1.0, maximum=179.0, literal_only=True, doc="the stereo camera's horizontal field")
PAN_LIMITS = InputPort("pan_limits", list[float], [-159.0, 159.0], unit="deg", literal_only=True,
                       doc="the pan range to use (within what the unit reports)")
TILT_LIMITS = InputPort("tilt_limits", list[float], [-47.0, 31.0], unit="deg", literal_only=True,
                        doc="the tilt range to use, positive looks up (within what the unit reports)")
PAN_RATE = InputPort("pan_rate", float, 300.0, unit="deg/s", minimum=1.0, maximum=3600.0, literal_only=True,
                     doc="the slew rate to use (at most the unit's top speed)")
PTU_COMMAND = OutputPort("ptu_command", PanTiltCommand, "/ptu/command", unit="rad, rad, rad/s",
                         doc="where the head should look (the runner sends it to the unit)")
PTU_STATE = InputPort("ptu", PanTiltState, Ref("/ptu/state"),
                      doc="where the head is, and the limits, step and speeds the unit reports")

HEAD_PORTS = (PAN_RATE, PAN_LIMITS, TILT_LIMITS, VERTICAL_FOV, HORIZONTAL_FOV, PTU_POSITION,
              CAMERA_POSITION)  # the pan-tilt head's ports


def _limits(values: list[float], what: str) -> tuple[float, float]:
    if len(values) != 2 or values[0] >= values[1]:
        raise ValueError(f"{what} is [low, high] in degrees, got {values}")
    return math.radians(values[0]), math.radians(values[1])


def gaze_params(node: BearingsBehaviour, **extra: Any) -> GazeParams:
    """The :class:`GazeParams` a gaze node's literal ports describe (before the unit has a say)."""
    head = StereoHead(xyz(node.get_input(PTU_POSITION), "ptu_position"),
                      xyz(node.get_input(CAMERA_POSITION), "camera_position"),
                      math.radians(node.get_input(VERTICAL_FOV)), math.radians(node.get_input(HORIZONTAL_FOV)))
    return GazeParams(head=head, pan_rate=math.radians(node.get_input(PAN_RATE)),
                      pan_limits=_limits(node.get_input(PAN_LIMITS), "pan_limits"),
                      tilt_limits=_limits(node.get_input(TILT_LIMITS), "tilt_limits"), **extra)


def unit_params(asked: GazeParams, state: PanTiltState | None) -> GazeParams:
    """``asked`` kept within what the unit reports in ``state`` (unchanged without a report)."""
    if state is None or state.limits is None:
        return asked
    return _within(asked, state.limits)


@functools.lru_cache(maxsize=8)
def _within(asked: GazeParams, limits: PanTiltLimits) -> GazeParams:
    return asked.within(limits.pan, limits.tilt, limits.max_speed)


def head_command(pan: float, tilt: float, params: GazeParams, state: PanTiltState | None) -> PanTiltCommand:
    """A command to (pan, tilt) at the rate of ``params``, clipped into the unit's reported limits and
    rounded to its position step (into ``params``' ranges when the unit reports none)."""
    limits = None if state is None else state.limits
    pan = min(max(pan, params.pan_limits[0]), params.pan_limits[1])
    tilt = min(max(tilt, params.tilt_limits[0]), params.tilt_limits[1])
    if limits is None:
        return PanTiltCommand(pan, tilt, params.pan_rate)
    pan, tilt = limits.clip(pan, tilt)
    return PanTiltCommand(pan, tilt, limits.clip_speed(params.pan_rate))
