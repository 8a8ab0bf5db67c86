"""Where the left stereo camera is for a base pose and head angles: points between world and camera.

The base pose is ``X = (x, y, theta)`` in the odometry frame; the head (:class:`StereoHead`) puts
the left camera at ``e_b = ptu + R0 c`` on the base with the rotation ``R0 = Rz(pan) Rpitch(tilt)``
(base from camera body). A world point ``P`` is, in the base frame and in the camera's body frame,

    q = Rz(-theta) (P - (x, y, 0)),      p = R0^T (q - e_b)                            (V1)

and back ``P = (x, y, 0) + Rz(theta) (R0 p + e_b)``. The Jacobians are those of (V1):
``dq/dx = Rz(-theta) (-1, 0, 0)``, ``dq/dy = Rz(-theta) (0, -1, 0)``, ``dq/dtheta = (q_y, -q_x, 0)``
(the base-frame point turned by -90 degrees), ``dp/d(.) = R0^T dq/d(.)``, ``dp/dP = R0^T Rz(-theta)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maps.exploration.head import StereoHead
from perception.geometry import rot_pitch, rot_z


@dataclass(frozen=True, slots=True)
class Viewpoint:
    """The left camera on the base for one pair of head angles: ``rotation`` (base from camera body,
    ``R0``) and ``eye`` (its centre in the base frame, ``e_b``)."""

    rotation: np.ndarray
    eye: np.ndarray

    @classmethod
    def of(cls, head: StereoHead, pan: float, tilt: float) -> Viewpoint:
        """The left camera of ``head`` at (pan, tilt) rad."""
        rotation = rot_z(pan) @ rot_pitch(tilt)
        return cls(rotation, np.asarray(head.ptu, dtype=np.float64) + rotation @ np.asarray(head.camera, np.float64))

    def base_points(self, camera_points: np.ndarray) -> np.ndarray:
        """Camera body points (N, 3) in the base frame: ``R0 p + e_b``."""
        return np.asarray(camera_points, dtype=np.float64).reshape(-1, 3) @ self.rotation.T + self.eye

    def to_camera(self, pose: np.ndarray, world: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World points (N, 3) in the camera body frame at base pose ``pose`` (x, y, theta), by (V1),
        with the Jacobians (N, 3, 3) with respect to the pose and to the world point."""
        x, y, theta = (float(v) for v in pose)
        c, s = math.cos(theta), math.sin(theta)
        to_base = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # Rz(-theta)
        q = (np.asarray(world, dtype=np.float64).reshape(-1, 3) - (x, y, 0.0)) @ to_base.T
        p = (q - self.eye) @ self.rotation  # rows of R0^T (q - e_b)
        dq = np.zeros((len(q), 3, 3))  # dq / d(x, y, theta)
        dq[:, 0, 0], dq[:, 1, 0] = -c, s
        dq[:, 0, 1], dq[:, 1, 1] = -s, -c
        dq[:, 0, 2], dq[:, 1, 2] = q[:, 1], -q[:, 0]
        d_pose = np.einsum("ji,njk->nik", self.rotation, dq)  # R0^T dq
        d_point = np.broadcast_to(self.rotation.T @ to_base, (len(q), 3, 3))
        return p, d_pose, d_point

    def to_world(self, pose: np.ndarray, camera_points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Camera body points (N, 3) in the world at base pose ``pose``, with the Jacobians (N, 3, 3)
        with respect to the pose and to the camera point."""
        x, y, theta = (float(v) for v in pose)
        turn = rot_z(theta)
        b = self.base_points(camera_points) @ turn.T  # Rz(theta) (R0 p + e_b)
        world = b + (x, y, 0.0)
        d_pose = np.zeros((len(b), 3, 3))
        d_pose[:, 0, 0] = d_pose[:, 1, 1] = 1.0
        d_pose[:, 0, 2], d_pose[:, 1, 2] = -b[:, 1], b[:, 0]
        d_camera = np.broadcast_to(turn @ self.rotation, (len(b), 3, 3))
        return world, d_pose, d_camera
