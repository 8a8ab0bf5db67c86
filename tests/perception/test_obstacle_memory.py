"""Obstacle points remembered in the odometry frame for a second."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.geometry import Pose2D, frame_to_parent, parent_to_frame
from perception.obstacle_memory import ObstacleMemory


def test_points_go_to_the_odometry_frame_and_back():
    pose = Pose2D(1.0, 2.0, math.pi / 2)
    # 1 m ahead of a base facing +y at (1, 2) is (1, 3)
    assert frame_to_parent(pose, np.array([[1.0, 0.0]])) == pytest.approx(np.array([[1.0, 3.0]]))
    points = np.array([[0.3, -0.2], [2.0, 1.0]])
    assert parent_to_frame(pose, frame_to_parent(pose, points)) == pytest.approx(points)


def test_a_remembered_point_stays_where_it_was_as_the_robot_moves():
    memory = ObstacleMemory(keep=1.0).added(np.array([[2.0, 0.0]]), Pose2D(0.0, 0.0, 0.0), stamp=0.0)
    # the robot drove 0.5 m and turned left 90 degrees: the point is 1.5 m to its right
    assert memory.around(Pose2D(0.5, 0.0, math.pi / 2), now=0.5) == pytest.approx(np.array([[0.0, -1.5]]))


def test_old_scans_are_forgotten_and_a_scan_is_added_once():
    memory = ObstacleMemory(keep=1.0)
    for t in (0.0, 0.4, 0.4, 0.8):
        memory = memory.added(np.array([[1.0, t]]), Pose2D(), stamp=t)
    assert memory.stamps == (0.0, 0.4, 0.8)
    assert len(memory.around(Pose2D(), now=0.8)) == 3
    assert memory.around(Pose2D(), now=1.3)[:, 1] == pytest.approx([0.4, 0.8])  # 0.0 is older than a second
    memory = memory.added(np.zeros((0, 2)), Pose2D(), stamp=1.5)  # a scan with no echo
    assert memory.stamps == (0.8, 1.5) and len(memory.around(Pose2D(), now=1.5)) == 1
    assert len(memory.around(Pose2D(), now=5.0)) == 0
