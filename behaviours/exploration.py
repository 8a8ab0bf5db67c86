"""Exploration with the stereo pair on the pan-tilt unit (algorithm 3): the map and the next goal.

- :class:`MapStereo` integrates dense stereo into the exploration map (:mod:`maps.exploration.integrate`)
  and marks the floor under the robot, every tick; it never ends (RUNNING).
- :class:`SelectGoalPoint` chooses where to go next by the attractive power of the detected points
  (eq. 1; frontier mode when no point lies more than K beyond the border), and succeeds when no
  border is reachable: exploration is done.

Both work in the frame of the pose they read on their ``odometry`` input: the odometry frame,
corrected for drift by :class:`behaviours.localise.LocalisePose` in the shipped mission
(``odometry: "{/robot/pose}"``). Path following is :class:`behaviours.follow_path.FollowPath`,
the gaze :mod:`behaviours.gaze`.
"""

from __future__ import annotations

import math
from typing import Any

import cv2
import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from drivers.interfaces import PanTiltState
from maps.exploration.codec import pack_cells
from maps.exploration.goal import Goal, GoalParams, Mode, ModeSwitch, select_goal, verification_goal
from maps.exploration.grid import Cell, ExplorationMap, borders, mark_traversed
from maps.exploration.head import StereoHead
from maps.exploration.integrate import IntegrationParams, integrate_observation, observe
from perception.camera import PinholeCamera, StereoRig
from perception.frame import Frame
from perception.geometry import Pose2D

ROBOT_RADIUS = InputPort("robot_radius", float, 0.26, unit="m", minimum=0.05, maximum=2.0, literal_only=True,
                         doc="radius of the robot's disc")
CLEARANCE = InputPort("clearance", float, 0.05, unit="m", minimum=0.0, maximum=1.0, literal_only=True,
                      doc="room kept between the disc and obstacle cells beyond robot_radius (localisation "
                          "error): paths are planned with it, and FollowPath stops the robot short of it")
MAP = InputPort("map", ExplorationMap, Ref("/map/exploration"), doc="the exploration map")
GOAL = InputPort("goal", Goal, Ref("/map/exploration_goal"), doc="the exploration goal (None: none)")
POSE = InputPort("odometry", Pose2D, Ref("/robot/odometry"),
                 doc="the robot's pose (the map's frame): odometry, or a drift-corrected pose")
PTU_POSITION = InputPort("ptu_position", list[float], [0.1, 0.0, 1.0], unit="m", literal_only=True,
                         doc="the pan/tilt axes' intersection on the base: x, y, z")
CAMERA_POSITION = InputPort("camera_position", list[float], [0.05, 0.0, 0.08], unit="m", literal_only=True,
                            doc="the left stereo camera on the pan-tilt head: x, y, z")


def xyz(values: list[float], what: str) -> tuple[float, float, float]:
    """Three numbers from a list port."""
    if len(values) != 3:
        raise ValueError(f"{what} is [x, y, z], got {values}")
    return float(values[0]), float(values[1]), float(values[2])


def stereo_points(depth: np.ndarray, rig: StereoRig, step: int) -> tuple[np.ndarray, np.ndarray]:
    """Body-frame points (M x 3) and their left pixels (M x 2) of a depth map sampled every ``step``
    pixels (``perception.stereo.dense_points`` with the pixels kept, for the image-neighbour edges)."""
    vs, us = np.mgrid[0 : depth.shape[0] : step, 0 : depth.shape[1] : step]
    z = depth[vs, us].ravel()
    ok = np.isfinite(z)
    uv = np.column_stack((us.ravel()[ok], vs.ravel()[ok])).astype(np.float64)
    bearings = rig.left.pixel_to_bearing(uv)
    return bearings * (z[ok] / bearings[:, 0])[:, None], uv


BELOW_FLOOR = 0.2  # m: stereo points this far below the floor are wrong matches, dropped


def drop_jumps(depth: np.ndarray, max_jump: float, radius: int = 3) -> np.ndarray:
    """The depth map without the pixels within ``radius`` of a depth jump larger than ``max_jump``
    (relative): a semi-global matcher smears depth across occluding edges (a door jamb in front of
    the room behind), streaks that would otherwise become obstacles on the floor between the two."""
    if max_jump <= 0.0:
        return depth
    kernel = np.ones((2 * radius + 1, 2 * radius + 1), np.uint8)
    ok = np.isfinite(depth)
    high = cv2.dilate(np.where(ok, depth, 0.0).astype(np.float32), kernel)
    low = cv2.erode(np.where(ok, depth, np.finfo(np.float32).max).astype(np.float32), kernel)
    keep = ok & (high - low <= max_jump * low)
    return np.where(keep, depth, np.nan).astype(np.float32)


def halved(rig: StereoRig) -> StereoRig:
    """The rig of images halved by ``cv2.pyrDown`` (pixel centres: ``(u + 0.5) / 2 - 0.5``)."""
    def half(c: PinholeCamera) -> PinholeCamera:
        return PinholeCamera((c.width + 1) // 2, (c.height + 1) // 2, c.fx / 2.0, c.fy / 2.0,
                             (c.cx + 0.5) / 2.0 - 0.5, (c.cy + 0.5) / 2.0 - 0.5, c.dist)

    return StereoRig(half(rig.left), half(rig.right), rig.baseline)


@register
class MapStereo(BearingsBehaviour):
    """Integrate dense stereo of the pan-tilt pair into the exploration map, and mark the robot's disc.

    Every tick: the robot's disc is explored free (it stands there; the cameras never see that
    floor); the first tick marks ``start_radius`` instead (the free floor assumed around the start,
    which a look-around then joins to the first footprints). At most every ``period`` seconds, a new
    stereo frame becomes depth (OpenCV's semi-global matcher, ``num_disparities``: nothing nearer
    than ``f B / num_disparities``, 0.66 m for the simulator's pair at 96), points every ``step``
    pixels, and :func:`maps.exploration.integrate_stereo` at the pose and the pan-tilt angles of
    this tick (the frame is grabbed in the same tick). RUNNING for ever: run it beside the
    exploration, which ends the mission.

    Report section ``exploration``: explored area over time with the path length driven (map
    frame), the final map (its explored cells, packed), and every observation as a virtual range
    scan (``scans``: time, pan, tilt, free range per bin), so an evaluation can draw what was seen
    at the true poses.
    """

    PORTS = (
        InputPort("camera", str, "stereo", literal_only=True, doc="the stereo pair on the pan-tilt unit"),
        InputPort("period", float, 0.4, unit="s", minimum=0.0, maximum=60.0, literal_only=True,
                  doc="at most one integration per period (stereo matching costs ~0.1 s)"),
        InputPort("num_disparities", int, 96, minimum=16, maximum=256, literal_only=True,
                  doc="disparity search range (px): nearest depth f B / n"),
        InputPort("step", int, 8, minimum=1, maximum=64, literal_only=True,
                  doc="sample the depth every step px (of the full image)"),
        InputPort("levels", int, 1, minimum=0, maximum=3, literal_only=True,
                  doc="match images halved this many times (1: 8x faster, depth within a few cm at 3 m)"),
        InputPort("max_jump", float, 0.15, minimum=0.0, maximum=10.0, literal_only=True,
                  doc="depths within 3 px (of the matched image) may differ by this fraction; pixels beside "
                      "larger jumps are dropped (0: keep all)"),
        InputPort("resolution", float, 0.05, unit="m", minimum=0.01, maximum=0.5, literal_only=True,
                  doc="map cell size"),
        InputPort("explore_range", float, 3.0, unit="m", minimum=0.5, maximum=20.0, literal_only=True,
                  doc="floor is explored (and obstacles marked) up to this plan range"),
        InputPort("start_radius", float, 0.6, unit="m", minimum=0.0, maximum=5.0, literal_only=True,
                  doc="free floor assumed around the start pose"),
        ROBOT_RADIUS,
        PTU_POSITION,
        CAMERA_POSITION,
        InputPort("frames", dict, Ref("/perception/frames"), doc="the latest frame of each camera, by name"),
        InputPort("ptu", PanTiltState, Ref("/ptu/state"), doc="the pan-tilt angles the frame was taken at"),
        POSE,
        OutputPort("map", ExplorationMap, "/map/exploration", doc="the exploration map (odometry frame)"),
    )
    AREA_EVERY = 2.0  # s between samples of the explored area over time

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self._ptu = xyz(self.get_input("ptu_position"), "ptu_position")
        self._camera = xyz(self.get_input("camera_position"), "camera_position")
        self._params = IntegrationParams(explore_range=float(self.get_input("explore_range")))
        self.map: ExplorationMap | None = None
        self.head: StereoHead | None = None
        self._last_stamp: float | None = None
        self._last_integration = -math.inf
        self._last_pose: Pose2D | None = None
        self.path_length = 0.0
        self.area_over_time: list[list[float]] = []
        self.scans: list[list[float]] = []
        self._scan_bins = 0
        self._logged = -1  # the integration last logged to rerun

    def update(self) -> Status:
        pose = self.get_input("odometry", None)
        if pose is None:
            self.feedback_message = "waiting for a pose"
            return Status.RUNNING
        if self._last_pose is not None:
            self.path_length += math.hypot(pose.x - self._last_pose.x, pose.y - self._last_pose.y)
        self._last_pose = pose
        if self.map is None:
            empty = ExplorationMap.empty(float(self.get_input("resolution")), 5.0, (pose.x, pose.y))
            self.map = mark_traversed(empty, pose, float(self.get_input("start_radius")))
        else:
            self.map = mark_traversed(self.map, pose, float(self.get_input("robot_radius")))
        self._integrate(pose)
        now = self.now()
        if not self.area_over_time or now - self.area_over_time[-1][0] >= self.AREA_EVERY:
            self.area_over_time.append([round(now, 2), round(self.map.explored_area, 3), round(self.path_length, 3)])
        self.set_output("map", self.map)
        self.feedback_message = f"{self.map.explored_area:.1f} m^2 explored, {len(self.map.points)} points"
        return Status.RUNNING

    def _integrate(self, pose: Pose2D) -> None:
        from perception.stereo import dense_depth  # OpenCV's matcher: imported when a mission maps

        frame = (self.get_input("frames", None) or {}).get(self.get_input("camera"))
        ptu = self.get_input("ptu", None)
        if not isinstance(frame, Frame) or frame.right is None or ptu is None or self.map is None:
            return
        if frame.stamp == self._last_stamp or self.now() - self._last_integration < float(self.get_input("period")):
            return
        self._last_stamp, self._last_integration = frame.stamp, self.now()
        rig = frame.camera
        if self.head is None:
            self.head = StereoHead.for_rig(rig, self._ptu, self._camera)
        levels = int(self.get_input("levels"))
        left, right, small = frame.image, frame.right, rig
        for _ in range(levels):
            left, right, small = cv2.pyrDown(left), cv2.pyrDown(right), halved(small)
        scale = 2**levels
        depth = dense_depth(left, right, small, num_disparities=-(-int(self.get_input("num_disparities")) // scale))
        depth = drop_jumps(depth, float(self.get_input("max_jump")))
        points, uv = stereo_points(depth, small, max(1, int(self.get_input("step")) // scale))
        uv = (uv + 0.5) * scale - 0.5  # full-image pixels: image neighbours as integrate_stereo expects
        view = self.head.view(pose, ptu.pan, ptu.tilt)
        above = points @ view.rotation[2] + view.eye[2] >= -BELOW_FLOOR  # the floor is flat: lower is a wrong match
        points, uv = points[above], uv[above]
        seen = observe(points, uv, view, self._params)  # its range scan: integrated and recorded
        self.map = integrate_observation(self.map, seen, self._params)
        self._scan_bins = len(seen.ranges)
        self.scans.append([round(self.now(), 2), round(ptu.pan, 4), round(ptu.tilt, 4),
                           *np.round(seen.ranges, 2).tolist()])

    def report_sections(self) -> dict[str, dict[str, Any]]:
        """The ``exploration`` section's map part (see the class docstring)."""
        if self.map is None:
            return {"exploration": {"explored_area_m2": 0.0}}
        m = self.map
        head = self.head or StereoHead(self._ptu, self._camera)
        return {"exploration": {
            "explored_area_m2": m.explored_area,
            "obstacle_area_m2": float(np.count_nonzero(m.cells == Cell.OBSTACLE)) * m.frame.resolution**2,
            "path_length_m": self.path_length,
            "points": len(m.points),
            "edges": len(m.edges),
            "integrations": len(self.scans),
            "area_over_time": self.area_over_time + [[round(self.now(), 2), round(m.explored_area, 3),
                                                      round(self.path_length, 3)]],
            "map": {"x0": m.frame.x0, "y0": m.frame.y0, "resolution": m.frame.resolution, "rows": m.frame.rows,
                    "cols": m.frame.cols, "explored": pack_cells(m.cells == Cell.FREE)},
            "scan": {"ptu": list(head.ptu), "camera": list(head.camera), "vertical_fov": head.vertical_fov,
                     "horizontal_fov": head.horizontal_fov, "bins": self._scan_bins,
                     "columns": "t, pan, tilt, then the free range of each bin (m), right to left"},
            "scans": self.scans,
        }}

    def log_rerun(self, rec: Any) -> None:
        """The explored area, the obstacles and the borders (an image over the odometry frame), the
        points and the interest edges (3-D), every 10th integration."""
        if self.map is None or len(self.scans) % 10 != 1 or self._logged == len(self.scans):
            return
        self._logged = len(self.scans)
        import rerun as rr

        from behaviours.gaze import log_map  # one drawing of the map for the gaze and the map

        log_map(rec, rr, self.map, borders(self.map, 6))


@register
class SelectGoalPoint(BearingsBehaviour):
    """Choose the next exploration goal by attractive power (eq. 1); SUCCESS when no border is reachable.

    ``A_P = d(P_p, P_b) - eta G(v_S, P_b)``: the detected point farthest beyond the explored
    border, less eta times the travel cost to that border; the goal is the border point ``P_b``
    (see :mod:`maps.exploration.goal`). No point more than ``k`` beyond the border: frontier mode,
    the closest reachable border point, until one is (``strategy: closest_frontier``: frontier
    mode always, the evaluation's baseline). The goal is chosen again every ``reselect`` seconds
    (the map grows as the robot drives; the current goal is kept while within ``hysteresis`` of the
    best) and when the robot is within ``reach`` of it (its point is then spent and its border point
    avoided: the unknown beyond it was not seen from there). Points seen in fewer than
    ``min_sightings`` observations do not attract (stray stereo matches).

    RUNNING while there is a goal (written to ``goal``; path following and the gaze read it);
    SUCCESS when no border has been reachable ``patience`` selections in a row (DONE); FAILURE
    when no border is reachable but patience is not used up: look around and tick it again (a
    recovery). A goal abandoned because the branch was halted (path following failed: a path
    blocked by what the cameras saw on the way) is spent and its border point avoided too. Before a
    selection finds no border, the avoided border points get a second chance (the map may have
    changed since: a doorway's stray obstacles cleared; the cameras looked elsewhere on arrival);
    one reached or abandoned again is avoided for good. Before a selection without a reachable border
    counts, the obstacle cells that close a border a narrower disc reaches are looked at again
    (:func:`maps.exploration.goal.verification_goal`: a VERIFY goal), once per place.
    The mode, strikes, spent points, avoided targets and verified places outlive re-entries.
    """

    PORTS = (
        InputPort("strategy", str, "attraction", choices=("attraction", "closest_frontier"), literal_only=True,
                  doc="attraction: eq. 1 with frontier mode; closest_frontier: the closest border always"),
        InputPort("eta", float, 0.25, minimum=0.0, maximum=0.5, literal_only=True,
                  doc="weight of the travel cost in eq. 1"),
        InputPort("k", float, 1.0, unit="m", minimum=0.0, maximum=100.0, literal_only=True,
                  doc="a point must lie this far beyond the border to attract"),
        ROBOT_RADIUS,
        CLEARANCE,
        InputPort("margin", float, 0.3, unit="m", minimum=0.0, maximum=5.0, literal_only=True,
                  doc="paths with less clearance than robot_radius + clearance + margin cost more"),
        InputPort("penalty", float, 3.0, minimum=0.0, maximum=100.0, literal_only=True,
                  doc="...up to (1 + penalty) times their length"),
        InputPort("patience", int, 2, minimum=1, maximum=100, literal_only=True,
                  doc="selections in a row without a reachable border before done"),
        InputPort("min_frontier", float, 0.3, unit="m", minimum=0.0, maximum=10.0, literal_only=True,
                  doc="shorter border pieces are ignored"),
        InputPort("hysteresis", float, 0.5, unit="m", minimum=0.0, maximum=10.0, literal_only=True,
                  doc="keep the current goal while its power (frontier: cost) is this close to the best"),
        InputPort("reselect", float, 2.0, unit="s", minimum=0.1, maximum=600.0, literal_only=True,
                  doc="choose again this often while driving"),
        InputPort("reach", float, 0.6, unit="m", minimum=0.05, maximum=5.0, literal_only=True,
                  doc="a goal this close is reached"),
        InputPort("min_sightings", int, 2, minimum=1, maximum=1000, literal_only=True,
                  doc="points seen in fewer observations do not attract"),
        InputPort("point_clearance", float, 0.3, unit="m", minimum=0.0, maximum=10.0, literal_only=True,
                  doc="points whose floor projection is this close to an obstacle do not attract"),
        InputPort("verify_radius", float, 0.13, unit="m", minimum=0.0, maximum=2.0, literal_only=True,
                  doc="before done, look again at what closes a border a disc this size reaches (0: never)"),
        InputPort("look_back", float, 1.0, unit="m", minimum=0.0, maximum=10.0, literal_only=True,
                  doc="...from this far before the first place the robot's disc cannot pass"),
        MAP,
        POSE,
        OutputPort("goal", Goal, "/map/exploration_goal", doc="the goal: border point, path, mode (None: none)"),
    )

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.params = GoalParams(
            eta=float(self.get_input("eta")), k=float(self.get_input("k")),
            robot_radius=float(self.get_input("robot_radius")) + float(self.get_input("clearance")),
            min_frontier=float(self.get_input("min_frontier")),
            margin=float(self.get_input("margin")), penalty=float(self.get_input("penalty")),
            patience=int(self.get_input("patience")), hysteresis=float(self.get_input("hysteresis")),
            closest_frontier=self.get_input("strategy") == "closest_frontier",
            min_sightings=int(self.get_input("min_sightings")),
            point_clearance=float(self.get_input("point_clearance")),
            verify_radius=float(self.get_input("verify_radius")), look_back=float(self.get_input("look_back")),
        )  # fmt: skip
        self.switch = ModeSwitch()
        self.goal: Goal | None = None
        self.avoid: list[tuple[float, float]] = []  # reached or abandoned: avoided until a second chance
        self.forgiven: list[tuple[float, float]] = []  # had their second chance
        self.given_up: list[tuple[float, float]] = []  # reached or abandoned twice: avoided for good
        self.verified: list[tuple[float, float]] = []  # border points whose blocking cells were looked at again
        self.selected_at = -math.inf
        self.goals: list[list[Any]] = []
        self.mode_switches: list[list[Any]] = []
        self.selections = 0
        self.reached = 0
        self.abandoned = 0
        self._logged: Goal | None = None  # the goal last logged to rerun
        self._recorded: Goal | None = None  # the goal last recorded in ``goals``

    def initialise(self) -> None:
        self.goal = None  # choose afresh on every entry

    def update(self) -> Status:
        m = self.get_input("map", None)
        pose = self.get_input("odometry", None)
        if m is None or pose is None:
            self.feedback_message = "waiting for the map and a pose"
            return Status.RUNNING
        goal, now = self.goal, self.now()
        reached = goal is not None and math.hypot(pose.x - goal.target[0], pose.y - goal.target[1]) <= float(
            self.get_input("reach"))
        if goal is not None and not reached and now - self.selected_at < float(self.get_input("reselect")):
            return Status.RUNNING
        if reached and goal is not None:
            self.reached += 1
            self._spend(goal)
        before = self.switch
        self._select(m, pose, None if reached else goal)
        if self.goal is None and self.avoid:  # a second chance for the abandoned border points
            self.forgiven += self.avoid
            self.avoid = []
            self.switch = before
            self._select(m, pose, None)
        if self.goal is None and self._verify(m, pose):
            self.switch = before  # looking again is not a strike
        if self.switch.mode is Mode.DONE:
            self.feedback_message = "done: no border is reachable"
            return Status.SUCCESS
        if self.goal is None:
            strikes = f"{self.switch.strikes} of {self.params.patience}"
            self.feedback_message = f"no reachable border ({strikes}): look around"
            return Status.FAILURE
        g = self.goal
        self.feedback_message = f"{g.mode.value}: to ({g.target[0]:.2f}, {g.target[1]:.2f}), G {g.cost:.2f} m"
        return Status.RUNNING

    def _spend(self, goal: Goal) -> None:
        """A goal reached or abandoned: its point spent and its border point avoided, or, for a
        VERIFY goal, the place it looked at verified."""
        if goal.mode is Mode.VERIFY and goal.blocked is not None:
            self.verified.append(goal.blocked)
            return
        self.switch = self.switch.spend(goal.point)
        self._avoid(goal.target)

    def _verify(self, m: ExplorationMap, pose: Pose2D) -> bool:
        """No border is reachable: set a VERIFY goal if some border is closed only by cells worth
        looking at again (:func:`maps.exploration.goal.verification_goal`)."""
        goal = verification_goal(m, (pose.x, pose.y), self.params, avoid=self._avoided(),
                                 verified=np.array(self.verified) if self.verified else None)
        if goal is None:
            return False
        self._set_goal(goal)
        return True

    def _avoided(self) -> np.ndarray | None:
        """The targets whose border points are no candidates now (K x 2), None without any."""
        targets = self.avoid + self.given_up
        return np.array(targets) if targets else None

    def _avoid(self, target: tuple[float, float]) -> None:
        """Avoid a border point reached or abandoned: until its second chance, or for good after it."""
        again = any(math.dist(target, f) <= self.params.avoid_radius for f in self.forgiven)
        (self.given_up if again else self.avoid).append(target)

    def _select(self, m: ExplorationMap, pose: Pose2D, current: Goal | None) -> None:
        before = self.switch.mode
        self.switch, goal = select_goal(self.switch, m, (pose.x, pose.y), self.params, current=current,
                                        avoid=self._avoided())
        self.selections += 1
        self.selected_at = self.now()
        now = round(self.now(), 2)
        if self.switch.mode is not before:
            self.mode_switches.append([now, before.value, self.switch.mode.value])
        self._set_goal(goal)

    def _set_goal(self, goal: Goal | None) -> None:
        """Make ``goal`` the goal (on the blackboard) and record it when it is a new one."""
        last = self._recorded
        if goal is not None and (last is None or goal.mode is not last.mode or goal.point != last.point
                                 or math.dist(goal.target, last.target) > 0.25):
            self._recorded = goal
            self.goals.append([round(self.now(), 2), goal.mode.value, round(goal.target[0], 3),
                               round(goal.target[1], 3), goal.point, round(goal.distance, 3), round(goal.cost, 3),
                               None if math.isnan(goal.power) else round(goal.power, 3)])
        self.goal = goal
        self.set_output("goal", goal)

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID and self.goal is not None:  # halted: the goal could not be followed
            self.abandoned += 1
            self._spend(self.goal)
            self.goal = None
            self.set_output("goal", None)

    def report_sections(self) -> dict[str, dict[str, Any]]:
        """The ``exploration`` section's goal part: goals, mode switches, how selection ended."""
        return {"exploration": {
            "mode": self.switch.mode.value,
            "done": self.switch.mode is Mode.DONE,
            "strategy": self.get_input("strategy"),
            "selections": self.selections,
            "goals_reached": self.reached,
            "goals_abandoned": self.abandoned,
            "verifications": sum(g[1] == Mode.VERIFY.value for g in self.goals),
            "goal_count": len(self.goals),
            "goals": self.goals,
            "goal_columns": "t, mode, x, y, point, d, G, A_P",
            "mode_switch_count": len(self.mode_switches),
            "mode_switches": self.mode_switches,
        }}

    def log_rerun(self, rec: Any) -> None:
        """The goal: its border point, its path and the attracting point."""
        goal = self.goal
        if goal is None or self._logged is goal:
            return
        self._logged = goal
        import rerun as rr

        colour = (255, 80, 80) if goal.mode is Mode.ATTRACTION else (255, 160, 0)
        rec.log("odometry_frame/exploration/goal", rr.Points2D([goal.target], radii=0.1, colors=[colour],
                                                               labels=[goal.mode.value]))
        if len(goal.path) > 1:
            rec.log("odometry_frame/exploration/path", rr.LineStrips2D([goal.path], colors=[colour], radii=0.02))
