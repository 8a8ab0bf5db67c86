"""BuildGraph alone: the covariance model by hand, and two targets of the lab driven there and back."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.roadmap.display import roadmap_section
from behaviours.roadmap.graph import BuildGraph, measured_motion, straight_is_free
from behaviours.roadmap.values import TargetImages
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from maps.roadmap import Roadmap
from maps.room import RoomEstimate
from perception.geometry import Pose2D
from tests.behaviours.fake_world import FakeWorld, error_to, rope, target_images

A, B = Pose2D(4.0, 3.0, 0.0), Pose2D(4.0, 1.8, 0.0)  # lab world frame
REFERENCE = Pose2D(3.6, 2.4, 0.3)  # where the reference image is taken: the origin of the reference frame
FLOOR = np.array([[3.2, 1.2], [5.2, 1.2], [5.2, 4.0], [3.2, 4.0]])  # clear of the pillars and the furniture


def in_reference(pose: Pose2D) -> Pose2D:
    return pose.relative_to(REFERENCE)


def test_measured_motion_and_its_covariance_by_hand():
    motion = measured_motion(Pose2D(1.0, 1.0, math.pi / 2), Pose2D(0.0, 2.0, math.pi))
    # in the start frame the end is at (1, 1) facing +90 deg: turn 45, drive sqrt(2), turn 45
    assert (motion.angle1, motion.distance, motion.angle2) == pytest.approx((math.pi / 4, math.sqrt(2), math.pi / 4))
    turn = (0.01 * math.pi / 4 + math.radians(0.5)) ** 2 + math.radians(0.6) ** 2 * math.sqrt(2)
    drive = 0.02 * math.sqrt(2) + 0.02
    assert np.diag(motion.covariance) == pytest.approx([turn, drive ** 2, turn])
    assert motion.covariance[0, 1] == 0.0


def test_straight_edges_must_stay_on_standable_floor_away_from_their_ends():
    room = RoomEstimate.from_polygon(np.array([[0, 0], [4, 0], [4, 3], [2.2, 3], [2.2, 1.0], [1.8, 1.0], [1.8, 3],
                                               [0, 3]], dtype=float))
    assert straight_is_free(room, Pose2D(0.8, 0.5), Pose2D(3.2, 0.5), 0.28)
    assert not straight_is_free(room, Pose2D(0.8, 2.0), Pose2D(3.2, 2.0), 0.28)  # through the wall
    assert straight_is_free(room, Pose2D(1.6, 2.0), Pose2D(2.1, 2.0), 0.28)  # only its ends: not checked


def setup_graph(world: FakeWorld, targets: TargetImages, **ports) -> BehaviourHarness:
    roadmap = Roadmap().with_target("A", in_reference(A), "A.png").with_target("B", in_reference(B), "B.png")
    floor = np.array([[p.x, p.y] for p in (in_reference(Pose2D(*corner)) for corner in FLOOR)])
    room = RoomEstimate(floor, floor.mean(axis=0), REFERENCE.relative_to(world.start))  # reference in odometry
    reference = target_images(world, {"reference": REFERENCE}).get("reference")
    return BehaviourHarness(BuildGraph(**ports), blackboard=world.blackboard(
        __map__roadmap=roadmap, __map__target_images=targets, __map__room=room, __map__reference_image=reference))


def test_drives_the_pair_there_and_back_and_fuses_the_edge(tmp_path):
    world = FakeWorld(start=Pose2D(3.7, 2.8, 0.1))
    harness = setup_graph(world, target_images(world, {"A": A, "B": B}), file=str(tmp_path / "lab.roadmap"))
    assert harness.tick_until(between=world.step, max_ticks=6000) == Status.SUCCESS
    graph = harness.read("/map/roadmap")
    assert graph.is_connected() and len(graph.edges) == 1
    truth = B.relative_to(A)
    measured = graph.motion("A", "B").relative_pose()
    assert measured.distance_to(truth) < 0.03 and abs(math.degrees(measured.theta - truth.theta)) < 1.0
    assert min(error_to(world, A)[0], error_to(world, B)[0]) < 0.03  # ends homed at one of them
    saved = Roadmap.load(tmp_path / "lab.roadmap")
    assert saved.names == ("A", "B") and len(saved.edges) == 1
    assert report_sections(harness.behaviour) == {"roadmap": {
        **roadmap_section(graph), "pairs_tried": 1, "dropped": [], "not_straight": [],
        "homed_short": [], "saved": str(tmp_path / "lab.roadmap")}}
    assert [d.entity for d in harness.behaviour.drawings()] == ["roadmap/targets",
                                                                "roadmap/graph"]
    assert list(harness.behaviour.drawings()) == []  # the same graph: not again


def test_a_failed_pair_returns_to_the_reference_is_dropped_and_the_graph_is_not_connected():
    world = FakeWorld(start=Pose2D(3.7, 2.8, 0.1))
    targets = target_images(world, {"A": A, "B": Pose2D(6.5, 4.5, math.pi)})  # B's image is of somewhere else
    harness = setup_graph(world, targets)
    assert harness.tick_until(between=world.step, max_ticks=8000) == Status.FAILURE
    assert harness.behaviour.feedback_message == "the graph is not connected: A | B"
    assert error_to(world, REFERENCE)[0] < 0.03  # back at the reference after the failure
    dropped = report_sections(harness.behaviour)["roadmap"]["dropped"]
    assert [(d["from"], d["to"]) for d in dropped][0] in (("A", "B"), ("B", "A"))
    assert harness.read("/map/roadmap").edges == ()  # the roadmap is written all the same


def test_a_drive_held_short_of_the_far_target_homes_from_where_it_stopped():
    # the monitor holds the robot 0.3 m before B on the straight line between them (furniture beside
    # a target): the edge is still measured, homed pose to homed pose, and nothing is touched
    world = FakeWorld(start=Pose2D(3.7, 2.8, 0.1), hold=rope(4.0, 2.1))
    harness = setup_graph(world, target_images(world, {"A": A, "B": B}))
    assert harness.tick_until(between=world.step, max_ticks=8000) == Status.SUCCESS
    graph = harness.read("/map/roadmap")
    truth = B.relative_to(A)
    measured = graph.motion("A", "B").relative_pose()
    assert measured.distance_to(truth) < 0.03 and abs(math.degrees(measured.theta - truth.theta)) < 1.0
    short = report_sections(harness.behaviour)["roadmap"]["homed_short"]
    assert sorted((s["from"], s["to"]) for s in short) == [("A", "B"), ("B", "A")]  # held both ways
    assert all("no progress" in s["reason"] for s in short)
    assert world.contacts == 0
