"""TargetHoming alone: an ideal robot in the lab (fake world), manual clock; the geometry by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.roadmap.homing import HomingSettings, Look, TargetHoming, _step_motion, _triangulate, room_of
from behaviours.roadmap.travel import ReturnToReference
from behaviours.roadmap.vision import MIN_INLIERS, Comparison, camera_pose
from behaviours.testing import BehaviourHarness
from maps.room import RoomEstimate
from perception.geometry import Pose2D
from perception.planar import PlanarResult, PlanarStatus
from tests.behaviours.fake_world import FakeWorld, error_to, target_images

TARGET = Pose2D(4.0, 3.0, 0.0)  # the lab's centre, looking at the east wall
OFFSET = (0.15, 0.0)


def planar(turn: float, bearing: float, status: PlanarStatus = PlanarStatus.OK) -> PlanarResult:
    """A planar estimate with this turn and body-frame bearing of the displacement."""
    direction = np.array([-math.sin(bearing), math.cos(bearing)])  # optical (x right, z forward)
    return PlanarResult(turn, direction, np.ones(40, dtype=bool), status)


def look_from(robot: Pose2D, target_camera: Pose2D) -> Look:
    """The exact look of a camera at ``target_camera`` from the robot pose ``robot``."""
    camera = camera_pose(robot, OFFSET)
    rel = target_camera.relative_to(camera)
    return Look(robot, camera, Comparison(40, planar(rel.theta, math.atan2(rel.y, rel.x))), 0.0)


def test_triangulation_puts_the_target_where_the_two_rays_meet():
    target_camera = camera_pose(TARGET, OFFSET)
    first = look_from(Pose2D(2.5, 2.6, 0.3), target_camera)
    second = look_from(Pose2D(2.45, 2.85, 0.3), target_camera)  # 0.25 m to the side, same heading
    found = _triangulate(first, second, OFFSET)
    assert found is not None
    goal, distance = found
    assert goal.distance_to(TARGET) < 1e-9 and goal.theta == pytest.approx(TARGET.theta, abs=1e-9)
    assert distance == pytest.approx(target_camera.distance_to(first.camera), abs=1e-9)


def test_no_triangle_without_parallax_or_without_a_direction():
    target_camera = camera_pose(TARGET, OFFSET)
    first = look_from(Pose2D(2.0, 3.0, 0.0), target_camera)
    along = look_from(Pose2D(2.25, 3.0, 0.0), target_camera)  # a step towards the target: no parallax
    assert _triangulate(first, along, OFFSET) is None
    turn_only = Look(first.odometry, first.camera, Comparison(40, planar(0.1, 0.0, PlanarStatus.NO_TRANSLATION)), 0)
    assert _triangulate(turn_only, look_from(Pose2D(2.0, 3.25, 0.0), target_camera), OFFSET) is None


@pytest.mark.parametrize(("bearing", "side", "turn", "sign"), [
    (0.0, 1, math.pi / 2, 1.0),          # target ahead: step left
    (0.0, -1, -math.pi / 2, 1.0),        # ... or right
    (math.radians(60), 1, math.radians(-30), -1.0),  # perpendicular is 150 deg: back up along -30 deg instead
    (math.radians(-20), 1, math.radians(70), 1.0),
])
def test_sidestep_is_perpendicular_and_never_turns_more_than_90_degrees(bearing, side, turn, sign):
    look = Look(Pose2D(), Pose2D(), Comparison(40, planar(0.0, bearing)), 0.0)
    got_turn, got_sign = _step_motion(look, side)
    assert got_turn == pytest.approx(turn) and got_sign == sign
    assert abs(got_turn) <= math.pi / 2 + 1e-12
    travel = got_sign * np.array([math.cos(got_turn), math.sin(got_turn)])
    assert abs(travel @ [math.cos(bearing), math.sin(bearing)]) < 1e-9  # perpendicular to the homing direction


def homing(world: FakeWorld, **ports) -> BehaviourHarness:
    targets = target_images(world, {"centre": TARGET})
    node = TargetHoming(target="centre", **ports)
    return BehaviourHarness(node, blackboard=world.blackboard(**{"__map__target_images": targets}))


def test_homes_to_the_target_image_from_a_metre_and_a_half():
    world = FakeWorld(start=Pose2D(2.6, 2.2, math.radians(15)))
    harness = homing(world)
    assert harness.tick_until(between=world.step, max_ticks=3000) == Status.SUCCESS
    distance, heading = error_to(world, TARGET)
    assert distance < 0.03 and heading < 1.0
    result = harness.read("/map/homing")
    assert result.target == "centre" and result.iterations >= 2  # one round to get there, one to confirm
    assert world.start.compose(result.pose).distance_to(TARGET) < 0.03  # the estimate, in the odometry frame
    assert harness.read("/robot/command").v == 0.0  # ends at rest


def test_turns_first_when_the_target_faces_away_and_keeps_the_head_level():
    world = FakeWorld(start=Pose2D(3.3, 3.5, math.radians(-35)), pan=0.4)
    harness = homing(world)
    harness.tick()
    assert harness.read("/ptu/command").pan == 0.0  # images are taken with the head level
    assert harness.tick_until(between=world.step, max_ticks=3000) == Status.SUCCESS
    distance, heading = error_to(world, TARGET)
    assert distance < 0.03 and heading < 1.0


def test_fails_when_the_target_is_not_in_sight():
    world = FakeWorld(start=Pose2D(5.0, 3.0, math.pi))  # looking west, the target image looks east
    harness = homing(world)
    assert harness.tick_until(between=world.step, max_ticks=200) == Status.FAILURE
    assert "lost sight of centre" in harness.behaviour.feedback_message
    assert harness.read("/map/homing") is None


def test_fails_at_once_without_a_target_name_or_images():
    world = FakeWorld()
    harness = BehaviourHarness(TargetHoming(), blackboard=world.blackboard())
    assert harness.tick() == Status.FAILURE
    assert harness.behaviour.feedback_message == "no target to home to"


def test_the_settings_are_the_homing_ports():
    node = TargetHoming(step=0.3, done_distance=0.05, max_rounds=3, min_inliers=30)
    assert HomingSettings.of(node) == HomingSettings(0.3, 0.05, 3, 30)
    assert HomingSettings.of(TargetHoming()) == HomingSettings(0.25, 0.08, 5, MIN_INLIERS)


def test_the_room_is_read_whether_a_node_has_it_optional_or_required():
    room = RoomEstimate.from_polygon(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 2.0], [0.0, 2.0]]))
    optional, given, required = TargetHoming(), TargetHoming(room="{/map/room}"), ReturnToReference()
    for node in (optional, given, required):
        BehaviourHarness(node, blackboard={"/map/room": room})
        assert room_of(node) is (None if node is optional else room)  # optional and not given: no room
