"""Drift correction: the odometry pose corrected by what a camera sees: :class:`LocalisePose`.

Two sources, told apart by what the node's ``camera`` delivers:

- a **stereo pair** (a :class:`~perception.frame.Frame` with a right image, on the pan-tilt unit):
  visual SLAM on the pair's own features (:class:`maps.slam.slam.StereoSlam`): ORB features
  matched along the epipolar lines (:func:`perception.stereo.sparse_stereo`), triangulated into
  landmarks, recognised again by descriptor where the predicted pose says they should be, fused
  with odometry; keyframes, loop closure in a pose graph. The head's angles come from ``ptu``.
  What a real robot has: the shipped ``explore`` mission runs on it.
- a **bearings sensor** (:class:`~perception.frame.LandmarkBearings`: landmarks handed over with
  their identity, the simulator's ideal ``landmarks`` camera): the EKF of
  :mod:`maps.exploration.pose`. No robot has such a sensor; it stays as the oracle an
  evaluation compares with (``bearings eval exploration --option localisation=ideal``).

The node starts at the first tick that has both odometry and a frame of its camera, at the
odometry pose (the corrected pose is in the odometry frame), and writes ``pose`` every tick from
then on: odometry increments predict every tick, each new frame corrects. Without frames the pose
follows odometry.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.exploration.ports import CAMERA_POSITION, FRAMES, PTU_POSITION, xyz
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.telemetry import Drawing, Figure, Points
from drivers.interfaces import PanTiltState
from maps.exploration.head import StereoHead
from maps.exploration.pose import FilterParams, PoseFilter
from maps.slam.slam import StereoSlam
from perception.frame import Frame, LandmarkBearings
from perception.geometry import Pose2D
from perception.stereo import sparse_stereo

TRACK_EVERY = 1.0  # s between the rows of the pose track in the report


@register
class LocalisePose(BearingsBehaviour):
    """Correct odometry drift from what ``camera`` sees (see the module docstring): visual SLAM on a
    stereo pair, or an EKF on an ideal sensor's identified landmark bearings.

    Every tick: predict with the odometry increment; on a new frame of ``camera``, correct. Writes
    the corrected pose to ``pose``. SUCCESS every tick (a perception step: it belongs under the
    mission's ``sense:``); before its first frame it writes nothing. Report section
    ``exploration``, figures ``localisation.*``: the source, landmarks, corrections, the pose's
    covariance (x, y, theta; m, rad) and its standard deviations, the largest of them, the
    correction of odometry, the final pose with its time, and ``track`` (every second: time, x, y,
    theta, sigma of the position, sigma of the heading).
    """

    CAMERA = InputPort("camera", str, "stereo", literal_only=True, camera=True,
                       doc="the camera the pose is corrected with: a stereo pair (visual SLAM on its features) or a "
                           "bearings sensor of identified landmarks (the simulator's ideal 'landmarks')")
    MOUNT = InputPort("mount", list[float], [0.0, 0.0, 0.0], unit="m, m, deg", literal_only=True,
                      doc="bearings sensor: where it sits on the base: x, y, yaw")
    BEARING_SIGMA = InputPort("bearing_sigma", float, 1.0, unit="deg", minimum=0.01, maximum=30.0, literal_only=True,
                              doc="bearings sensor: azimuth noise of a landmark on the horizon")
    FEATURES = InputPort("features", int, 600, minimum=50, maximum=5000, literal_only=True,
                         doc="stereo: ORB features detected per image")
    LEVELS = InputPort("levels", int, 3, minimum=1, maximum=8, literal_only=True,
                       doc="stereo: ORB pyramid levels (1: full resolution only; more find corners of blurred "
                           "texture and recognise points from nearer and farther)")
    PTU = InputPort("ptu", PanTiltState, Ref("/ptu/state"), doc="stereo: the pan-tilt angles the frame was taken at")
    ODOMETRY = InputPort("odometry", Pose2D, Ref("/robot/odometry"), doc="the base's (drifting) odometry")
    POSE_OUT = OutputPort("pose", Pose2D, "/robot/pose", doc="odometry corrected by what the camera sees (odometry "
                                                             "frame)")
    PORTS = (CAMERA, MOUNT, BEARING_SIGMA, FEATURES, LEVELS, PTU_POSITION, CAMERA_POSITION, FRAMES, PTU, ODOMETRY,
             POSE_OUT)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        mount = [float(v) for v in self.get_input(self.MOUNT)]
        if len(mount) != 3:
            raise ValueError(f"{self.name}: mount is [x, y, yaw_deg], got {mount}")
        self._mount = (mount[0], mount[1], math.radians(mount[2]))
        self._params = FilterParams(bearing_sigma=math.radians(self.get_input(self.BEARING_SIGMA)))
        self._head = StereoHead(xyz(self.get_input(PTU_POSITION), "ptu_position"),
                                xyz(self.get_input(CAMERA_POSITION), "camera_position"))
        self.filter: PoseFilter | None = None  # the bearings sensor's EKF
        self.slam: StereoSlam | None = None  # the stereo pair's SLAM
        self._last_stamp: float | None = None
        self.corrections = 0
        self._max_sigma = (0.0, 0.0)
        self.track: list[list[float]] = []
        self._drawn_keyframes = -1

    # -- every tick ------------------------------------------------------------------------------
    def update(self) -> Status:
        odometry = self.get_input(self.ODOMETRY, None)
        frame = (self.get_input(FRAMES, None) or {}).get(self.get_input(self.CAMERA))
        if odometry is None:
            self.feedback_message = "waiting for odometry"
            return Status.SUCCESS
        if self.filter is None and self.slam is None and not self._start(odometry, frame):
            self.feedback_message = f"waiting for a frame of {self.get_input(self.CAMERA)!r}"
            return Status.SUCCESS
        if self.slam is not None:
            self._stereo(odometry, frame)
        else:
            self._bearings(odometry, frame)
        pose, covariance = self.pose_and_covariance()
        position, heading = _sigmas(covariance)
        self._max_sigma = (max(self._max_sigma[0], position), max(self._max_sigma[1], heading))
        if not self.track or self.now() - self.track[-1][0] >= TRACK_EVERY - 1e-6:
            self.track.append([round(self.now(), 2), round(pose.x, 4), round(pose.y, 4), round(pose.theta, 5),
                               round(position, 4), round(heading, 5)])
        self.set_output(self.POSE_OUT, pose)
        self.feedback_message = (f"{self._landmark_count()} landmarks, sigma {position:.2f} m "
                                 f"{math.degrees(heading):.1f} deg")
        return Status.SUCCESS

    def _start(self, odometry: Pose2D, frame: Any) -> bool:
        """Start the source the camera's first frame calls for; False while there is none."""
        if isinstance(frame, LandmarkBearings):
            self.filter = PoseFilter.start(odometry, self._params)
        elif isinstance(frame, Frame) and frame.right is not None:
            self.slam = StereoSlam.start(odometry, self._head)
        elif isinstance(frame, Frame):
            raise ValueError(f"{self.name}: camera {frame.camera_name!r} is not a stereo pair nor a bearings sensor")
        else:
            return False
        return True

    def _stereo(self, odometry: Pose2D, frame: Any) -> None:
        assert self.slam is not None
        self.slam.predict(odometry)
        ptu = self.get_input(self.PTU, None)
        if not isinstance(frame, Frame) or frame.right is None or frame.stamp == self._last_stamp:
            return
        self._last_stamp = frame.stamp
        stereo = sparse_stereo(frame.image, frame.right, frame.camera, n_features=self.get_input(self.FEATURES),
                               levels=self.get_input(self.LEVELS))
        pan, tilt = (ptu.pan, ptu.tilt) if ptu is not None else (0.0, 0.0)
        outcome = self.slam.observe(stereo, frame.camera, pan, tilt, frame.stamp)
        if outcome.used >= self.slam.params.min_update:
            self.corrections += 1

    def _bearings(self, odometry: Pose2D, frame: Any) -> None:
        assert self.filter is not None
        f = self.filter.predict(odometry)
        if isinstance(frame, LandmarkBearings) and frame.stamp != self._last_stamp:
            self._last_stamp = frame.stamp
            if len(frame.ids):
                f = f.update(frame.ids, frame.bearings, self._mount)
                self.corrections += 1
        self.filter = f

    def pose_and_covariance(self) -> tuple[Pose2D, np.ndarray]:
        """The corrected pose and its (x, y, theta) covariance in the odometry frame."""
        if self.slam is not None:
            return self.slam.pose, self.slam.covariance
        assert self.filter is not None
        return self.filter.pose, self.filter.covariance[:3, :3]

    def _landmark_count(self) -> int:
        if self.slam is not None:
            return len(self.slam.landmarks)
        return len(self.filter.ids) if self.filter is not None else 0

    # -- telemetry -------------------------------------------------------------------------------
    def figures(self) -> Iterator[Figure]:
        """The ``exploration`` section's ``localisation`` part (see the class docstring)."""
        source = "visual" if self.slam is not None else "ideal" if self.filter is not None else "none"
        yield from (Figure("exploration", "localisation.source", source),
                    Figure("exploration", "localisation.landmarks", self._landmark_count()),
                    Figure("exploration", "localisation.corrections", self.corrections))
        if self.slam is None and self.filter is None:
            return
        pose, covariance = self.pose_and_covariance()
        position, heading = _sigmas(covariance)
        odometry = self.slam.odometry if self.slam is not None else self.filter.last_odometry  # type: ignore[union-attr]
        values: list[tuple[str, Any]] = [
            ("covariance", np.round(covariance, 9).tolist()),
            ("position_sigma_m", position), ("heading_sigma_deg", math.degrees(heading)),
            ("max_position_sigma_m", self._max_sigma[0]), ("max_heading_sigma_deg", math.degrees(self._max_sigma[1])),
            ("correction_m", math.hypot(pose.x - odometry.x, pose.y - odometry.y) if odometry else 0.0),
            ("final_pose.x", pose.x), ("final_pose.y", pose.y), ("final_pose.theta", pose.theta),
            ("final_pose.t", pose.stamp),
        ]
        if self.slam is not None:
            s = self.slam
            values += [("keyframes", len(s.keyframes)), ("loop_closures", len(s.loops)), ("frames", s.frames),
                       ("found_per_frame", s.found / max(s.frames, 1)), ("culled", s.culled), ("merged", s.merged),
                       ("odometry_turn_scale", s.turns.scale)]
        values.append(("track", [*self.track]))
        yield from (Figure("exploration", f"localisation.{name}", value) for name, value in values)

    def drawings(self) -> Iterator[Drawing]:
        """The corrected pose (every tick) and the landmarks (the SLAM's at each new keyframe, the
        EKF's every tick), in the odometry frame."""
        if self.slam is None and self.filter is None:
            return
        pose, _ = self.pose_and_covariance()
        yield Points("odometry_frame/localisation/pose", np.array([[pose.x, pose.y]]), (60, 120, 255), radius=0.05)
        if self.slam is not None:
            if len(self.slam.keyframes) != self._drawn_keyframes and len(self.slam.landmarks):
                self._drawn_keyframes = len(self.slam.keyframes)
                yield Points("odometry_frame/localisation/landmarks", self.slam.landmarks.positions[:, :2],
                             (80, 140, 255), radius=0.02)
            return
        assert self.filter is not None
        if self.filter.ids:
            sure = self.filter.landmark_range_sigma < 0.5
            labels = tuple(str(i) for i, ok in zip(self.filter.ids, sure, strict=True) if ok)
            yield Points("odometry_frame/localisation/landmarks", self.filter.landmarks[sure], (80, 140, 255),
                         radius=0.06, labels=labels)


def _sigmas(covariance: np.ndarray) -> tuple[float, float]:
    """Standard deviations of the position (m, along its worst axis) and of the heading (rad)."""
    worst = float(np.linalg.eigvalsh(covariance[:2, :2])[-1])
    return math.sqrt(max(worst, 0.0)), math.sqrt(max(float(covariance[2, 2]), 0.0))
