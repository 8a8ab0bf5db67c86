"""Matching: ratio test, mutual check, a frame against a stored landmark set."""

from __future__ import annotations

import numpy as np
import pytest

from perception.camera import PanoramaCamera
from perception.features import detect
from perception.matching import DEFAULT_RATIO, Landmarks, match_descriptors, match_features, match_landmarks
from perception.synthetic import textured_panorama
from perception.zinf import ZinfStatus, estimate_motion

PANO = PanoramaCamera()


@pytest.fixture(scope="module")
def views():
    image = textured_panorama(1)
    turned = np.roll(image, -40, axis=1)  # content 40 px left = azimuth +20 deg: the robot turned right
    return detect(image, camera=PANO), detect(turned, camera=PANO)


def test_defaults_follow_the_paper_for_sift():
    assert DEFAULT_RATIO["sift"] == 0.65 and DEFAULT_RATIO["orb"] == 0.75


def test_ratio_test_and_mutual_check_on_a_toy_set():
    train = np.array([[0.0, 0.0], [10.0, 0.0], [10.5, 0.0]], dtype=np.float32)
    query = np.array([[0.1, 0.0], [10.2, 0.0], [0.3, 0.0]], dtype=np.float32)
    found = match_descriptors(query, train, "sift", ratio=0.65, mutual=False)
    # query 1 is ambiguous (10.0 vs 10.5); queries 0 and 2 both pick train 0
    assert list(zip(found.query, found.train, strict=True)) == [(0, 0), (2, 0)]
    mutual = match_descriptors(query, train, "sift", ratio=0.65, mutual=True)
    assert list(zip(mutual.query, mutual.train, strict=True)) == [(0, 0)]  # train 0's nearest is query 0
    assert mutual.distance[0] == pytest.approx(0.1)
    with pytest.raises(ValueError):
        match_descriptors(query, train, "sift", ratio=1.5)
    assert len(match_descriptors(query[:0], train, "sift")) == 0


def test_matches_between_turned_panoramas_are_one_to_one_and_correct(views):
    a, b = views
    found = match_features(a, b)
    assert len(np.unique(found.train)) == len(found) == len(np.unique(found.query))
    du = (b.keypoints_uv[found.train, 0] - a.keypoints_uv[found.query, 0] + 40 + 360) % 720 - 360
    assert len(found) > 200 and (np.abs(du) < 4.0).mean() > 0.95
    strict = match_features(a, b, ratio=0.5)
    assert len(strict) < len(found)
    loose = match_features(a, b, mutual=False)
    assert len(loose) >= len(found)


def test_frame_against_landmarks_feeds_z_infinity(views):
    a, b = views
    landmarks = Landmarks(a.descriptors, PANO.pixel_to_bearing(a.keypoints_uv), a.kind)
    matched = match_landmarks(b, PANO.pixel_to_bearing(b.keypoints_uv), landmarks)
    assert len(matched) > 200 and matched.ref.shape == matched.cur.shape == (len(matched), 3)
    assert np.allclose(matched.ref, landmarks.bearings[matched.landmark])
    motion = estimate_motion(matched.ref, matched.cur)
    assert motion.status is ZinfStatus.NO_TRANSLATION  # a pure turn
    assert np.degrees(motion.yaw) == pytest.approx(20.0, abs=0.3)  # landmarks moved 20 deg to the left


def test_kinds_must_agree(views):
    a, _ = views
    with pytest.raises(ValueError):
        match_landmarks(a, np.zeros((len(a), 3)), Landmarks(np.zeros((1, 128), np.float32), np.zeros((1, 3)), "sift"))
