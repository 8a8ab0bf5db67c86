"""Where the stereo pair on the pan-tilt unit looks while the robot drives (algorithm 3, eq. 2-5).

:class:`WatchInterestEdges` watches interest edges: it pans to keep an edge's closer point in view
up to 90 degrees, follows it until it leaves the image (eq. 3), turns back (eq. 4: only so far
that the robot's path ahead stays in the image) or to the remembered P_A on the other side,
alternates sides, lifts the cameras by eq. 5, and limits the robot's speed when the pan rate cannot
keep up (written to ``speed_limit``, which path following reads). The decision is
:func:`maps.exploration.gaze.next_gaze`, re-evaluated every tick from the current pose and map (the
map re-classifies edges as the robot moves, eq. 2). ``mode: fixed`` keeps the cameras looking
ahead (the evaluation's comparison). Safety comes first: while path following reports unseen floor
on the path ahead (``unseen_ahead``), the cameras look there instead (the robot would stop before
it otherwise; see :mod:`behaviours.exploration.follow_path`). The look-around while the robot
stands is :class:`behaviours.exploration.look_around.LookAround`.

It commands the head through ``/ptu/command`` (:class:`~drivers.interfaces.PanTiltCommand`),
within the limits and the speed the unit reports (:mod:`behaviours.exploration.head`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import replace
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.exploration.head import HEAD_PORTS, PTU_COMMAND, PTU_STATE, gaze_params, head_command, unit_params
from behaviours.exploration.ports import MAP, POSE, ROBOT_RADIUS, disc_radius
from behaviours.footprint import FOOTPRINT
from behaviours.ports import InputPort, OutputPort
from behaviours.registry import register
from behaviours.telemetry import Arrows, Drawing, Figure, Points
from drivers.interfaces import PanTiltCommand
from maps.exploration.gaze import LEAVE_RULES, TURN_BACK_RULES, Gaze, next_gaze, pan_to_point
from perception.geometry import Pose2D


@register
class WatchInterestEdges(BearingsBehaviour):
    """Watch interest edges with the pan-tilt cameras while the robot drives (eq. 2-5).

    Every tick, from the pose and the map: the edge to watch (a *watch now* edge, nearest first;
    alternating sides every ``dwell`` seconds, remembering the other side's edge P_A; a point that
    leaves the view, by eq. 3 (``leave: eq3``) or once past +-``max_pan`` (``leave: pan_limit``),
    is retired and the head turns to P_A or back), pan = its bearing (at most ``max_pan``), tilt =
    eq. 5 (rounded to ``tilt_step``), and the speed at which the pan rate (times ``rate_margin``)
    still keeps up to ``speed_limit`` (``max_speed`` without a limit). Nothing to watch: at
    ``home_tilt``, turned back to eq. 4's delta on the side last watched (``turn_back: eq4``, the
    far edge of the robot's path ``keep_ahead`` ahead kept in the image) or straight ahead
    (``turn_back: front``, and before any edge was watched). ``mode: fixed``: straight ahead always.
    Unseen floor on the path ahead (``unseen_ahead``, from path following): the cameras look at it,
    whatever the mode (the edge state carries on meanwhile). RUNNING for ever (it runs beside path
    following); it never fails.
    """

    MODE = InputPort("mode", str, "edges", choices=("edges", "fixed"), literal_only=True,
                     doc="edges: watch interest edges; fixed: cameras straight ahead")
    HOME_TILT = InputPort("home_tilt", float, -35.0, unit="deg", minimum=-90.0, maximum=90.0, literal_only=True,
                          doc="tilt with nothing to watch (-35: the floor from ~0.6 m to the explore range)")
    MAX_PAN = InputPort("max_pan", float, 90.0, unit="deg", minimum=0.0, maximum=180.0, literal_only=True,
                        doc="follow a point up to this far off the heading")
    RATE_MARGIN = InputPort("rate_margin", float, 0.8, minimum=0.05, maximum=1.0, literal_only=True,
                            doc="plan with this fraction of the pan rate (the speed limit)")
    DWELL = InputPort("dwell", float, 1.5, unit="s", minimum=0.1, maximum=60.0, literal_only=True,
                      doc="watch one side this long when the other has an edge too")
    TILT_STEP = InputPort("tilt_step", float, 5.0, unit="deg", minimum=0.0, maximum=45.0, literal_only=True,
                          doc="tilt targets are rounded to this (the head holds still through small changes)")
    MAX_SPEED = InputPort("max_speed", float, 1.2, unit="m/s", minimum=0.01, maximum=5.0, literal_only=True,
                          doc="the speed limit written when the pan rate sets none")
    TURN_RATE = InputPort("turn_rate", float, 0.0, unit="rad/s",
                          doc="the robot's commanded turn rate (it enters the speed limit)")
    NEAR_FLOOR = InputPort("near_floor", float, 0.8, unit="m", minimum=0.0, maximum=10.0, literal_only=True,
                           doc="unseen floor nearer than this to the pan axis is looked at from this far")
    UNSEEN_AHEAD = InputPort("unseen_ahead", Pose2D, None,
                             doc="unseen floor on the path ahead ({/robot/unseen_ahead}): look there first")
    SPEED_LIMIT = OutputPort("speed_limit", float, "/robot/speed_limit", unit="m/s",
                             doc="the top forward speed at which the pan keeps up")
    GAZE = OutputPort("gaze", Gaze, "/map/gaze", doc="the gaze state: edge watched, P_A, side, edges done")
    LEAVE = InputPort("leave", str, "eq3", choices=LEAVE_RULES, literal_only=True,
                      doc="eq3: follow a point until it leaves the image (eq. 3); pan_limit: until it passes max_pan")
    TURN_BACK = InputPort("turn_back", str, "eq4", choices=TURN_BACK_RULES, literal_only=True,
                          doc="eq4: turn back only so far that the path ahead stays in view (eq. 4); front: ahead")
    KEEP_AHEAD = InputPort("keep_ahead", float, 1.0, unit="m", minimum=0.1, maximum=10.0, literal_only=True,
                           doc="eq. 4's a: the far edge of the path this far ahead stays in the image")
    PORTS = (MODE, HOME_TILT, MAX_PAN, RATE_MARGIN, DWELL, TILT_STEP, MAX_SPEED, *HEAD_PORTS, TURN_RATE, NEAR_FLOOR,
             UNSEEN_AHEAD, MAP, POSE, PTU_COMMAND, SPEED_LIMIT, GAZE, LEAVE, TURN_BACK, KEEP_AHEAD, ROBOT_RADIUS,
             FOOTPRINT, PTU_STATE)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.asked = gaze_params(self, max_pan=math.radians(self.get_input(self.MAX_PAN)),
                                 rate_margin=self.get_input(self.RATE_MARGIN),
                                 home_tilt=math.radians(self.get_input(self.HOME_TILT)),
                                 dwell=self.get_input(self.DWELL), leave=self.get_input(self.LEAVE),
                                 turn_back=self.get_input(self.TURN_BACK), keep_ahead=self.get_input(self.KEEP_AHEAD),
                                 keep_across=self.get_input(ROBOT_RADIUS))  # 0: the footprint's (first tick)
        self._sized = False
        self.params = self.asked
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
        pan = float(pan_to_point(pose, axis, np.array([point.x, point.y]))[0])
        distance = max(math.hypot(point.x - axis[0], point.y - axis[1]), self.get_input(self.NEAR_FLOOR))
        return pan, math.atan2(-head.lens_height, distance)

    def update(self) -> Status:
        m, pose, unit = self.get_input(MAP, None), self.get_input(POSE, None), self.get_input(PTU_STATE, None)
        if not self._sized:  # the robot's footprint is on the blackboard once the tree runs
            self._sized, self.asked = True, replace(self.asked, keep_across=disc_radius(self))
        self.params = p = unit_params(self.asked, unit)
        top = self.get_input(self.MAX_SPEED)
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
        self.command = head_command(float(pan), tilt, p, unit)
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
