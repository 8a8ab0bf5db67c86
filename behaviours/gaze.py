"""Where the stereo pair on the pan-tilt unit looks during exploration (algorithm 3, eq. 2-5).

- :class:`WatchInterestEdges` watches interest edges while the robot drives: it pans to keep an
  edge's closer point in view up to 90 degrees (eq. 3), limits the robot's speed when the pan rate
  cannot keep up (eq. 4; written to ``speed_limit``, which path following reads), turns back when
  the point leaves the view, alternates sides remembering P_A, and lifts the cameras by eq. 5. The
  decision is :func:`maps.exploration_gaze.next_gaze`, re-evaluated every tick from the current
  pose and map (the map re-classifies edges as the robot moves, eq. 2). ``mode: fixed`` keeps the
  cameras looking ahead (the evaluation's comparison). Safety comes first: while path following
  reports unseen floor on the path ahead (``unseen_ahead``), the cameras look there instead (the
  robot would stop before it otherwise; see :mod:`behaviours.follow_path`).
- :class:`LookAround` steps the head through :func:`maps.exploration_gaze.survey` while the robot
  stands: at the start (the first footprints join the robot's disc) and as a recovery.

Both command the head through ``/ptu/command`` (:class:`~drivers.interfaces.PanTiltCommand`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.exploration import CAMERA_POSITION, MAP, POSE, PTU_POSITION, xyz
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from drivers.interfaces import PanTiltCommand, PanTiltState
from maps.exploration.gaze import Gaze, GazeParams, next_gaze, pan_to_point, survey
from maps.exploration.grid import Cell, ExplorationMap
from maps.exploration.head import StereoHead
from maps.exploration.interest import Interest
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
FREE_COLOUR, OBSTACLE_COLOUR, BORDER_COLOUR = (200, 230, 200), (60, 60, 60), (250, 170, 0)
INTEREST_COLOURS = {Interest.WATCH_NOW: (255, 40, 40), Interest.WATCH_LATER: (255, 200, 0)}


def _limits(values: list[float], what: str) -> tuple[float, float]:
    if len(values) != 2 or values[0] >= values[1]:
        raise ValueError(f"{what} is [low, high] in degrees, got {values}")
    return math.radians(values[0]), math.radians(values[1])


def gaze_params(node: BearingsBehaviour, **extra: Any) -> GazeParams:
    """The :class:`GazeParams` a gaze node's literal ports describe."""
    head = StereoHead(xyz(node.get_input("ptu_position"), "ptu_position"),
                      xyz(node.get_input("camera_position"), "camera_position"),
                      math.radians(float(node.get_input("vertical_fov"))),
                      math.radians(float(node.get_input("horizontal_fov"))))
    return GazeParams(head=head, pan_rate=math.radians(float(node.get_input("pan_rate"))),
                      pan_limits=_limits(node.get_input("pan_limits"), "pan_limits"),
                      tilt_limits=_limits(node.get_input("tilt_limits"), "tilt_limits"), **extra)


def log_map(rec: Any, rr: Any, m: ExplorationMap, border: np.ndarray) -> None:
    """The exploration map in rerun, odometry frame: explored / obstacle / border cells as an image
    placed on the floor, the points (3-D, a sample) and the interest edges not yet *never*."""
    f = m.frame
    image = np.zeros((*f.shape, 4), dtype=np.uint8)
    image[m.cells == Cell.FREE] = (*FREE_COLOUR, 255)
    image[m.cells == Cell.OBSTACLE] = (*OBSTACLE_COLOUR, 255)
    image[border] = (*BORDER_COLOUR, 255)
    rec.log("odometry_frame/exploration/map", rr.Image(image[::-1]))  # row 0 at the top in an image
    rec.log("odometry_frame/exploration/map_origin",
            rr.Points2D([[f.x0, f.y0], [f.x0 + f.cols * f.resolution, f.y0 + f.rows * f.resolution]], radii=0.02))
    rows, cols = np.nonzero(m.cells == Cell.FREE)
    rec.log("odometry_frame/exploration/explored",
            rr.Points2D(f.centre_of(rows, cols), radii=f.resolution / 2, colors=[FREE_COLOUR]))
    rows, cols = np.nonzero(border)
    rec.log("odometry_frame/exploration/borders",
            rr.Points2D(f.centre_of(rows, cols), radii=f.resolution / 2, colors=[BORDER_COLOUR]))
    rows, cols = np.nonzero(m.cells == Cell.OBSTACLE)
    rec.log("odometry_frame/exploration/obstacles",
            rr.Points2D(f.centre_of(rows, cols), radii=f.resolution / 2, colors=[OBSTACLE_COLOUR]))
    points = m.points[:: max(1, len(m.points) // 5000)]
    rec.log("exploration_3d/points", rr.Points3D(points, radii=0.02, colors=[(120, 120, 255)]))
    live = m.interest != Interest.NEVER
    if live.any():
        strips = np.stack((m.points[m.edges[live, 0]], m.points[m.edges[live, 1]]), axis=1)
        colours = [INTEREST_COLOURS[Interest(int(s))] for s in m.interest[live]]
        rec.log("exploration_3d/interest_edges", rr.LineStrips3D(strips, colors=colours, radii=0.01))


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

    PORTS = (
        InputPort("mode", str, "edges", choices=("edges", "fixed"), literal_only=True,
                  doc="edges: watch interest edges; fixed: cameras straight ahead"),
        InputPort("home_tilt", float, -35.0, unit="deg", minimum=-90.0, maximum=90.0, literal_only=True,
                  doc="tilt with nothing to watch (-35: the floor from ~0.6 m to the explore range)"),
        InputPort("max_pan", float, 90.0, unit="deg", minimum=0.0, maximum=180.0, literal_only=True,
                  doc="follow a point up to this far off the heading (eq. 3)"),
        InputPort("rate_margin", float, 0.8, minimum=0.05, maximum=1.0, literal_only=True,
                  doc="plan with this fraction of the pan rate (eq. 4)"),
        InputPort("dwell", float, 1.5, unit="s", minimum=0.1, maximum=60.0, literal_only=True,
                  doc="watch one side this long when the other has an edge too"),
        InputPort("tilt_step", float, 5.0, unit="deg", minimum=0.0, maximum=45.0, literal_only=True,
                  doc="tilt targets are rounded to this (the head holds still through small changes)"),
        InputPort("max_speed", float, 1.2, unit="m/s", minimum=0.01, maximum=5.0, literal_only=True,
                  doc="the speed limit written when eq. 4 sets none"),
        *HEAD_PORTS,
        InputPort("turn_rate", float, 0.0, unit="rad/s", doc="the robot's commanded turn rate (eq. 4)"),
        InputPort("near_floor", float, 0.8, unit="m", minimum=0.0, maximum=10.0, literal_only=True,
                  doc="unseen floor nearer than this to the pan axis is looked at from this far"),
        InputPort("unseen_ahead", Pose2D, None,
                  doc="unseen floor on the path ahead ({/robot/unseen_ahead}): look there first"),
        MAP,
        POSE,
        PTU_COMMAND,
        OutputPort("speed_limit", float, "/robot/speed_limit", unit="m/s",
                   doc="the top forward speed at which the pan keeps up (eq. 4)"),
        OutputPort("gaze", Gaze, "/map/gaze", doc="the gaze state: edge watched, P_A, side, edges done"),
    )

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.params = gaze_params(self, max_pan=math.radians(float(self.get_input("max_pan"))),
                                  rate_margin=float(self.get_input("rate_margin")),
                                  home_tilt=math.radians(float(self.get_input("home_tilt"))),
                                  dwell=float(self.get_input("dwell")))
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
        distance = max(math.hypot(point.x - axis[0], point.y - axis[1]), float(self.get_input("near_floor")))
        return float(np.clip(pan, *self.params.pan_limits)), math.atan2(-head.lens_height, distance)

    def update(self) -> Status:
        m, pose = self.get_input("map", None), self.get_input("odometry", None)
        p, top = self.params, float(self.get_input("max_speed"))
        pan, tilt, limit, self.point = 0.0, p.home_tilt, top, None
        if m is not None and pose is not None and self.get_input("mode") == "edges":
            turn = self.get_input("turn_rate", 0.0)
            before = self.gaze.target
            self.gaze, cmd = next_gaze(self.gaze, m, pose, self.now(), p, turn_rate=float(turn or 0.0))
            pan, tilt, limit, self.point = cmd.pan, cmd.tilt, min(cmd.max_speed, top), cmd.point
            if self.gaze.target is not None:
                self.watch_ticks += 1
                self.edges_watched.add(self.gaze.target)
                self.switches += int(before is not None and before != self.gaze.target)
        unseen = self.get_input("unseen_ahead", None)
        if unseen is not None and pose is not None:
            pan, tilt = self._look_at(pose, unseen)
            self.look_ahead_ticks += 1
        self.ticks += 1
        self.limited_ticks += int(limit < top)
        step = math.radians(float(self.get_input("tilt_step")))
        if step > 0.0:
            tilt = float(np.clip(round(tilt / step) * step, *p.tilt_limits))
        self.command = PanTiltCommand(float(pan), tilt, p.pan_rate)
        self.set_output("ptu_command", self.command)
        self.set_output("speed_limit", float(limit))
        self.set_output("gaze", self.gaze)
        self.feedback_message = ("looking ahead" if self.point is None else
                                 f"watching edge {self.gaze.target} at pan {math.degrees(pan):.0f} deg"
                                 + (f", speed <= {limit:.2f} m/s" if limit < top else ""))
        return Status.RUNNING

    def report_sections(self) -> dict[str, dict[str, Any]]:
        """The ``exploration`` section's gaze part."""
        return {"exploration": {
            "gaze_mode": self.get_input("mode"),
            "gaze_watching_fraction": self.watch_ticks / self.ticks if self.ticks else 0.0,
            "gaze_edges_watched": len(self.edges_watched),
            "gaze_switches": self.switches,
            "gaze_speed_limited_fraction": self.limited_ticks / self.ticks if self.ticks else 0.0,
            "gaze_look_ahead_fraction": self.look_ahead_ticks / self.ticks if self.ticks else 0.0,
        }}

    def log_rerun(self, rec: Any) -> None:
        """Where the cameras look: a ray from the pan axis, and the watched point."""
        pose, command = self.get_input("odometry", None), self.command
        if pose is None or command is None:
            return
        import rerun as rr

        axis = self.params.head.axis_xy(pose)
        direction = pose.theta + command.pan
        reach = 1.5 * math.cos(command.tilt)
        rec.log("odometry_frame/exploration/gaze", rr.Arrows2D(
            vectors=[[reach * math.cos(direction), reach * math.sin(direction)]], origins=[axis.tolist()],
            colors=[(255, 220, 0)]))
        watched = [] if self.point is None else [self.point[:2].tolist()]
        rec.log("odometry_frame/exploration/watched", rr.Points2D(watched, radii=0.08, colors=[(255, 0, 255)]))


@register
class LookAround(BearingsBehaviour):
    """Look all around with the pan-tilt cameras while the robot stands; SUCCESS when done.

    The head steps through :func:`maps.exploration_gaze.survey` (rows of tilts from the lowest up
    to the horizon, pans from one limit to the other, fields of view overlapping by ``overlap``),
    holding each pose for ``settle`` seconds once the unit reports it there (so the map integrates
    a frame from it). The base gets no command (the runner stops it).
    """

    PORTS = (
        InputPort("overlap", float, 0.15, minimum=0.0, maximum=0.9, literal_only=True,
                  doc="fraction by which neighbouring views overlap"),
        InputPort("settle", float, 0.4, unit="s", minimum=0.0, maximum=10.0, literal_only=True,
                  doc="hold each pose this long once there"),
        InputPort("tolerance", float, 1.0, unit="deg", minimum=0.01, maximum=10.0, literal_only=True,
                  doc="the head is at a pose within this"),
        *HEAD_PORTS,
        InputPort("ptu", PanTiltState, Ref("/ptu/state"), doc="where the head is"),
        PTU_COMMAND,
    )

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.params = gaze_params(self)
        self.poses = survey(self.params, float(self.get_input("overlap")))
        self.index = 0
        self.arrived: float | None = None
        self.surveys = 0

    def initialise(self) -> None:
        self.index, self.arrived = 0, None

    def update(self) -> Status:
        pan, tilt = (float(v) for v in self.poses[self.index])
        self.set_output("ptu_command", PanTiltCommand(pan, tilt, self.params.pan_rate))
        state = self.get_input("ptu", None)
        tolerance = math.radians(float(self.get_input("tolerance")))
        there = state is not None and not state.moving and abs(state.pan - pan) <= tolerance and abs(
            state.tilt - tilt) <= tolerance
        self.feedback_message = f"view {self.index + 1} of {len(self.poses)}"
        if not there:
            self.arrived = None
            return Status.RUNNING
        if self.arrived is None:
            self.arrived = self.now()
        if self.now() - self.arrived < float(self.get_input("settle")):
            return Status.RUNNING
        self.index, self.arrived = self.index + 1, None
        if self.index < len(self.poses):
            return Status.RUNNING
        self.surveys += 1
        self.index = 0
        return Status.SUCCESS

    def report_sections(self) -> dict[str, dict[str, Any]]:
        """How many look-arounds were made (the start's and the recoveries')."""
        return {"exploration": {f"look_arounds_{self.name.replace(' ', '_')}": self.surveys}}

