"""The left camera on the pan-tilt head at a base pose: points to and from the world, by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration.head import StereoHead
from maps.slam.viewpoint import Viewpoint

HEAD = StereoHead(ptu=(0.1, 0.0, 1.0), camera=(0.05, 0.0, 0.08))


def test_a_point_straight_ahead_of_the_turned_head_by_hand():
    view = Viewpoint.of(HEAD, pan=math.pi / 2, tilt=0.0)
    # eye on the base: (0.1, 0, 1.0) + Rz(90 deg) (0.05, 0, 0.08) = (0.1, 0.05, 1.08)
    assert view.eye == pytest.approx([0.1, 0.05, 1.08])
    # base at (1, 2) facing +y: eye in the world (1 - 0.05, 2 + 0.1, 1.08), looking along -x
    pose = np.array([1.0, 2.0, math.pi / 2])
    p, _, _ = view.to_camera(pose, np.array([[0.95 - 3.0, 2.1, 1.08]]))
    assert p[0] == pytest.approx([3.0, 0.0, 0.0], abs=1e-12)
    world, _, _ = view.to_world(pose, np.array([[3.0, 0.0, 0.0]]))
    assert world[0] == pytest.approx([-2.05, 2.1, 1.08])


def test_tilt_down_sees_the_floor_ahead():
    view = Viewpoint.of(HEAD, pan=0.0, tilt=-math.pi / 4)
    eye = view.eye
    # looking 45 degrees down, the optical axis meets the floor eye_z ahead of the eye, sqrt(2) eye_z along it
    world, _, _ = view.to_world(np.zeros(3), np.array([[math.sqrt(2.0) * eye[2], 0.0, 0.0]]))
    assert world[0] == pytest.approx([eye[0] + eye[2], 0.0, 0.0], abs=1e-12)


def test_jacobians_match_finite_differences():
    rng = np.random.default_rng(1)
    view = Viewpoint.of(HEAD, pan=0.7, tilt=-0.3)
    pose = np.array([0.4, -1.2, 2.1])
    world = rng.uniform(-5, 5, (10, 3))
    p, d_pose, d_point = view.to_camera(pose, world)
    camera = rng.uniform(-3, 3, (10, 3))
    w, w_pose, w_camera = view.to_world(pose, camera)
    eps = 1e-7
    for k in range(3):
        step = np.zeros(3)
        step[k] = eps
        assert np.allclose(d_pose[:, :, k], (view.to_camera(pose + step, world)[0] - p) / eps, atol=1e-5)
        assert np.allclose(d_point[:, :, k], (view.to_camera(pose, world + step)[0] - p) / eps, atol=1e-5)
        assert np.allclose(w_pose[:, :, k], (view.to_world(pose + step, camera)[0] - w) / eps, atol=1e-5)
        assert np.allclose(w_camera[:, :, k], (view.to_world(pose, camera + step)[0] - w) / eps, atol=1e-5)
    assert np.allclose(view.to_camera(pose, w)[0], camera)
