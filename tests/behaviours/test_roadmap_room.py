"""RoomEstimationDodecagon alone: an ideal robot on the lab's start, its stereo pair rendered."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.roadmap.display import room_section
from behaviours.roadmap.room import RoomEstimationDodecagon
from behaviours.roadmap.values import TargetView
from behaviours.roadmap.vision import describe
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from maps.room import RigMount, RoomEstimate, dodecagon
from perception.geometry import Pose2D
from tests.behaviours.fake_world import FakeWorld

LAB_START = Pose2D(1.5, 1.5, math.radians(30))


@pytest.fixture(scope="module")
def estimated():
    world = FakeWorld(start=LAB_START, cameras=("stereo", "front"))
    node = RoomEstimationDodecagon()
    harness = BehaviourHarness(node, blackboard=world.blackboard())
    corners: list[Pose2D] = []

    def between(h: BehaviourHarness) -> None:
        if node.feedback_message.startswith("corner") and len(corners) < len(node._points):
            corners.append(h.read("/robot/odometry"))
        world.step(h)

    status = harness.tick_until(between=between, max_ticks=2000)
    # read now: every test starts with a clean blackboard
    outputs = {key: harness.read(key) for key in ("/map/room", "/map/reference_image", "/robot/command")}
    outputs.update(report=report_sections(node), drawings=list(node.drawings()), again=list(node.drawings()))
    return status, node, world, corners, outputs


def test_drives_the_dodecagon_taking_twelve_pairs(estimated):
    status, node, world, corners, outputs = estimated
    assert status == Status.SUCCESS
    expected = dodecagon(Pose2D(), 0.25)
    assert len(corners) == 12
    for got, want in zip(corners, expected, strict=True):
        assert got.distance_to(want) < 0.05 and abs(math.remainder(got.theta - want.theta, 2 * math.pi)) < 0.02
    assert outputs["/robot/command"].v == 0.0


def test_the_room_matches_the_lab_and_the_reference_is_the_richest_image(estimated):
    _, node, world, _, outputs = estimated
    room, reference = outputs["/map/room"], outputs["/map/reference_image"]
    assert room.free.free.sum() * room.free.cell ** 2 > 20.0  # the lab's floor seen from its start: ~30 m2
    truth = world.start.compose(room.reference_pose)  # where the reference pose is in the world
    for wall_point in ([0.0, 1.0], [2.0, 0.0], [2.5, 5.15]):  # two walls and a desk, in view
        local = Pose2D(*wall_point).relative_to(truth)
        direction = math.atan2(local.y - room.centre[1], local.x - room.centre[0])
        expected = math.hypot(local.x - room.centre[0], local.y - room.centre[1])
        assert room.distances(np.array([direction]))[0] == pytest.approx(expected, abs=0.25)
    assert reference.name == "reference" and reference.camera is not None
    assert len(reference.features) == max(node._features) == node._features[room.reference_index]


def test_fails_when_the_views_do_not_go_all_around(world_file):
    path = world_file("""
        format: 1
        ceiling: 2.6
        walls:
          - {points: [[2, -2], [2, 2]], height: 2.6, texture: {seed: 3, pixels_per_m: 60, feature_size: 0.2}}
        """)  # one wall ahead, open floor everywhere else
    world = FakeWorld(world=str(path), start=Pose2D(), cameras=("stereo", "front"))
    harness = BehaviourHarness(RoomEstimationDodecagon(), blackboard=world.blackboard())
    assert harness.tick_until(between=world.step, max_ticks=2000) == Status.FAILURE
    assert harness.behaviour.feedback_message.startswith("room estimate:")


def test_reports_the_room_and_draws_it_once_and_the_robot_every_time(estimated):
    _, node, _, _, outputs = estimated
    room, reference = outputs["/map/room"], outputs["/map/reference_image"]
    assert outputs["report"] == {"roadmap": {"room": room_section(room, node._points, node._features,
                                                                  reference.stamp)}}
    assert [d.entity for d in outputs["drawings"]] == [
        "roadmap/room/free", "roadmap/room/obstacles", "roadmap/room/corners", "roadmap/room/reference",
        "roadmap/robot"]
    assert [d.entity for d in outputs["again"]] == ["roadmap/robot"]


def test_reports_whatever_room_is_on_its_output_and_nothing_before():
    node = RoomEstimationDodecagon()
    harness = BehaviourHarness(node)
    assert report_sections(node) == {} and list(node.drawings()) == []
    room = RoomEstimate.from_polygon(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 2.0], [0.0, 2.0]]))
    harness.write("/map/room", room)  # a re-anchored room is this node's output too: same key
    node._points, node._features = [100] * 12, [50] * 12
    nan_stamp = report_sections(node)["roadmap"]["room"]
    assert math.isnan(nan_stamp.pop("reference_stamp"))  # no reference image: no stamp
    expected = room_section(room, [100] * 12, [50] * 12, math.nan)
    expected.pop("reference_stamp")
    assert nan_stamp == expected
    image = np.zeros((8, 8), np.uint8)
    harness.write("/map/reference_image", TargetView("reference", image, describe(image), stamp=12.5))
    assert report_sections(node)["roadmap"]["room"]["reference_stamp"] == 12.5
    assert [d.entity for d in node.drawings()] == ["roadmap/room/free",
                                                   "roadmap/room/reference"]  # no odometry: no robot


def test_the_rig_is_mounted_as_its_ports_say():
    node = RoomEstimationDodecagon(rig_height=1.2, pan_axis=[0.2, 0.01], rig_offset=[0.04, -0.06])
    assert node.mount() == RigMount(1.2, (0.2, 0.01), (0.04, -0.06))
    with pytest.raises(ValueError, match=r"RoomEstimationDodecagon.pan_axis takes \[x, y\], got \[0.1\]"):
        RoomEstimationDodecagon(pan_axis=[0.1])


def test_a_dodecagon_that_does_not_fit_says_what_room_it_needs():
    """Started 0.5 m from the lab's west wall facing north: the corners' circle (centre to the left,
    radius 0.25 / (2 sin 15 deg) = 0.483 m) runs into the wall; the robot stalls against it."""
    world = FakeWorld(start=Pose2D(0.5, 1.5, math.radians(90)), cameras=("stereo", "front"))
    node = RoomEstimationDodecagon()
    harness = BehaviourHarness(node, blackboard=world.blackboard())
    assert harness.tick_until(between=world.step, max_ticks=3000) == Status.FAILURE
    # 2 (0.483 + 0.26) = 1.486 m: the corners' circle and the default robot disc (nothing published)
    assert "driving to corner" in node.feedback_message
    assert "needs a free disc 1.49 m across, its centre 0.48 m to the robot's left" in node.feedback_message
