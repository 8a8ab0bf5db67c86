"""Localisation figures for ``bearings bench localisation --json``: the visual SLAM against the ideal EKF.

A scripted drive in ``lab`` at the explore mission's 5 Hz (the head looks about, the base turns on the
spot, then drives and turns), every frame of both cameras rendered first (not timed), then fed to
both localisations with the same odometry:

- ``ideal_ms_per_frame``: CPU of :class:`maps.exploration.pose.PoseFilter` (prediction and update on
  the ideal ``landmarks`` sensor's identified bearings) per frame;
- ``visual_stereo_ms``: CPU of :func:`perception.stereo.sparse_stereo` (ORB on both images, matching
  along the rows, sub-pixel corners) per frame; ``visual_slam_ms``: CPU of
  :class:`maps.slam.slam.StereoSlam` (prediction, association, update, keyframes, loops) per frame;
  ``visual_ms_per_frame`` their sum and ``visual_vs_ideal_cost_ratio`` its ratio to the EKF's;
- ``*_position_error_m``, ``*_heading_error_deg``: each pose (and odometry's) against the truth at
  the end of the drive.

CPU time of this process (``time.process_time``) with OpenCV on one thread; medians over the frames.
"""

from __future__ import annotations

import math
import time
from typing import Any

import cv2
import numpy as np

from drivers.interfaces import PanTiltState
from drivers.sim.simulation import Simulation
from maps.exploration.head import StereoHead
from maps.exploration.pose import PoseFilter
from maps.slam.slam import StereoSlam
from perception.frame import Frame, LandmarkBearings
from perception.geometry import Pose2D, wrap_angle
from perception.stereo import sparse_stereo

RATE = 5.0  # Hz, the explore mission's


def _script(frames: int) -> list[tuple[float, float, float, float]]:
    """(v, w, pan, tilt) per frame: look about, turn on the spot, drive and turn."""
    third = max(1, frames // 3)
    look = [(0.0, 0.0, 0.8 * math.sin(i / 3.0), -0.3) for i in range(third)]
    turn = [(0.0, 1.0, 0.0, -0.4)] * third
    drive = [(0.3, 0.4 * math.sin(i / 4.0), 0.3 * math.sin(i / 5.0), -0.5) for i in range(frames - 2 * third)]
    return look + turn + drive


def _errors(pose: Pose2D, truth: Pose2D) -> tuple[float, float]:
    return math.hypot(pose.x - truth.x, pose.y - truth.y), math.degrees(abs(wrap_angle(pose.theta - truth.theta)))


def run(quick: bool = False) -> dict[str, Any]:
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        return _measure(12 if quick else 75)
    finally:
        cv2.setNumThreads(threads)


def _measure(frames: int) -> dict[str, Any]:
    sim = Simulation.load("lab", seed=0)
    start = sim.true_pose()
    rows: list[tuple[Pose2D, PanTiltState, Frame, LandmarkBearings]] = []
    for v, w, pan, tilt in _script(frames):
        sim.ptu.move(pan, tilt, 2.0)
        sim.robot.base.drive(v, w)
        stereo, landmarks = sim.robot.cameras["stereo"].grab(), sim.robot.cameras["landmarks"].grab()
        if not isinstance(stereo, Frame) or stereo.right is None or not isinstance(landmarks, LandmarkBearings):
            raise RuntimeError("the lab world's stereo and landmarks cameras gave no frame")
        rows.append((sim.robot.base.odometry(), sim.ptu.state(), stereo, landmarks))
        sim.step(1.0 / RATE)
    odometry0 = rows[0][0]
    ekf = PoseFilter.start(odometry0)
    slam = StereoSlam.start(odometry0, StereoHead())
    ideal, stereo_ms, slam_ms = [], [], []
    for odometry, ptu, stereo, landmarks in rows:
        begin = time.process_time()
        ekf = ekf.predict(odometry)
        if len(landmarks.ids):
            ekf = ekf.update(landmarks.ids, landmarks.bearings)
        ideal.append(time.process_time() - begin)
        assert stereo.right is not None  # checked when recorded
        begin = time.process_time()
        features = sparse_stereo(stereo.image, stereo.right, stereo.camera, n_features=600, levels=3)
        middle = time.process_time()
        slam.predict(odometry)
        slam.observe(features, stereo.camera, ptu.pan, ptu.tilt, stereo.stamp)
        stereo_ms.append(middle - begin)
        slam_ms.append(time.process_time() - middle)
    # the truth when the last frame was taken: the simulation stepped once more after it
    truth = sim.truth.true[-2]
    end = Pose2D(truth[1], truth[2], truth[3]).relative_to(start)
    figures: dict[str, Any] = {"world": "lab", "frames": frames, "rate_hz": RATE, "threads": 1}
    median = {name: float(np.median(values)) * 1e3 for name, values in
              (("ideal", ideal), ("stereo", stereo_ms), ("slam", slam_ms))}
    visual = median["stereo"] + median["slam"]
    figures.update({
        "ideal_ms_per_frame": round(median["ideal"], 3),
        "visual_stereo_ms": round(median["stereo"], 3),
        "visual_slam_ms": round(median["slam"], 3),
        "visual_ms_per_frame": round(visual, 3),
        "visual_vs_ideal_cost_ratio": round(visual / max(median["ideal"], 1e-6), 1),
        "visual_keyframes": len(slam.keyframes),
        "visual_landmarks": len(slam.landmarks),
    })
    for name, pose in (("ideal", ekf.pose), ("visual", slam.pose), ("odometry", rows[-1][0])):
        position, heading = _errors(pose, end)
        figures[f"{name}_position_error_m"] = round(position, 4)
        figures[f"{name}_heading_error_deg"] = round(heading, 3)
    return figures
