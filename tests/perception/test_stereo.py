"""Stereo depth on synthetic rectified pairs: known disparity, repeated texture."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from perception.camera import PinholeCamera, StereoRig
from perception.features import detect
from perception.stereo import (
    dense_depth,
    dense_points,
    dense_samples,
    drop_jumps,
    halved,
    points_from_disparity,
    pyramid_points,
    sparse_stereo,
)
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


def test_dense_samples_keep_each_points_pixel():
    depth = np.full((48, 64), np.nan, dtype=np.float32)
    depth[8, 16] = 2.0  # one valid sample
    depth[24, 0] = 4.0
    points, uv = dense_samples(depth, RIG, step=8)
    assert uv.tolist() == [[16.0, 8.0], [0.0, 24.0]]
    # by hand: the pixel (16, 8) at depth 2 lies (319.5 - 16) / 500 * 2 to the left, (239.5 - 8) / 500 * 2 up
    assert points[0] == pytest.approx([2.0, 303.5 / 250.0, 231.5 / 250.0])
    assert np.array_equal(dense_points(depth, RIG, step=8), points)


def test_pixels_beside_a_depth_jump_are_dropped():
    depth = np.full((20, 30), 2.0, dtype=np.float32)
    depth[:, 15:] = 5.0  # a jamb at 2 m in front of a wall at 5 m
    depth[0, 0] = np.nan
    out = drop_jumps(depth, 0.15, radius=3)
    dropped = np.flatnonzero(np.isnan(out[10]))
    assert dropped.tolist() == list(range(12, 18))  # 3 px either side of the edge
    assert np.isnan(out[0, 0]) and out[10, 5] == 2.0 and out[10, 25] == 5.0
    gentle = np.tile(np.linspace(2.0, 2.2, 30, dtype=np.float32), (20, 1))  # a floor: 0.7 % a pixel
    assert np.isfinite(drop_jumps(gentle, 0.15)).all()
    assert drop_jumps(depth, 0.0) is depth


def test_a_halved_rig_sees_the_same_bearings_at_the_halved_pixels():
    half = halved(RIG)
    assert (half.left.width, half.left.height, half.left.fx, half.baseline) == (320, 240, 250.0, 0.1)
    uv = np.array([[100.0, 50.0], [619.0, 401.0]])
    small = (uv + 0.5) / 2.0 - 0.5  # where cv2.pyrDown puts those pixel centres
    assert half.left.pixel_to_bearing(small) == pytest.approx(RIG.left.pixel_to_bearing(uv))


def test_matching_halved_images_gives_the_wall_at_full_image_pixels(wall):
    d = 20.0
    points, uv = pyramid_points(wall, shifted(wall, d), RIG, levels=1, num_disparities=48, max_jump=0.15, step=8)
    assert len(points) > 1000 and np.median(points[:, 0]) == pytest.approx(500.0 * 0.1 / d, rel=0.03)
    # every 4th pixel of the halved image, (u + 0.5) * 2 - 0.5 in the full one: 0.5, 8.5, 16.5, ...
    assert np.all((uv - 0.5) % 8 == 0) and np.all(uv.max(axis=0) <= [639.0, 479.0])
