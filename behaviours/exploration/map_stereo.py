"""The exploration map from dense stereo of the pan-tilt pair (algorithm 3): :class:`MapStereo`.

It integrates dense stereo into the exploration map (:mod:`maps.exploration.integrate`) and marks
the floor under the robot, every tick; it never ends (RUNNING). It works in the frame of the pose
it reads on its ``odometry`` input: the odometry frame, corrected for drift by
:class:`behaviours.exploration.localise.LocalisePose` in the shipped mission
(``odometry: "{/robot/pose}"``).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.exploration.drawing import map_drawings
from behaviours.exploration.ports import CAMERA_POSITION, FRAMES, POSE, PTU_POSITION, ROBOT_RADIUS, disc_radius, xyz
from behaviours.footprint import FOOTPRINT
from behaviours.keys import RANGES_KEY
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.telemetry import Drawing, Figure
from drivers.interfaces import PanTiltState
from maps.exploration.codec import pack_cells
from maps.exploration.grid import Cell, ExplorationMap, borders, mark_traversed
from maps.exploration.head import StereoHead
from maps.exploration.integrate import IntegrationParams, clear_rays, integrate_observation, observe
from perception.frame import Frame
from perception.geometry import Pose2D, frame_to_parent
from perception.ranges import RangeScan
from perception.stereo import BELOW_FLOOR, pyramid_points


@register
class MapStereo(BearingsBehaviour):
    """Integrate dense stereo of the pan-tilt pair into the exploration map, and mark the robot's disc.

    Every tick: the robot's disc is explored free (it stands there; the cameras never see that
    floor); the first tick marks ``start_radius`` instead (the free floor assumed around the start,
    which a look-around then joins to the first footprints). At most every ``period`` seconds, a new
    stereo frame becomes depth (OpenCV's semi-global matcher, ``num_disparities``: nothing nearer
    than ``f B / num_disparities``, 0.66 m for the simulator's pair at 96), points every ``step``
    pixels (:func:`perception.stereo.pyramid_points`), and
    :func:`maps.exploration.integrate.integrate_observation` at the pose and the pan-tilt angles of
    this tick (the frame is grabbed in the same tick). RUNNING for ever: run it beside the
    exploration, which ends the mission.

    Report section ``exploration``: explored area over time with the path length driven (map
    frame), the final map (its explored cells, packed), and every observation as a virtual range
    scan (``scans``: time, pan, tilt, free range per bin), so an evaluation can draw what was seen
    at the true poses.
    """

    CAMERA = InputPort("camera", str, "stereo", literal_only=True, camera=True,
                       doc="the stereo pair on the pan-tilt unit")
    PERIOD = InputPort("period", float, 0.4, unit="s", minimum=0.0, maximum=60.0, literal_only=True,
                       doc="at most one integration per period (stereo matching costs ~0.1 s)")
    NUM_DISPARITIES = InputPort("num_disparities", int, 96, minimum=16, maximum=256, literal_only=True,
                                doc="disparity search range (px): nearest depth f B / n")
    STEP = InputPort("step", int, 8, minimum=1, maximum=64, literal_only=True,
                     doc="sample the depth every step px (of the full image)")
    LEVELS = InputPort("levels", int, 1, minimum=0, maximum=3, literal_only=True,
                       doc="match images halved this many times (1: 8x faster, depth within a few cm at 3 m)")
    MAX_JUMP = InputPort("max_jump", float, 0.15, minimum=0.0, maximum=10.0, literal_only=True,
                         doc="depths within 3 px (of the matched image) may differ by this fraction; pixels beside "
                             "larger jumps are dropped (0: keep all)")
    RESOLUTION = InputPort("resolution", float, 0.05, unit="m", minimum=0.01, maximum=0.5, literal_only=True,
                           doc="map cell size")
    EXPLORE_RANGE = InputPort("explore_range", float, 3.0, unit="m", minimum=0.5, maximum=20.0, literal_only=True,
                              doc="floor is explored (and obstacles marked) up to this plan range")
    START_RADIUS = InputPort("start_radius", float, 0.6, unit="m", minimum=0.0, maximum=5.0, literal_only=True,
                             doc="free floor assumed around the start pose")
    PTU = InputPort("ptu", PanTiltState, Ref("/ptu/state"), doc="the pan-tilt angles the frame was taken at")
    RANGES = InputPort("ranges", RangeScan, Ref(RANGES_KEY.path),
                       doc="range echoes: obstacle cells on a sensor's axis before its echo are cleared")
    MAP_OUT = OutputPort("map", ExplorationMap, "/map/exploration", doc="the exploration map (odometry frame)")
    PORTS = (CAMERA, PERIOD, NUM_DISPARITIES, STEP, LEVELS, MAX_JUMP, RESOLUTION, EXPLORE_RANGE, START_RADIUS,
             ROBOT_RADIUS, FOOTPRINT, PTU_POSITION, CAMERA_POSITION, FRAMES, PTU, POSE, RANGES, MAP_OUT)
    RANGES_OPTIONAL = True  # without range sensors the cameras alone clear what they see past
    AREA_EVERY = 2.0  # s between samples of the explored area over time
    ECHO_REACH = 1.5  # m: echoes clear obstacle cells this near the sensor (where the cameras see least), no farther
    DRAW_EVERY = 10  # integrations between drawings of the map

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self._ptu = xyz(self.get_input(PTU_POSITION), "ptu_position")
        self._camera = xyz(self.get_input(CAMERA_POSITION), "camera_position")
        self._params = IntegrationParams(explore_range=self.get_input(self.EXPLORE_RANGE))
        self.map: ExplorationMap | None = None
        self.head: StereoHead | None = None
        self._last_stamp: float | None = None
        self._last_echo: float | None = None
        self._last_integration = -math.inf
        self._last_pose: Pose2D | None = None
        self.path_length = 0.0
        self.area_over_time: list[list[float]] = []
        self.scans: list[list[float]] = []
        self._scan_bins = 0
        self._drawn = -1  # the integration last drawn

    def update(self) -> Status:
        pose = self.get_input(POSE, None)
        if pose is None:
            self.feedback_message = "waiting for a pose"
            return Status.RUNNING
        if self._last_pose is not None:
            self.path_length += math.hypot(pose.x - self._last_pose.x, pose.y - self._last_pose.y)
        self._last_pose = pose
        if self.map is None:
            empty = ExplorationMap.empty(self.get_input(self.RESOLUTION), 5.0, (pose.x, pose.y))
            self.map = mark_traversed(empty, pose, self.get_input(self.START_RADIUS))
        else:
            self.map = mark_traversed(self.map, pose, disc_radius(self))
        self._clear_echoes(pose)
        self._integrate(pose)
        now = self.now()
        if not self.area_over_time or now - self.area_over_time[-1][0] >= self.AREA_EVERY:
            self.area_over_time.append([round(now, 2), round(self.map.explored_area, 3), round(self.path_length, 3)])
        self.set_output(self.MAP_OUT, self.map)
        self.feedback_message = f"{self.map.explored_area:.1f} m^2 explored, {len(self.map.points)} points"
        return Status.RUNNING

    def _clear_echoes(self, pose: Pose2D) -> None:
        """Obstacle cells on a range sensor's axis before its echo, within ``ECHO_REACH``, are seen past
        (:func:`maps.exploration.integrate.clear_rays`; new echoes only). Near the robot only: a sonar
        passes under a table top that the cameras saw, as the collision monitor's sonar does."""
        scan = self.get_input(self.RANGES, None)
        if not isinstance(scan, RangeScan) or self.map is None or scan.stamp == self._last_echo:
            return
        self._last_echo = scan.stamp
        ranges = np.asarray(scan.ranges, dtype=float)
        echo = np.isfinite(ranges)
        if not echo.any():
            return
        sensors = [s for s, e in zip(scan.sensors, echo, strict=True) if e]
        x, y, heading = (np.array([getattr(s, a) for s in sensors]) for a in ("x", "y", "heading"))
        reach = np.minimum(ranges[echo], self.ECHO_REACH + self._params.see_past)  # near the robot only
        origins = frame_to_parent(pose, np.column_stack((x, y)))  # base frame to odometry
        ends = frame_to_parent(pose, np.column_stack((x + reach * np.cos(heading), y + reach * np.sin(heading))))
        self.map = clear_rays(self.map, origins, ends, self._params)

    def _integrate(self, pose: Pose2D) -> None:
        frame = (self.get_input(FRAMES, None) or {}).get(self.get_input(self.CAMERA))
        ptu = self.get_input(self.PTU, None)
        if not isinstance(frame, Frame) or frame.right is None or ptu is None or self.map is None:
            return
        if frame.stamp == self._last_stamp or self.now() - self._last_integration < self.get_input(self.PERIOD):
            return
        self._last_stamp, self._last_integration = frame.stamp, self.now()
        rig = frame.camera
        if self.head is None:
            self.head = StereoHead.for_rig(rig, self._ptu, self._camera)
        points, uv = pyramid_points(frame.image, frame.right, rig, levels=self.get_input(self.LEVELS),
                                    num_disparities=self.get_input(self.NUM_DISPARITIES),
                                    max_jump=self.get_input(self.MAX_JUMP), step=self.get_input(self.STEP))
        view = self.head.view(pose, ptu.pan, ptu.tilt)
        above = points @ view.rotation[2] + view.eye[2] >= -BELOW_FLOOR  # the floor is flat: lower is a wrong match
        seen = observe(points[above], uv[above], view, self._params)
        self.map = integrate_observation(self.map, seen, self._params)
        self._scan_bins = len(seen.ranges)
        self.scans.append([round(self.now(), 2), round(ptu.pan, 4), round(ptu.tilt, 4),
                           *np.round(seen.ranges, 2).tolist()])

    def figures(self) -> Iterator[Figure]:
        """The ``exploration`` section's map part (see the class docstring)."""
        if self.map is None:
            yield Figure("exploration", "explored_area_m2", 0.0, headline=True)
            return
        m, f = self.map, self.map.frame
        head = self.head or StereoHead(self._ptu, self._camera)
        area = [round(self.now(), 2), round(m.explored_area, 3), round(self.path_length, 3)]
        yield from (Figure("exploration", name, value, headline=name == "explored_area_m2") for name, value in (
            ("explored_area_m2", m.explored_area),
            ("obstacle_area_m2", float(np.count_nonzero(m.cells == Cell.OBSTACLE)) * f.resolution**2),
            ("path_length_m", self.path_length),
            ("points", len(m.points)),
            ("edges", len(m.edges)),
            ("integrations", len(self.scans)),
            ("area_over_time", [*self.area_over_time, area]),
            ("map.x0", f.x0), ("map.y0", f.y0), ("map.resolution", f.resolution), ("map.rows", f.rows),
            ("map.cols", f.cols), ("map.explored", pack_cells(m.cells == Cell.FREE)),
            ("scan.ptu", list(head.ptu)), ("scan.camera", list(head.camera)),
            ("scan.vertical_fov", head.vertical_fov), ("scan.horizontal_fov", head.horizontal_fov),
            ("scan.bins", self._scan_bins),
            ("scan.columns", "t, pan, tilt, then the free range of each bin (m), right to left"),
            ("scans", self.scans),
        ))

    def drawings(self) -> Iterator[Drawing]:
        """The explored area, the obstacles and the borders (an image over the odometry frame), the
        points and the interest edges (3-D), every 10th integration."""
        if self.map is None or len(self.scans) % self.DRAW_EVERY != 1 or self._drawn == len(self.scans):
            return
        self._drawn = len(self.scans)
        yield from map_drawings(self.map, borders(self.map, 6))
