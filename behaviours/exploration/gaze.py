"""Where the stereo pair on the pan-tilt unit looks during exploration (algorithm 3, eq. 2-5).

- :class:`WatchInterestEdges` watches interest edges while the robot drives: it pans to keep an
  edge's closer point in view up to 90 degrees (eq. 3), limits the robot's speed when the pan rate
  cannot keep up (eq. 4; written to ``speed_limit``, which path following reads), turns back when
  the point leaves the view, alternates sides remembering P_A, and lifts the cameras by eq. 5. The
  decision is :func:`maps.exploration.gaze.next_gaze`, re-evaluated every tick from the current
  pose and map (the map re-classifies edges as the robot moves, eq. 2). ``mode: fixed`` keeps the
  cameras looking ahead (the evaluation's comparison). Safety comes first: while path following
  reports unseen floor on the path ahead (``unseen_ahead``), the cameras look there instead (the
  robot would stop before it otherwise; see :mod:`behaviours.exploration.follow_path`).
- :class:`LookAround` steps the head through :func:`maps.exploration.gaze.survey` while the robot
  stands: at the start (the first footprints join the robot's disc) and as a recovery.

Both command the head through ``/ptu/command`` (:class:`~drivers.interfaces.PanTiltCommand`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.exploration.ports import CAMERA_POSITION, MAP, POSE, PTU_POSITION, xyz
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.telemetry import Arrows, Drawing, Figure, Points
from drivers.interfaces import PanTiltCommand, PanTiltState
from maps.exploration.gaze import Gaze, GazeParams, next_gaze, pan_to_point, survey
from maps.exploration.head import StereoHead
from perception.geometry import Pose2D

# The simulator's default stereo pair: 640 x 480, f = 525 px.
VERTICAL_FOV = InputPort("vertical_fov", float, math.degrees(2.0 * math.atan(240.0 / 525.0)), unit="deg",
                         minimum=1.0, maximum=179.0, literal_only=True, doc="the stereo camera's vertical field")
HORIZONTAL_FOV = InputPort("horizontal_fov", float, math.degrees(2.0 * math.atan(320.0 / 525.0)), unit="deg",
                           minimum=1.0, maximum=179.0, literal_only=True, doc="the stereo camera's horizontal field")
PAN_LIMITS = InputPort("pan_limits", list[float], [-159.0, 159.0], unit="deg", literal_only=True,
                       doc="the pan-tilt unit's pan range")
TILT_LIMITS = InputPort("tilt_limits", list[float], [-47.0, 31.0], unit="deg", literal_only=True,
                        doc="the pan-tilt unit's tilt range (positive looks up)")
PAN_RATE = InputPort("pan_rate", float, 300.0, unit="deg/s", minimum=1.0, maximum=3600.0, literal_only=True,
                     doc="the unit's top slew rate")
PTU_COMMAND = OutputPort("ptu_command", PanTiltCommand, "/ptu/command", unit="rad, rad, rad/s",
                         doc="where the head should look (the runner sends it to the unit)")


def _limits(values: list[float], what: str) -> tuple[float, float]:
    if len(values) != 2 or values[0] >= values[1]:
        raise ValueError(f"{what} is [low, high] in degrees, got {values}")
    return math.radians(values[0]), math.radians(values[1])


def gaze_params(node: BearingsBehaviour, **extra: Any) -> GazeParams:
    """The :class:`GazeParams` a gaze node's literal ports describe."""
    head = StereoHead(xyz(node.get_input(PTU_POSITION), "ptu_position"),
                      xyz(node.get_input(CAMERA_POSITION), "camera_position"),
                      math.radians(node.get_input(VERTICAL_FOV)), math.radians(node.get_input(HORIZONTAL_FOV)))
    return GazeParams(head=head, pan_rate=math.radians(node.get_input(PAN_RATE)),
                      pan_limits=_limits(node.get_input(PAN_LIMITS), "pan_limits"),
                      tilt_limits=_limits(node.get_input(TILT_LIMITS), "tilt_limits"), **extra)


HEAD_PORTS = (PAN_RATE, PAN_LIMITS, TILT_LIMITS, VERTICAL_FOV, HORIZONTAL_FOV, PTU_POSITION,
              CAMERA_POSITION)  # the pan-tilt head's ports


@register
class WatchInterestEdges(BearingsBehaviour):
    """Watch interest edges with the pan-tilt cameras while the robot drives (eq. 2-5).

    Every tick, from the pose and the map: the edge to watch (a *watch now* edge, nearest first;
    alternating sides every ``dwell`` seconds, remembering the other side's edge P_A; a point that
    leaves +-``max_pan`` is retired and the head turns to P_A or back to the front), pan = its
    bearing (eq. 3), tilt = eq. 5 (rounded to ``tilt_step``), and the speed at which the pan rate
    (times ``rate_margin``) still keeps up (eq. 4) to ``speed_limit`` (``max_speed`` without a
    limit). Nothing to watch: straight ahead at ``home_tilt``. ``mode: fixed``: always that.
    Unseen floor on the path ahead (``unseen_ahead``, from path following): the cameras look at it,
    whatever the mode (the edge state carries on meanwhile). RUNNING for ever (it runs beside path
    following); it never fails.
    """

    MODE = InputPort("mode", str, "edges", choices=("edges", "fixed"), literal_only=True,
                     doc="edges: watch interest edges; fixed: cameras straight ahead")
    HOME_TILT = InputPort("home_tilt", float, -35.0, unit="deg", minimum=-90.0, maximum=90.0, literal_only=True,
                          doc="tilt with nothing to watch (-35: the floor from ~0.6 m to the explore range)")
    MAX_PAN = InputPort("max_pan", float, 90.0, unit="deg", minimum=0.0, maximum=180.0, literal_only=True,
                        doc="follow a point up to this far off the heading (eq. 3)")
    RATE_MARGIN = InputPort("rate_margin", float, 0.8, minimum=0.05, maximum=1.0, literal_only=True,
                            doc="plan with this fraction of the pan rate (eq. 4)")
    DWELL = InputPort("dwell", float, 1.5, unit="s", minimum=0.1, maximum=60.0, literal_only=True,
                      doc="watch one side this long when the other has an edge too")
    TILT_STEP = InputPort("tilt_step", float, 5.0, unit="deg", minimum=0.0, maximum=45.0, literal_only=True,
                          doc="tilt targets are rounded to this (the head holds still through small changes)")
    MAX_SPEED = InputPort("max_speed", float, 1.2, unit="m/s", minimum=0.01, maximum=5.0, literal_only=True,
                          doc="the speed limit written when eq. 4 sets none")
    TURN_RATE = InputPort("turn_rate", float, 0.0, unit="rad/s", doc="the robot's commanded turn rate (eq. 4)")
    NEAR_FLOOR = InputPort("near_floor", float, 0.8, unit="m", minimum=0.0, maximum=10.0, literal_only=True,
                           doc="unseen floor nearer than this to the pan axis is looked at from this far")
    UNSEEN_AHEAD = InputPort("unseen_ahead", Pose2D, None,
                             doc="unseen floor on the path ahead ({/robot/unseen_ahead}): look there first")
    SPEED_LIMIT = OutputPort("speed_limit", float, "/robot/speed_limit", unit="m/s",
                             doc="the top forward speed at which the pan keeps up (eq. 4)")
    GAZE = OutputPort("gaze", Gaze, "/map/gaze", doc="the gaze state: edge watched, P_A, side, edges done")
    PORTS = (MODE, HOME_TILT, MAX_PAN, RATE_MARGIN, DWELL, TILT_STEP, MAX_SPEED, *HEAD_PORTS, TURN_RATE, NEAR_FLOOR,
             UNSEEN_AHEAD, MAP, POSE, PTU_COMMAND, SPEED_LIMIT, GAZE)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.params = gaze_params(self, max_pan=math.radians(self.get_input(self.MAX_PAN)),
                                  rate_margin=self.get_input(self.RATE_MARGIN),
                                  home_tilt=math.radians(self.get_input(self.HOME_TILT)),
                                  dwell=self.get_input(self.DWELL))
        self.gaze = Gaze()
        self.point: np.ndarray | None = None
        self.command: PanTiltCommand | None = None
        self.watch_ticks = 0
        self.ticks = 0
        self.limited_ticks = 0
        self.switches = 0
        self.edges_watched: set[int] = set()
        self.look_ahead_ticks = 0

    def _look_at(self, pose: Pose2D, point: Pose2D) -> tuple[float, float]:
        """Pan and tilt that centre a floor point in the image, or the nearest floor the cameras can
        see in its direction (``near_floor`` from the pan axis: nearer, stereo finds no depth)."""
        head = self.params.head
        axis = head.axis_xy(pose)
        pan = float(pan_to_point(pose, axis, np.array([point.x, point.y]))[0])  # eq. 3
        distance = max(math.hypot(point.x - axis[0], point.y - axis[1]), self.get_input(self.NEAR_FLOOR))
        return float(np.clip(pan, *self.params.pan_limits)), math.atan2(-head.lens_height, distance)

    def update(self) -> Status:
        m, pose = self.get_input(MAP, None), self.get_input(POSE, None)
        p, top = self.params, self.get_input(self.MAX_SPEED)
        pan, tilt, limit, self.point = 0.0, p.home_tilt, top, None
        if m is not None and pose is not None and self.get_input(self.MODE) == "edges":
            turn = self.get_input(self.TURN_RATE, 0.0) or 0.0
            before = self.gaze.target
            self.gaze, cmd = next_gaze(self.gaze, m, pose, self.now(), p, turn_rate=turn)
            pan, tilt, limit, self.point = cmd.pan, cmd.tilt, min(cmd.max_speed, top), cmd.point
            if self.gaze.target is not None:
                self.watch_ticks += 1
                self.edges_watched.add(self.gaze.target)
                self.switches += int(before is not None and before != self.gaze.target)
        unseen = self.get_input(self.UNSEEN_AHEAD, None)
        if unseen is not None and pose is not None:
            pan, tilt = self._look_at(pose, unseen)
            self.look_ahead_ticks += 1
        self.ticks += 1
        self.limited_ticks += int(limit < top)
        step = math.radians(self.get_input(self.TILT_STEP))
        if step > 0.0:
            tilt = float(np.clip(round(tilt / step) * step, *p.tilt_limits))
        self.command = PanTiltCommand(float(pan), tilt, p.pan_rate)
        self.set_output(PTU_COMMAND, self.command)
        self.set_output(self.SPEED_LIMIT, limit)
        self.set_output(self.GAZE, self.gaze)
        self.feedback_message = ("looking ahead" if self.point is None else
                                 f"watching edge {self.gaze.target} at pan {math.degrees(pan):.0f} deg"
                                 + (f", speed <= {limit:.2f} m/s" if limit < top else ""))
        return Status.RUNNING

    def figures(self) -> Iterator[Figure]:
        """The ``exploration`` section's gaze part."""
        share = self._share
        yield from (Figure("exploration", name, value) for name, value in (
            ("gaze_mode", self.get_input(self.MODE)),
            ("gaze_watching_fraction", share(self.watch_ticks)),
            ("gaze_edges_watched", len(self.edges_watched)),
            ("gaze_switches", self.switches),
            ("gaze_speed_limited_fraction", share(self.limited_ticks)),
            ("gaze_look_ahead_fraction", share(self.look_ahead_ticks)),
        ))

    def _share(self, ticks: int) -> float:
        """The fraction of the ticks so far (0 before the first)."""
        return ticks / self.ticks if self.ticks else 0.0

    def drawings(self) -> Iterator[Drawing]:
        """Where the cameras look: a ray from the pan axis, and the watched point (every tick)."""
        pose, command = self.get_input(POSE, None), self.command
        if pose is None or command is None:
            return
        axis = self.params.head.axis_xy(pose)
        direction = pose.theta + command.pan
        reach = 1.5 * math.cos(command.tilt)
        yield Arrows("odometry_frame/exploration/gaze",
                     np.array([[reach * math.cos(direction), reach * math.sin(direction)]]), (255, 220, 0),
                     origins=axis.reshape(1, 2))
        watched = np.zeros((0, 2)) if self.point is None else self.point[None, :2]
        yield Points("odometry_frame/exploration/watched", watched, (255, 0, 255), radius=0.08)


@register
class LookAround(BearingsBehaviour):
    """Look all around with the pan-tilt cameras while the robot stands; SUCCESS when done.

    The head steps through :func:`maps.exploration.gaze.survey` (rows of tilts from the lowest up
    to the horizon, pans from one limit to the other, fields of view overlapping by ``overlap``),
    holding each pose for ``settle`` seconds once the unit reports it there (so the map integrates
    a frame from it). The base gets no command (the runner stops it).
    """

    OVERLAP = InputPort("overlap", float, 0.15, minimum=0.0, maximum=0.9, literal_only=True,
                        doc="fraction by which neighbouring views overlap")
    SETTLE = InputPort("settle", float, 0.4, unit="s", minimum=0.0, maximum=10.0, literal_only=True,
                       doc="hold each pose this long once there")
    TOLERANCE = InputPort("tolerance", float, 1.0, unit="deg", minimum=0.01, maximum=10.0, literal_only=True,
                          doc="the head is at a pose within this")
    PTU = InputPort("ptu", PanTiltState, Ref("/ptu/state"), doc="where the head is")
    PORTS = (OVERLAP, SETTLE, TOLERANCE, *HEAD_PORTS, PTU, PTU_COMMAND)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.params = gaze_params(self)
        self.poses = survey(self.params, self.get_input(self.OVERLAP))
        self.index = 0
        self.arrived: float | None = None
        self.surveys = 0

    def initialise(self) -> None:
        self.index, self.arrived = 0, None

    def update(self) -> Status:
        pan, tilt = (float(v) for v in self.poses[self.index])
        self.set_output(PTU_COMMAND, PanTiltCommand(pan, tilt, self.params.pan_rate))
        state = self.get_input(self.PTU, None)
        tolerance = math.radians(self.get_input(self.TOLERANCE))
        there = state is not None and not state.moving and abs(state.pan - pan) <= tolerance and abs(
            state.tilt - tilt) <= tolerance
        self.feedback_message = f"view {self.index + 1} of {len(self.poses)}"
        if not there:
            self.arrived = None
            return Status.RUNNING
        if self.arrived is None:
            self.arrived = self.now()
        if self.now() - self.arrived < self.get_input(self.SETTLE):
            return Status.RUNNING
        self.index, self.arrived = self.index + 1, None
        if self.index < len(self.poses):
            return Status.RUNNING
        self.surveys += 1
        self.index = 0
        return Status.SUCCESS

    def figures(self) -> Iterator[Figure]:
        """How many look-arounds were made (the start's and the recoveries')."""
        yield Figure("exploration", f"look_arounds_{self.name.replace(' ', '_')}", self.surveys)

