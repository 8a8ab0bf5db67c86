"""The pose update (T1)-(T2): a heading corrected by one far landmark, worked by hand; a pose found again."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration.head import StereoHead
from maps.slam.tracking import refine_pose
from maps.slam.viewpoint import Viewpoint
from perception.camera import PinholeCamera, StereoRig
from perception.stereo_geometry import project

CAMERA = PinholeCamera(640, 480, 500.0, 500.0, 320.0, 240.0)
RIG = StereoRig(CAMERA, CAMERA, 0.1)
HEAD = StereoHead(ptu=(0.1, 0.0, 1.0), camera=(0.05, 0.0, 0.08))
LEVEL = Viewpoint.of(HEAD, 0.0, 0.0)


def observe(pose: np.ndarray, world: np.ndarray, view: Viewpoint = LEVEL) -> np.ndarray:
    return project(RIG, view.to_camera(pose, world)[0])[0]


def test_a_far_landmark_corrects_the_heading_as_a_kalman_gain_by_hand():
    # position known; heading prior 0 +- 1/500 rad (prior information 500^2 = 250 000 rad^-2).
    # One landmark 1 km dead ahead: u and u_r each move fx = 500 px per rad of heading, noise 1 px,
    # so the observation carries 2 * 500^2 = 500 000 rad^-2 of information about the heading.
    # Posterior: (0 * 250 000 + delta * 500 000) / 750 000 = 2/3 delta, sigma 1 / sqrt(750 000).
    delta = 0.001
    landmark = np.array([[0.15 + 1000.0, 0.0, 1.08]])
    prior = np.diag([1e-12, 1e-12, (1.0 / 500.0) ** 2])
    update = refine_pose(np.zeros(3), prior, landmark, np.zeros((1, 3, 3)), observe(np.array([0, 0, delta]), landmark),
                         LEVEL, RIG, sigma_px=1.0, huber=100.0)
    assert update.mean[2] == pytest.approx(2.0 / 3.0 * delta, rel=1e-3)
    assert math.sqrt(update.covariance[2, 2]) == pytest.approx(1.0 / math.sqrt(750_000.0), rel=1e-3)
    assert update.mean[:2] == pytest.approx([0.0, 0.0], abs=1e-9)


def test_a_pose_is_found_again_from_landmarks_all_around_despite_a_wrong_one():
    rng = np.random.default_rng(4)
    truth = np.array([0.8, -0.3, math.radians(20.0)])
    view = Viewpoint.of(HEAD, 0.4, -0.3)
    camera_points = np.column_stack((rng.uniform(1.0, 5.0, 40), rng.uniform(-1.5, 1.5, 40), rng.uniform(-1, 1, 40)))
    world = view.to_world(truth, camera_points)[0]
    observed = observe(truth, world, view) + rng.normal(0.0, 0.5, (40, 3))
    observed[0] += (40.0, -25.0, 40.0)  # a wrong association
    prior_mean = truth + np.array([0.1, 0.05, math.radians(2.0)])
    update = refine_pose(prior_mean, np.diag([0.2**2, 0.2**2, math.radians(5.0) ** 2]), world,
                         np.zeros((40, 3, 3)), observed, view, RIG, sigma_px=0.5)
    assert update.mean[:2] == pytest.approx(truth[:2], abs=0.01)
    assert update.mean[2] == pytest.approx(truth[2], abs=math.radians(0.1))
    assert update.chi2[0] > 100.0 and np.median(update.chi2[1:]) < 5.0
