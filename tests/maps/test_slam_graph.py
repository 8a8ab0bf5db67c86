"""The pose graph (G1): relative poses, whiteners and a least-squares solution worked by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.slam.graph import Edge, compose, optimise, relative, whitener


def test_a_pose_in_the_frame_of_another_and_back_by_hand():
    # a at (1, 2) facing +y; b at (1, 3) facing -x: b is 1 m straight ahead of a, turned a further 90 degrees
    a, b = np.array([1.0, 2.0, math.pi / 2]), np.array([1.0, 3.0, math.pi])
    assert relative(a, b)[0] == pytest.approx([1.0, 0.0, math.pi / 2])
    assert abs(compose(a, np.array([1.0, 0.0, math.pi / 2]))) == pytest.approx([1.0, 3.0, math.pi])


def test_the_whitener_squares_to_the_information():
    # covariance diag(4, 1, 0.25): information diag(1/4, 1, 4), so L = diag(1/2, 1, 2)
    assert np.abs(whitener(np.diag([4.0, 1.0, 0.25]))) == pytest.approx(np.diag([0.5, 1.0, 2.0]))


def test_a_loop_shorter_than_odometry_shares_its_error_by_the_weights():
    # three poses on a line (headings 0), the first fixed at 0; odometry: 1 m, then 1 m; the loop: 1.8 m.
    # Equal weights minimise (x1 - 1)^2 + (x2 - x1 - 1)^2 + (x2 - 1.8)^2: 2 x1 - x2 = 0, 2 x2 - x1 = 2.8,
    # so x1 = 2.8 / 3 = 0.9333, x2 = 5.6 / 3 = 1.8667: each edge takes a third of the 0.2 m.
    start = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    unit = whitener(np.eye(3) * 0.01)
    odometry = [Edge(0, 1, np.array([1.0, 0.0, 0.0]), unit), Edge(1, 2, np.array([1.0, 0.0, 0.0]), unit)]
    solved = optimise(start, [*odometry, Edge(0, 2, np.array([1.8, 0.0, 0.0]), unit)])
    assert solved[:, 0] == pytest.approx([0.0, 2.8 / 3.0, 5.6 / 3.0], abs=1e-6)
    assert solved[:, 1:] == pytest.approx(np.zeros((3, 2)), abs=1e-9)
    # a loop a million times surer holds x2 at 1.8; the odometry edges split the rest: x1 = 0.9
    stiff = optimise(start, [*odometry, Edge(0, 2, np.array([1.8, 0.0, 0.0]), whitener(np.eye(3) * 1e-8))])
    assert stiff[:, 0] == pytest.approx([0.0, 0.9, 1.8], abs=1e-5)
