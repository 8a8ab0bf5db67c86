"""Where the stereo pair looks from: the head's view, its fields of view, the floor footprint."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration.head import StereoHead, footprint
from perception.camera import PinholeCamera
from perception.geometry import Pose2D
from tests.maps.exploration_maps import SIMPLE


def test_head_view_places_the_left_camera_like_the_simulator():
    head = StereoHead(ptu=(0.1, 0.0, 1.0), camera=(0.05, 0.0, 0.08))
    view = head.view(Pose2D(1.0, 2.0, math.pi / 2), pan=0.0, tilt=0.0)
    assert view.eye == pytest.approx([1.0, 2.15, 1.08])
    assert view.rotation @ np.array([1.0, 0.0, 0.0]) == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)
    panned = head.view(Pose2D(1.0, 2.0, math.pi / 2), pan=math.pi / 2, tilt=0.0)
    assert panned.eye == pytest.approx([0.95, 2.1, 1.08])
    lifted = head.view(Pose2D(), pan=0.0, tilt=math.radians(30))
    # camera offset (0.05, 0, 0.08) lifted by 30 degrees about the tilt axis
    assert lifted.eye == pytest.approx(
        [0.1 + 0.05 * math.cos(math.pi / 6) - 0.04, 0.0, 1.0 + 0.025 + 0.08 * math.cos(math.pi / 6)]
    )
    assert lifted.rotation @ np.array([1.0, 0.0, 0.0]) == pytest.approx([math.cos(math.pi / 6), 0.0, 0.5])


def test_head_fields_of_view_from_the_rig_camera():
    cam = PinholeCamera(640, 480, 320.0, 320.0, 319.5, 239.5)
    head = StereoHead.for_rig(type("Rig", (), {"left": cam})(), (0.1, 0.0, 1.0), (0.05, 0.0, 0.08))
    assert head.horizontal_fov == pytest.approx(math.pi / 2)  # 640 px across at f = 320
    assert head.vertical_fov == pytest.approx(2 * math.atan(240 / 320))


def test_footprint_near_and_far_edges():
    direction, near, far = footprint(SIMPLE.view(Pose2D(), 0.0, 0.0))
    assert direction == pytest.approx([1.0, 0.0]) and near == pytest.approx(1.0) and far == math.inf
    _, near, far = footprint(SIMPLE.view(Pose2D(), 0.0, math.radians(-60)))  # top row 15 deg down
    assert near == pytest.approx(0.0, abs=1e-9) and far == pytest.approx(1.0 / math.tan(math.radians(15)))
    _, near, _ = footprint(SIMPLE.view(Pose2D(), 0.0, math.radians(50)))  # bottom row above the horizon
    assert near == math.inf
