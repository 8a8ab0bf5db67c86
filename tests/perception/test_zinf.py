"""Z-infinity on synthetic landmark scenes with known motion."""

from __future__ import annotations

import numpy as np
import pytest

from perception.synthetic import angle_deg, make_scene, rotation_error_deg
from perception.zinf import ZinfStatus, estimate_motion, largest_azimuth_gap


def test_rotation_and_translation_recovered_exactly_without_noise():
    scene = make_scene(1, yaw_deg=35.0, position=(0.6, -0.3, 0.0))
    result = estimate_motion(scene.ref, scene.cur)
    assert result.ok
    assert rotation_error_deg(result.rotation, scene.rotation) < 0.05
    assert angle_deg(result.translation, scene.position) < 1.0
    assert result.far[scene.far].mean() > 0.95  # the far landmarks are found as far
    assert result.inliers.mean() > 0.95
    assert 0.0 < result.confidence <= 1.0
    assert result.yaw == pytest.approx(np.radians(-35.0), abs=1e-3)


def test_home_direction_points_back_in_the_current_frame():
    scene = make_scene(2, yaw_deg=90.0, position=(1.0, 0.0, 0.0))
    result = estimate_motion(scene.ref, scene.cur)
    # the robot moved 1 m forward then turned left 90 deg: the start is now on its left (+y)
    assert angle_deg(result.home_direction, np.array([0.0, 1.0, 0.0])) < 1.0


def test_pure_rotation_gives_rotation_and_no_translation():
    scene = make_scene(3, yaw_deg=-60.0, tilt_deg=4.0, position=(0.0, 0.0, 0.0))
    result = estimate_motion(scene.ref, scene.cur)
    assert result.status is ZinfStatus.NO_TRANSLATION
    assert result.rotation_ok and not result.ok
    assert rotation_error_deg(result.rotation, scene.rotation) < 0.01
    assert result.far.all()
    assert np.allclose(result.translation, 0.0)
    assert result.confidence == 0.0


def test_pure_translation_gives_identity_and_direction():
    scene = make_scene(4, yaw_deg=0.0, position=(-0.4, 0.4, 0.0))
    result = estimate_motion(scene.ref, scene.cur)
    assert result.ok
    assert rotation_error_deg(result.rotation, np.eye(3)) < 0.05
    assert angle_deg(result.translation, scene.position) < 1.0


@pytest.mark.parametrize("seed", range(5))
def test_sign_of_translation_follows_eq6(seed):
    rng = np.random.default_rng(100 + seed)
    heading = rng.uniform(-np.pi, np.pi)
    position = (0.5 * np.cos(heading), 0.5 * np.sin(heading), 0.0)
    scene = make_scene(seed, yaw_deg=float(rng.uniform(-90, 90)), position=position)
    result = estimate_motion(scene.ref, scene.cur, rng=seed)
    assert result.ok
    assert angle_deg(result.translation, scene.position) < 1.0  # not 180


def test_no_far_landmarks_reports_no_rotation_instead_of_a_guess():
    scene = make_scene(5, n_far=0, n_near=300, yaw_deg=25.0, position=(0.8, 0.3, 0.0))
    result = estimate_motion(scene.ref, scene.cur)
    assert result.status is ZinfStatus.NO_ROTATION
    assert not result.rotation_ok
    assert not result.far.any() and not result.inliers.any()
    assert np.allclose(result.rotation, np.eye(3)) and np.allclose(result.translation, 0.0)


def test_landmarks_on_one_side_only_are_rejected_by_the_gap_rule():
    scene = make_scene(6, azimuth_range_deg=(-70.0, 70.0), yaw_deg=10.0)
    assert largest_azimuth_gap(scene.ref[scene.far]) > np.pi
    result = estimate_motion(scene.ref, scene.cur)
    assert result.status is ZinfStatus.NO_ROTATION
    # the same scene with the rule relaxed does find the rotation: the rule is what rejected it
    relaxed = estimate_motion(scene.ref, scene.cur, max_gap=2 * np.pi)
    assert relaxed.rotation_ok
    assert rotation_error_deg(relaxed.rotation, scene.rotation) < 0.1


def test_too_few_correspondences():
    scene = make_scene(7, n_far=3, n_near=3)
    result = estimate_motion(scene.ref, scene.cur)
    assert result.status is ZinfStatus.NOT_ENOUGH_LANDMARKS


@pytest.mark.parametrize("seed", range(3))
def test_half_outliers_are_rejected(seed):
    scene = make_scene(seed, outlier_fraction=0.5, yaw_deg=45.0, position=(0.3, 0.5, 0.0))
    result = estimate_motion(scene.ref, scene.cur, rng=seed)
    assert result.ok
    assert rotation_error_deg(result.rotation, scene.rotation) < 0.1
    assert angle_deg(result.translation, scene.position) < 2.0
    # a random junk bearing lands on its epipolar plane by chance now and then; only a few may
    assert (result.inliers & scene.outlier).sum() <= 0.05 * scene.outlier.sum()
    assert result.inliers[~scene.outlier].mean() > 0.9


@pytest.mark.parametrize("seed", range(3))
def test_noise_with_outliers_and_tilt(seed):
    scene = make_scene(
        seed, noise_deg=0.2, outlier_fraction=0.5, yaw_deg=-120.0, tilt_deg=3.0, position=(0.5, 0.0, 0.05)
    )
    result = estimate_motion(scene.ref, scene.cur, rng=seed)
    assert result.ok
    assert rotation_error_deg(result.rotation, scene.rotation) < 0.2
    assert angle_deg(result.translation, scene.position) < 3.0
    assert (result.inliers & scene.outlier).sum() <= 0.05 * scene.outlier.sum()


def test_weights_silence_downweighted_landmarks():
    scene = make_scene(8, outlier_fraction=0.3)
    weights = np.where(scene.outlier, 0.0, 1.0)
    result = estimate_motion(scene.ref, scene.cur, weights)
    assert result.ok and angle_deg(result.translation, scene.position) < 1.0
    with pytest.raises(ValueError):
        estimate_motion(scene.ref, scene.cur, -weights)


def test_deterministic_for_a_seed():
    scene = make_scene(9, noise_deg=0.3, outlier_fraction=0.4)
    a = estimate_motion(scene.ref, scene.cur, rng=42)
    b = estimate_motion(scene.ref, scene.cur, rng=42)
    assert np.array_equal(a.rotation, b.rotation) and np.array_equal(a.translation, b.translation)
    assert np.array_equal(a.inliers, b.inliers)


def test_azimuth_gap():
    az = np.radians([0.0, 90.0, 180.0])
    b = np.column_stack((np.cos(az), np.sin(az), np.zeros(3)))
    assert largest_azimuth_gap(b) == pytest.approx(np.pi)
    assert largest_azimuth_gap(b[:1]) == pytest.approx(2 * np.pi)
