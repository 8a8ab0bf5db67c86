"""Stereo depth on synthetic rectified pairs: known disparity, repeated texture."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from perception.camera import PinholeCamera, StereoRig
from perception.features import detect
from perception.stereo import dense_depth, dense_points, points_from_disparity, sparse_stereo
from perception.synthetic import textured_panorama

CAM = PinholeCamera(640, 480, 500.0, 500.0, 319.5, 239.5)
RIG = StereoRig(CAM, CAM, baseline=0.1)


def shifted(image: np.ndarray, disparity: float) -> np.ndarray:
    """The right view of a fronto-parallel plane: everything moves ``disparity`` px to the left."""
    M = np.array([[1.0, 0.0, -disparity], [0.0, 1.0, 0.0]])
    size = (image.shape[1], image.shape[0])
    return cv2.warpAffine(image, M, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)


@pytest.fixture(scope="module")
def wall() -> np.ndarray:
    return cv2.resize(textured_panorama(3, width=640, height=240, shapes=500), (640, 480))


def test_points_from_disparity_geometry():
    found = points_from_disparity(RIG, np.array([[319.5, 239.5], [0.0, 239.5]]), np.array([25.0, 50.0]))
    assert found.depth == pytest.approx([2.0, 1.0])
    assert np.allclose(found.points[0], [2.0, 0.0, 0.0])
    assert found.points[1, 0] == pytest.approx(1.0) and found.points[1, 1] == pytest.approx(319.5 / 500.0)


def test_sparse_stereo_recovers_a_wall_at_two_metres(wall):
    d = 500.0 * 0.1 / 2.0  # 25 px
    found = sparse_stereo(wall, shifted(wall, d), RIG)
    assert len(found) > 150
    assert np.median(found.depth) == pytest.approx(2.0, rel=0.01)
    assert (np.abs(found.disparity - d) < 1.0).mean() > 0.97
    assert np.allclose(found.points[:, 0], found.depth)


def test_sparse_stereo_rejects_repeated_texture():
    rng = np.random.default_rng(4)
    image = np.full((480, 640), 127, np.uint8)
    for y in range(12, 480, 32):  # a wallpaper of identical squares: every corner has look-alikes
        for x in range(12, 640, 24):
            cv2.rectangle(image, (x, y), (x + 10, y + 10), 230, -1)
    for _ in range(40):  # a few unique marks among the stripes
        cx, cy = int(rng.integers(40, 600)), int(rng.integers(40, 440))
        cv2.circle(image, (cx, cy), int(rng.integers(4, 9)), int(rng.integers(0, 256)), -1)
    image = cv2.GaussianBlur(image, (3, 3), 0)
    d = 10.0
    found = sparse_stereo(image, shifted(image, d), RIG, max_disparity=60)
    assert len(found) >= 10
    assert np.abs(found.disparity - d).max() < 1.0  # no depth from a wrong stripe
    # the texture does fool a plain nearest-neighbour matcher: the test has teeth
    left, right = detect(image, levels=1), detect(shifted(image, d), levels=1)
    naive = cv2.BFMatcher(cv2.NORM_HAMMING).match(left.descriptors, right.descriptors)
    wrong = [m for m in naive if abs(left.keypoints_uv[m.queryIdx, 0] - right.keypoints_uv[m.trainIdx, 0] - d) > 5]
    assert len(wrong) > 20


def test_dense_depth_on_a_wall(wall):
    d = 20.0
    depth = dense_depth(wall, shifted(wall, d), RIG, num_disparities=48)
    inner = depth[40:-40, 80:-40]
    valid = np.isfinite(inner)
    assert valid.mean() > 0.8
    assert np.median(inner[valid]) == pytest.approx(500.0 * 0.1 / d, rel=0.02)
    points = dense_points(depth, RIG, step=8)
    assert points.shape[1] == 3 and np.all(points[:, 0] > 0)
