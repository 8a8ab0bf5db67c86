"""The ports the exploration node types share: declared once, read alike, checked with a clear error."""

from __future__ import annotations

import pytest

from behaviours.exploration.follow_path import FollowPath
from behaviours.exploration.gaze import WatchInterestEdges
from behaviours.exploration.localise import LocalisePose
from behaviours.exploration.look_around import LookAround
from behaviours.exploration.map_stereo import MapStereo
from behaviours.exploration.ports import (
    CAMERA_POSITION,
    FRAMES,
    MAP,
    POSE,
    PTU_POSITION,
    ROBOT_RADIUS,
    disc_radius,
    xyz,
)
from behaviours.exploration.select_goal import SelectGoalPoint
from behaviours.footprint import FOOTPRINT
from behaviours.registry import Registry
from behaviours.testing import BehaviourHarness
from drivers.pioneer_body import BODIES


def test_xyz_reads_three_numbers_and_says_which_list_is_wrong():
    assert xyz([0.1, 0, 1], "ptu_position") == (0.1, 0.0, 1.0)
    with pytest.raises(ValueError, match=r"camera_position is \[x, y, z\], got \[0.05, 0.0\]"):
        xyz([0.05, 0.0], "camera_position")


def test_the_robots_disc_is_the_one_round_its_own_footprint_unless_a_radius_is_given():
    node = FollowPath()
    harness = BehaviourHarness(node, blackboard={})
    assert disc_radius(node) == 0.26  # run without the runner (no footprint published): a P3-DX's disc
    harness.write("/robot/footprint", BODIES["p3dx"].footprint)
    assert disc_radius(node) == pytest.approx(0.36845, abs=1e-5)  # the rear corners: hypot(0.301, 0.425 / 2)
    given = FollowPath(robot_radius=0.3)
    BehaviourHarness(given, blackboard={"/robot/footprint": BODIES["p3dx"].footprint})
    assert disc_radius(given) == 0.3


def test_a_shared_port_is_the_same_declaration_in_every_node_type():
    uses = [(ROBOT_RADIUS, (MapStereo, SelectGoalPoint, FollowPath, WatchInterestEdges)),
            (FOOTPRINT, (MapStereo, SelectGoalPoint, FollowPath, WatchInterestEdges)),
            (MAP, (SelectGoalPoint, FollowPath, WatchInterestEdges)),
            (POSE, (MapStereo, SelectGoalPoint, FollowPath, WatchInterestEdges)),
            (FRAMES, (MapStereo, LocalisePose)), (PTU_POSITION, (MapStereo, WatchInterestEdges, LookAround)),
            (CAMERA_POSITION, (MapStereo, WatchInterestEdges, LookAround))]
    for port, node_types in uses:
        for node_type in node_types:
            assert any(p is port for p in node_type.PORTS), f"{node_type.__name__}.{port.name}"


def test_the_exploration_node_types_are_builtins_from_the_sub_package():
    modules = {t.name: t.module for t in Registry.builtin().all_types()
               if t.module.startswith("behaviours.exploration")}
    assert modules == {
        "LocalisePose": "behaviours.exploration.localise", "MapStereo": "behaviours.exploration.map_stereo",
        "SelectGoalPoint": "behaviours.exploration.select_goal", "FollowPath": "behaviours.exploration.follow_path",
        "WatchInterestEdges": "behaviours.exploration.gaze", "LookAround": "behaviours.exploration.look_around",
    }


def test_a_head_position_of_the_wrong_length_is_refused_when_the_node_is_made():
    with pytest.raises(ValueError, match="ptu_position"):
        MapStereo(ptu_position=[0.1, 0.0])
