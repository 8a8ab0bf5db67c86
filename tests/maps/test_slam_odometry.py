"""Odometry's turns calibrated against the cameras (O1), by hand."""

from __future__ import annotations

import math

import pytest

from maps.slam.odometry import TurnCalibration, calibrated
from perception.geometry import Pose2D


def test_the_turn_factor_is_the_slope_through_the_origin_once_enough_was_turned():
    calibration = TurnCalibration(min_turn=1.0).add(0.5, 0.51)
    assert calibration.scale == 1.0  # 0.5 rad turned: not yet
    calibration = calibration.add(0.6, 0.612)
    # (0.5 * 0.51 + 0.6 * 0.612) / (0.5^2 + 0.6^2) = 0.6222 / 0.61 = 1.02
    assert calibration.scale == pytest.approx(1.02)
    assert calibration.turned == pytest.approx(1.1)


def test_the_factor_stays_within_its_bounds():
    assert TurnCalibration(min_turn=0.0).add(1.0, 2.0).scale == 1.1
    assert TurnCalibration(min_turn=0.0).add(1.0, -1.0).scale == 0.9


def test_the_increment_is_taken_in_the_robots_frame_and_its_turn_scaled():
    # odometry: 1 m ahead while facing +y, turning 0.1 rad; the calibrated pose faces +x
    last, now = Pose2D(1.0, 1.0, math.pi / 2), Pose2D(1.0, 2.0, math.pi / 2 + 0.1, 3.0)
    pose = calibrated(Pose2D(), last, now, 1.02)
    assert (pose.x, pose.y, pose.theta, pose.stamp) == pytest.approx((1.0, 0.0, 0.102, 3.0))
