"""Triangulation and projection of a point seen by a rectified stereo pair, against values worked by hand."""

from __future__ import annotations

import numpy as np
import pytest

from perception.camera import PinholeCamera, StereoRig
from perception.stereo_geometry import project, triangulate

# fx = fy = 500 px, centre (320, 240), baseline 0.1 m: f B = 50 px m
RIG = StereoRig(PinholeCamera(640, 480, 500.0, 500.0, 320.0, 240.0), PinholeCamera(640, 480, 500.0, 500.0, 320.0,
                                                                                    240.0), 0.1)


def test_a_point_two_metres_ahead_is_triangulated_by_hand():
    # u = 370, v = 215, u_r = 345: disparity 25 px, depth f B / d = 50 / 25 = 2 m;
    # y = -(370 - 320) 2 / 500 = -0.2 m (to the right), z = -(215 - 240) 2 / 500 = 0.1 m (up)
    points, covariance = triangulate(RIG, np.array([[370.0, 215.0, 345.0]]), sigma_px=0.5)
    assert points[0] == pytest.approx([2.0, -0.2, 0.1])
    # depth noise Z^2 / (f B) * sigma_d with sigma_d = sqrt(2) * 0.5 px: 4 / 50 * 0.7071 = 0.05657 m
    assert np.sqrt(covariance[0, 0, 0]) == pytest.approx(0.05657, abs=1e-5)
    # across the ray at the centre row: z = -(v - cy) Z / fy, with v alone: 2 / 500 * 0.5 = 0.002 m
    # plus the depth's share: (v - cy) / fy * dZ = 25 / 500 * 0.05657 = 0.00283 m -> sqrt(0.002^2 + 0.00283^2)
    assert np.sqrt(covariance[0, 2, 2]) == pytest.approx(np.hypot(0.002, 0.05 * 0.05657), abs=1e-6)


def test_projection_is_the_inverse_of_triangulation_by_hand():
    observed, jac = project(RIG, np.array([[2.0, -0.2, 0.1]]))
    assert observed[0] == pytest.approx([370.0, 215.0, 345.0])
    # du/dy = -fx / x = -250 px/m; du/dx = fx y / x^2 = 500 * -0.2 / 4 = -25 px/m
    assert jac[0, 0, 1] == pytest.approx(-250.0) and jac[0, 0, 0] == pytest.approx(-25.0)


def test_projection_jacobian_matches_finite_differences():
    rng = np.random.default_rng(3)
    points = np.column_stack((rng.uniform(1, 6, 20), rng.uniform(-1, 1, 20), rng.uniform(-1, 1, 20)))
    _, jac = project(RIG, points)
    eps = 1e-6
    for axis in range(3):
        shifted = points.copy()
        shifted[:, axis] += eps
        numeric = (project(RIG, shifted)[0] - project(RIG, points)[0]) / eps
        assert np.allclose(jac[:, :, axis], numeric, atol=1e-3)
    back, _ = triangulate(RIG, project(RIG, points)[0])
    assert np.allclose(back, points)


def test_a_point_without_disparity_is_refused():
    with pytest.raises(ValueError, match="positive disparity"):
        triangulate(RIG, np.array([[300.0, 200.0, 300.0]]))
