"""The drift-correcting pose filter (EKF over pose and inverse-depth landmarks), by hand and on a drive."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration.pose import FilterParams, PoseFilter
from perception.geometry import Pose2D, wrap_angle

LANDMARKS = {1: (4.0, 0.0), 2: (0.0, 5.0), 3: (-3.0, -3.0), 4: (3.0, 3.0)}


def bearings_from(pose: Pose2D, ids=LANDMARKS) -> tuple[np.ndarray, np.ndarray]:
    """Unit bearings (sensor frame, level) of the landmarks seen from a TRUE pose."""
    keys = sorted(ids)
    out = []
    for k in keys:
        x, y = LANDMARKS[k]
        a = math.atan2(y - pose.y, x - pose.x) - pose.theta
        out.append([math.cos(a), math.sin(a), 0.0])
    return np.array(keys), np.array(out)


def test_starts_at_the_first_odometry_pose_certain_of_it():
    f = PoseFilter.start(Pose2D(1.0, 2.0, 0.5))
    assert (f.pose.x, f.pose.y, f.pose.theta) == (1.0, 2.0, 0.5)
    assert f.pose_sigma() == (0.0, 0.0)


def test_prediction_composes_the_odometry_increment_in_the_robot_frame():
    f = PoseFilter.start(Pose2D(0.0, 0.0, 0.0))
    f = PoseFilter(np.array([1.0, 1.0, math.pi / 2]), np.zeros((3, 3)), last_odometry=Pose2D(0.0, 0.0, 0.0))
    f = f.predict(Pose2D(1.0, 0.0, 0.1))  # 1 m forward and 0.1 rad left, in the robot frame
    assert f.pose.x == pytest.approx(1.0) and f.pose.y == pytest.approx(2.0)
    assert f.pose.theta == pytest.approx(math.pi / 2 + 0.1)
    position, heading = f.pose_sigma()
    assert position == pytest.approx(math.sqrt(0.02**2 + 1e-4), rel=1e-3)  # OdometryNoise: 2 % and 1e-4 m^2/m
    assert heading == pytest.approx(math.sqrt((0.03 * 0.1) ** 2 + 4e-4 + 4e-4 * 0.1), rel=1e-3)


def test_a_landmark_seen_first_enters_in_inverse_depth_along_its_ray():
    f = PoseFilter.start(Pose2D())
    ids, b = bearings_from(Pose2D(), {1: None})
    f = f.update(ids, b)
    assert f.ids == (1,)
    x0, y0, alpha, rho = f.mean[3:7]
    assert (x0, y0, alpha, rho) == pytest.approx((0.0, 0.0, 0.0, FilterParams().rho0))
    assert f.landmarks[0] == pytest.approx([1.0 / FilterParams().rho0, 0.0])


def test_turning_on_the_spot_corrects_the_heading_before_any_landmark_has_a_distance():
    """Odometry under-counts a turn by 10 %: the landmarks seen before the turn tell the true heading."""
    f = PoseFilter.start(Pose2D())
    f = f.update(*bearings_from(Pose2D()))
    true = 0.0
    for _ in range(30):  # 90 degrees in 3-degree steps, odometry counts 2.7 each
        true += math.radians(3.0)
        f = f.predict(Pose2D(0.0, 0.0, f.last_odometry.theta + math.radians(2.7)))
        f = f.update(*bearings_from(Pose2D(0.0, 0.0, true)))
    assert math.degrees(abs(wrap_angle(f.pose.theta - true))) < 1.5  # odometry alone: 9 degrees off (3x the model)
    assert math.degrees(abs(wrap_angle(f.last_odometry.theta - true))) == pytest.approx(9.0)


def test_driving_maps_the_landmarks_and_keeps_heading_and_position():
    """A square drive whose odometry drifts 5 % in every turn and 2 % in distance; noisy bearings."""
    rng = np.random.default_rng(3)
    true, odo = Pose2D(), Pose2D()
    f = PoseFilter.start(odo)
    for leg in range(8):
        for _ in range(20):
            step = (0.05, 0.0) if leg % 2 == 0 else (0.0, math.radians(4.5))
            true = true.compose(Pose2D(step[0], 0.0, step[1]))
            odo = odo.compose(Pose2D(step[0] * 1.02, 0.0, step[1] * 0.95))
            f = f.predict(odo)
            ids, b = bearings_from(true)
            noise = rng.normal(0.0, math.radians(0.5), len(ids))
            c, s = np.cos(noise), np.sin(noise)
            b = np.column_stack((c * b[:, 0] - s * b[:, 1], s * b[:, 0] + c * b[:, 1], b[:, 2]))
            f = f.update(ids, b)
    assert math.degrees(abs(wrap_angle(odo.theta - true.theta))) > 10.0
    assert math.degrees(abs(wrap_angle(f.pose.theta - true.theta))) < 1.5
    assert math.hypot(f.pose.x - true.x, f.pose.y - true.y) < 0.1
    for k, xy in zip(f.ids, f.landmarks, strict=True):
        assert np.hypot(*(xy - np.array(LANDMARKS[k]))) < 0.5


def test_an_innovation_beyond_the_gate_is_ignored():
    f = PoseFilter.start(Pose2D())
    f = f.update(*bearings_from(Pose2D()))
    ids, b = bearings_from(Pose2D())
    wrong = b.copy()
    wrong[0] = [math.cos(1.0), math.sin(1.0), 0.0]  # landmark 1 suddenly 57 degrees off: a wrong id
    g = f.update(ids, wrong)
    assert g.pose.theta == pytest.approx(f.pose.theta, abs=1e-6)


def test_no_landmarks_is_plain_odometry():
    f = PoseFilter.start(Pose2D())
    for i in range(1, 6):
        f = f.predict(Pose2D(0.1 * i, 0.0, 0.01 * i)).update(np.zeros(0), np.zeros((0, 3)))
    assert (f.pose.x, f.pose.theta) == pytest.approx((0.5, 0.05))
