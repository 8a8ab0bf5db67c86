"""Where the stereo pair on the pan-tilt unit looks from: the head on the base, a camera view, its floor footprint."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from perception.camera import PinholeCamera, StereoRig
from perception.geometry import Pose2D, rot_pitch, rot_z


@dataclass(frozen=True, slots=True)
class CameraView:
    """The left stereo camera at one instant, in the odometry frame.

    ``rotation`` maps camera body vectors (x forward, y left, z up) to the odometry frame;
    ``heading`` is the robot's (its direction of travel, for phi of eq. 2).
    """

    eye: np.ndarray
    rotation: np.ndarray
    vertical_fov: float
    horizontal_fov: float
    heading: float


def vertical_fov(camera: PinholeCamera) -> float:
    """Angle (rad) between the top and bottom edges of the image along its centre column."""
    edges = camera.pixel_to_bearing(np.array([[camera.cx, -0.5], [camera.cx, camera.height - 0.5]]))
    return float(np.arccos(np.clip(edges[0] @ edges[1], -1.0, 1.0)))


def horizontal_fov(camera: PinholeCamera) -> float:
    """Angle (rad) between the left and right edges of the image along its centre row."""
    edges = camera.pixel_to_bearing(np.array([[-0.5, camera.cy], [camera.width - 0.5, camera.cy]]))
    return float(np.arccos(np.clip(edges[0] @ edges[1], -1.0, 1.0)))


@dataclass(frozen=True, slots=True)
class StereoHead:
    """The stereo pair on the pan-tilt unit: the pan/tilt axes' intersection on the base, the left
    camera on the head (both REP-103, metres; the world file's ``ptu.position`` and the camera's
    ``pose``), and the fields of view. Defaults: the simulator's default ``stereo`` camera."""

    ptu: tuple[float, float, float] = (0.1, 0.0, 1.0)
    camera: tuple[float, float, float] = (0.05, 0.0, 0.08)
    vertical_fov: float = 2.0 * math.atan(240.0 / 525.0)
    horizontal_fov: float = 2.0 * math.atan(320.0 / 525.0)

    @classmethod
    def for_rig(cls, rig: StereoRig, ptu: tuple[float, float, float], camera: tuple[float, float, float]) -> StereoHead:
        return cls(ptu, camera, vertical_fov(rig.left), horizontal_fov(rig.left))

    @property
    def lens_height(self) -> float:
        """Height of the lens above the floor with the head level (m)."""
        return self.ptu[2] + self.camera[2]

    def axis_xy(self, robot: Pose2D) -> np.ndarray:
        """Where the pan axis stands on the floor (odometry frame)."""
        c, s = math.cos(robot.theta), math.sin(robot.theta)
        return np.array([robot.x + c * self.ptu[0] - s * self.ptu[1], robot.y + s * self.ptu[0] + c * self.ptu[1]])

    def view(self, robot: Pose2D, pan: float, tilt: float) -> CameraView:
        """The left camera when the base is at ``robot`` (odometry) and the head at (pan, tilt)."""
        rotation = rot_z(robot.theta + pan) @ rot_pitch(tilt)
        head = np.array([*self.axis_xy(robot), self.ptu[2]])
        eye = head + rotation @ np.asarray(self.camera, dtype=np.float64)
        return CameraView(eye, rotation, self.vertical_fov, self.horizontal_fov, robot.theta)


def footprint(view: CameraView) -> tuple[np.ndarray, float, float]:
    """The floor seen by the camera, along its axis: (unit plan direction, near, far distance).

    Near and far are plan distances from the eye to where the bottom and top image rows meet the
    floor (near = inf: the camera sees no floor; far = inf: the top row is above the horizon).
    """
    half = view.vertical_fov / 2.0
    bottom = view.rotation @ np.array([math.cos(half), 0.0, -math.sin(half)])
    top = view.rotation @ np.array([math.cos(half), 0.0, math.sin(half)])
    axis = view.rotation[:2, 0]
    norm = float(np.hypot(*axis))
    direction = axis / norm if norm > 1e-9 else bottom[:2] / max(float(np.hypot(*bottom[:2])), 1e-12)

    def reach(ray: np.ndarray) -> float:
        if ray[2] >= -1e-12:
            return math.inf
        return max(0.0, float(view.eye[2] * (ray[:2] @ direction) / -ray[2]))  # 0: the floor under the eye

    return direction, reach(bottom), reach(top)

