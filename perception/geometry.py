"""Planar robot geometry shared by every layer: poses, angle wrapping, frame conventions.

Conventions (REP-103): x forward, y left, z up; angles in radians, counter-clockwise positive.
Bearing vectors produced by any camera model are unit 3-vectors in the camera body frame with the
same axes (x along the optical axis / panorama centre column, y left, z up).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def rot_z(angle: float) -> np.ndarray:
    """Rotation about the vertical axis by ``angle`` rad (REP-103: x forward, y left, z up)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rot_pitch(pitch: float) -> np.ndarray:
    """Rotation that lifts the x axis by ``pitch`` rad (about y by ``-pitch``; positive looks up):
    a pan-tilt head's tilt."""
    c, s = math.cos(pitch), math.sin(pitch)
    return np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])


def wrap_angle(angle: float) -> float:
    """Wrap an angle to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def wrap_angles(angles: np.ndarray) -> np.ndarray:
    """Vectorised :func:`wrap_angle`."""
    return (np.asarray(angles) + np.pi) % (2.0 * np.pi) - np.pi


@dataclass(frozen=True, slots=True)
class Pose2D:
    """A planar pose (x, y in metres, theta in radians) with the time it was measured."""

    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0
    stamp: float = 0.0

    def compose(self, other: Pose2D) -> Pose2D:
        """This pose followed by ``other`` expressed in this pose's frame."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return Pose2D(
            x=self.x + c * other.x - s * other.y,
            y=self.y + s * other.x + c * other.y,
            theta=wrap_angle(self.theta + other.theta),
            stamp=max(self.stamp, other.stamp),
        )

    def inverse(self) -> Pose2D:
        """The pose that undoes this one."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return Pose2D(
            x=-(c * self.x + s * self.y),
            y=-(-s * self.x + c * self.y),
            theta=wrap_angle(-self.theta),
            stamp=self.stamp,
        )

    def relative_to(self, origin: Pose2D) -> Pose2D:
        """This pose expressed in the frame of ``origin``."""
        return origin.inverse().compose(self)

    def distance_to(self, other: Pose2D) -> float:
        """Euclidean distance between the two positions (m)."""
        return math.hypot(other.x - self.x, other.y - self.y)

    def as_array(self) -> np.ndarray:
        """``[x, y, theta]`` as a float array."""
        return np.array([self.x, self.y, self.theta], dtype=float)


def frame_to_parent(frame: Pose2D, xy: np.ndarray) -> np.ndarray:
    """(x, y) rows (N x 2) given in the frame of the pose ``frame`` (origin there, x ahead, y left),
    in the frame that pose is given in (a base's points in odometry, a run's start frame in the world)."""
    c, s = math.cos(frame.theta), math.sin(frame.theta)
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    return np.column_stack([frame.x + c * xy[:, 0] - s * xy[:, 1], frame.y + s * xy[:, 0] + c * xy[:, 1]])


def parent_to_frame(frame: Pose2D, xy: np.ndarray) -> np.ndarray:
    """The inverse of :func:`frame_to_parent`: (x, y) rows in the frame of the pose ``frame``."""
    c, s = math.cos(frame.theta), math.sin(frame.theta)
    rel = np.asarray(xy, dtype=np.float64).reshape(-1, 2) - (frame.x, frame.y)
    return np.column_stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]])
