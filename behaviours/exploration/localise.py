"""Drift correction: the odometry pose corrected by identified landmark bearings.

:class:`LocalisePose` runs the pure filter of :mod:`maps.exploration.pose` (an EKF over the pose and
the landmarks it maps as it goes, landmarks in inverse depth) on every new frame of a bearings
sensor, fed with the odometry increments in between. It writes a corrected :class:`Pose2D` in the
odometry frame (the filter starts at the first odometry pose), which the exploration behaviours read
through their ``odometry`` input (``odometry: "{/robot/pose}"``). Why this and not Z-infinity or a
panorama compass: see :mod:`maps.exploration.pose`. Without the sensor (no such camera, nothing in
view) the pose is odometry, so a mission runs unchanged on a robot without it.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.exploration.ports import FRAMES
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.telemetry import Drawing, Figure, Points
from maps.exploration.pose import FilterParams, PoseFilter
from perception.frame import LandmarkBearings
from perception.geometry import Pose2D


@register
class LocalisePose(BearingsBehaviour):
    """Correct odometry drift with the bearings of identified landmarks (EKF-SLAM in the odometry frame).

    Every tick: predict with the odometry increment; on a new frame of the bearings sensor
    ``camera``, correct with the azimuth of every landmark (eq. of a bearing: atan2 of the unit
    vector). Writes the corrected pose to ``pose``. SUCCESS every tick (a perception step: it
    belongs under the mission's ``sense:``); before the first odometry it writes nothing.
    """

    CAMERA = InputPort("camera", str, "landmarks", literal_only=True, camera=True,
                       doc="the bearings sensor (identified landmarks) to correct with")
    MOUNT = InputPort("mount", list[float], [0.0, 0.0, 0.0], unit="m, m, deg", literal_only=True,
                      doc="where the sensor sits on the base: x, y, yaw")
    BEARING_SIGMA = InputPort("bearing_sigma", float, 1.0, unit="deg", minimum=0.01, maximum=30.0, literal_only=True,
                              doc="azimuth noise of a landmark on the horizon")
    ODOMETRY = InputPort("odometry", Pose2D, Ref("/robot/odometry"), doc="the base's (drifting) odometry")
    POSE_OUT = OutputPort("pose", Pose2D, "/robot/pose", doc="odometry corrected by the landmarks (odometry frame)")
    PORTS = (CAMERA, MOUNT, BEARING_SIGMA, FRAMES, ODOMETRY, POSE_OUT)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        mount = [float(v) for v in self.get_input(self.MOUNT)]
        if len(mount) != 3:
            raise ValueError(f"{self.name}: mount is [x, y, yaw_deg], got {mount}")
        self._mount = (mount[0], mount[1], math.radians(mount[2]))
        self._params = FilterParams(bearing_sigma=math.radians(self.get_input(self.BEARING_SIGMA)))
        self.filter: PoseFilter | None = None
        self._last_stamp: float | None = None
        self.corrections = 0
        self._max_sigma = (0.0, 0.0)

    def update(self) -> Status:
        odometry = self.get_input(self.ODOMETRY, None)
        if odometry is None:
            self.feedback_message = "waiting for odometry"
            return Status.SUCCESS
        f = PoseFilter.start(odometry, self._params) if self.filter is None else self.filter.predict(odometry)
        frame = (self.get_input(FRAMES, None) or {}).get(self.get_input(self.CAMERA))
        if isinstance(frame, LandmarkBearings) and frame.stamp != self._last_stamp:
            self._last_stamp = frame.stamp
            if len(frame.ids):
                f = f.update(frame.ids, frame.bearings, self._mount)
                self.corrections += 1
        self.filter = f
        position, heading = f.pose_sigma()
        self._max_sigma = (max(self._max_sigma[0], position), max(self._max_sigma[1], heading))
        self.set_output(self.POSE_OUT, f.pose)
        self.feedback_message = f"{len(f.ids)} landmarks, sigma {position:.2f} m {math.degrees(heading):.1f} deg"
        return Status.SUCCESS

    def figures(self) -> Iterator[Figure]:
        """The ``localisation`` section: landmarks mapped, corrections, the pose's uncertainty."""
        if self.filter is None:
            yield from (Figure("localisation", "landmarks", 0), Figure("localisation", "corrections", 0))
            return
        position, heading = self.filter.pose_sigma()
        odometry = self.filter.last_odometry
        pose = self.filter.pose
        yield from (Figure("localisation", name, value) for name, value in (
            ("landmarks", len(self.filter.ids)),
            ("corrections", self.corrections),
            ("position_sigma_m", position),
            ("heading_sigma_deg", math.degrees(heading)),
            ("max_position_sigma_m", self._max_sigma[0]),
            ("max_heading_sigma_deg", math.degrees(self._max_sigma[1])),
            ("correction_m", math.hypot(pose.x - odometry.x, pose.y - odometry.y) if odometry else 0.0),
            ("final_pose.x", pose.x), ("final_pose.y", pose.y), ("final_pose.theta", pose.theta),
        ))

    def drawings(self) -> Iterator[Drawing]:
        """The corrected pose and the mapped landmarks, in the odometry frame (every tick)."""
        if self.filter is None:
            return
        pose = self.filter.pose
        yield Points("odometry_frame/localisation/pose", np.array([[pose.x, pose.y]]), (60, 120, 255), radius=0.05)
        if self.filter.ids:
            sure = self.filter.landmark_range_sigma < 0.5
            labels = tuple(str(i) for i, ok in zip(self.filter.ids, sure, strict=True) if ok)
            yield Points("odometry_frame/localisation/landmarks", self.filter.landmarks[sure], (80, 140, 255),
                         radius=0.06, labels=labels)
