"""The image side of the roadmap: upright SIFT, matching by planar motion, camera and robot poses."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from behaviours.roadmap.vision import (
    MIN_INLIERS,
    Comparison,
    camera_pose,
    compare,
    compare_frame,
    describe,
    grey,
    mean_angle,
    optical_step,
    pinhole_of,
    robot_pose,
)
from perception.camera import PinholeCamera
from perception.geometry import Pose2D
from perception.planar import PlanarResult, PlanarStatus
from tests.behaviours.fake_world import FakeWorld

TARGET = Pose2D(4.0, 3.0, 0.0)  # lab world frame: where the target image is taken
OFFSET = (0.15, 0.0)  # the front camera on the robot


@pytest.fixture(scope="module")
def lab():
    """The lab's front camera images at the target and from 0.5 m behind, 0.3 m left, turned 11.5 deg left."""
    world = FakeWorld()
    here = TARGET.compose(Pose2D(-0.5, 0.3, 0.2))
    return world.sim.snapshot(TARGET, "front", pan=0.0, tilt=0.0), world.sim.snapshot(here, "front", pan=0.0,
                                                                                      tilt=0.0), here


def test_grey_converts_colour_and_keeps_grey():
    colour = np.zeros((4, 6, 3), np.uint8)
    colour[..., 2] = 255  # red in BGR
    assert grey(colour).shape == (4, 6) and grey(colour)[0, 0] == cv2.cvtColor(colour, cv2.COLOR_BGR2GRAY)[0, 0]
    flat = np.zeros((4, 6), np.uint8)
    assert grey(flat) is flat


def test_describe_gives_at_most_n_sift_features(lab):
    target, _, _ = lab
    features = describe(target.image, n_features=200)
    assert features.kind == "sift" and 50 < len(features) <= 200


def test_an_image_matches_its_target_with_the_turn_and_the_direction_to_it(lab):
    target, image, here = lab
    found = compare_frame(image, describe(target.image), target.camera)
    assert found.matched() and found.inliers >= MIN_INLIERS and found.matches >= found.inliers
    assert math.degrees(found.planar.theta) == pytest.approx(math.degrees(TARGET.theta - here.theta), abs=1.0)
    towards = camera_pose(TARGET, OFFSET).relative_to(camera_pose(here, OFFSET))  # the target camera, from here
    assert math.degrees(found.planar.bearing) == pytest.approx(math.degrees(math.atan2(towards.y, towards.x)),
                                                               abs=3.0)
    assert not found.at_target


def test_an_image_compared_with_itself_is_at_the_target(lab):
    target, _, _ = lab
    found = compare_frame(target, describe(target.image), None)  # a file's target: the live camera's model
    assert found.matched() and found.at_target and found.planar.theta == 0.0


def test_an_unrelated_image_does_not_match(lab):
    target, _, _ = lab
    noise = np.random.default_rng(5).integers(0, 255, (480, 640)).astype(np.uint8)
    assert not compare(describe(noise), target.camera, describe(target.image)).matched()


def test_a_match_needs_the_turn_and_enough_inliers():
    def comparison(inliers: int, status: PlanarStatus) -> Comparison:
        return Comparison(100, PlanarResult(0.1, np.zeros(2), np.arange(100) < inliers, status))

    assert comparison(25, PlanarStatus.OK).matched() and not comparison(24, PlanarStatus.OK).matched()
    assert comparison(10, PlanarStatus.OK).matched(min_inliers=10)
    assert comparison(40, PlanarStatus.NO_TRANSLATION).matched()  # the turn is known: a match at the target
    assert not comparison(40, PlanarStatus.NO_CONSENSUS).matched()


def test_homing_uses_a_stereo_rigs_left_camera():
    left = PinholeCamera(64, 48, 50.0, 50.0, 31.5, 23.5)

    class Rig:
        def __init__(self) -> None:
            self.left = left

    assert pinhole_of(Rig()) is left and pinhole_of(left) is left


def test_camera_and_robot_poses_by_hand():
    robot = Pose2D(1.0, 2.0, math.pi / 2)
    camera = camera_pose(robot, (0.15, 0.05))  # 0.15 m ahead (+y here), 0.05 m left (-x here)
    assert (camera.x, camera.y, camera.theta) == pytest.approx((0.95, 2.15, math.pi / 2))
    back = robot_pose(camera, (0.15, 0.05))
    assert (back.x, back.y, back.theta) == pytest.approx((1.0, 2.0, math.pi / 2))


def test_optical_step_is_x_right_z_forward_and_the_turn():
    step, turn = optical_step(Pose2D(1.0, 1.0, math.pi / 2), Pose2D(0.9, 1.2, math.pi / 2 + 0.3))
    # in the first camera's frame the second is 0.2 m forward and 0.1 m left: x right = -0.1, z = 0.2
    assert step == pytest.approx([-0.1, 0.2]) and turn == pytest.approx(0.3)


@pytest.mark.parametrize(("a", "b", "mean"), [(0.2, 0.4, 0.3), (3.0, -3.0, math.pi), (-0.1, 0.1, 0.0)])
def test_mean_angle_is_circular(a, b, mean):
    assert math.remainder(mean_angle(a, b) - mean, 2 * math.pi) == pytest.approx(0.0, abs=1e-12)
