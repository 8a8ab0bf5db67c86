"""The target pose graph: hand-computed cases of the weighted least squares."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.pose_graph import refine_targets
from maps.roadmap import EdgeMotion, Roadmap
from perception.geometry import Pose2D


def along_x(distance: float, sigma_distance: float, sigma_angle: float = 0.01) -> EdgeMotion:
    return EdgeMotion(0.0, distance, 0.0, np.diag([sigma_angle ** 2, sigma_distance ** 2, sigma_angle ** 2]))


def test_two_targets_on_a_line_are_placed_by_weighted_least_squares():
    # along x the (x, y, theta) covariances decouple: x is a 1-D least squares of the three distances
    va, vb, ve = 0.02 ** 2, 0.2 ** 2, 0.03 ** 2
    roadmap = (Roadmap().with_target("a", Pose2D(2.0, 0.0), "a.png").with_target("b", Pose2D(4.0, 0.0), "b.png")
               .with_edge("a", "b", along_x(2.2, math.sqrt(ve))))
    priors = {"a": along_x(2.0, math.sqrt(va)), "b": along_x(4.0, math.sqrt(vb))}
    refined = refine_targets(roadmap, priors)
    normal = np.array([[1 / va + 1 / ve, -1 / ve], [-1 / ve, 1 / vb + 1 / ve]])
    xa, xb = np.linalg.solve(normal, [2.0 / va - 2.2 / ve, 4.0 / vb + 2.2 / ve])
    a, b = refined.target("a").pose, refined.target("b").pose
    assert (a.x, b.x) == pytest.approx((xa, xb), abs=1e-6)
    assert b.x == pytest.approx(4.2, abs=0.01)  # the precise edge from the precise a wins over b's own trip
    assert (a.y, a.theta, b.y, b.theta) == pytest.approx((0.0, 0.0, 0.0, 0.0), abs=1e-9)
    assert refined.target("b").image == "b.png" and refined.edges == roadmap.edges


def test_a_heading_error_of_a_far_target_is_pulled_in_by_a_near_one():
    truth_a, truth_b = Pose2D(2.0, 1.0, 0.3), Pose2D(4.0, 3.0, -0.5)
    edge = EdgeMotion.from_relative_pose(truth_b.relative_to(truth_a), np.diag([1e-4, 1e-4, 1e-5]))
    measured_b = Pose2D(4.2, 2.8, -0.45)  # its own trip from the reference went wrong by a few degrees
    roadmap = Roadmap().with_target("a", truth_a).with_target("b", measured_b).with_edge("a", "b", edge)
    far = EdgeMotion.from_relative_pose(measured_b, np.diag([0.2 ** 2, 0.2 ** 2, math.radians(5) ** 2]))
    near = EdgeMotion.from_relative_pose(truth_a, np.diag([1e-4, 1e-4, 1e-5]))
    refined = refine_targets(roadmap, {"a": near, "b": far})
    assert refined.target("b").pose.distance_to(truth_b) < 0.02
    assert refined.target("a").pose.distance_to(truth_a) < 0.005


def test_targets_without_a_measurement_stay_and_nothing_to_fit_is_no_change():
    roadmap = Roadmap().with_target("a", Pose2D(1.0, 0.0)).with_target("b", Pose2D(3.0, 0.0))
    assert refine_targets(roadmap, {}) is roadmap
    roadmap = roadmap.with_edge("a", "b", along_x(2.5, 0.01))
    refined = refine_targets(roadmap, {"b": along_x(3.0, 0.01)})
    assert refined.target("a").pose == Pose2D(1.0, 0.0)
    assert refined.target("b").pose.x == pytest.approx(3.25, abs=1e-6)  # halfway: equal weights
