"""ScanForTargets alone: an ideal robot turning on the spot in the lab (fake world)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.roadmap.scan import ScanForTargets
from behaviours.roadmap.values import TargetImages, TargetView
from behaviours.roadmap.vision import describe
from behaviours.testing import BehaviourHarness
from maps.roadmap import Roadmap
from maps.room import RoomEstimate
from perception.geometry import Pose2D, wrap_angle
from tests.behaviours.fake_world import FakeWorld, target_images

TARGET = Pose2D(4.0, 3.0, 0.0)
START = Pose2D(3.0, 2.6, -math.pi / 2)  # a metre behind the target, looking away from what it sees
ROOM = RoomEstimate(np.array([[-3.0, -3.0], [3.0, -3.0], [3.0, 3.0], [-3.0, 3.0]]), np.zeros(2),
                    Pose2D(0.5, 0.0, 0.0))  # its reference pose, in the odometry frame


def scanner(world: FakeWorld, targets: TargetImages, **blackboard) -> BehaviourHarness:
    return BehaviourHarness(ScanForTargets(), blackboard=world.blackboard(
        __map__target_images=targets, __map__room=ROOM, **blackboard))


def test_turns_until_a_target_matches_and_stops_there():
    world = FakeWorld(start=START)
    harness = scanner(world, target_images(world, {"centre": TARGET}))
    assert harness.tick_until(between=world.step, max_ticks=2000) == Status.SUCCESS
    sighting, scan = harness.read("/map/sighting"), harness.read("/map/scan")
    assert sighting.target == "centre" and sighting.inliers >= 25
    assert 2 <= len(scan.headings) <= 4  # stopped early: the target faces 90 deg from the start
    turned = np.degrees(np.diff(scan.headings))
    assert turned == pytest.approx(np.full(len(turned), 30.0), abs=1.0)
    assert abs(math.degrees(wrap_angle(world.true_pose().theta - TARGET.theta))) < 45.0
    assert scan.found == "centre" and scan.seq == 1
    here = ROOM.to_reference(Pose2D())  # the scan record is in the reference frame
    assert (scan.x, scan.y) == pytest.approx((here.x, here.y))
    # scanning again from here with centre still not found: homing to it from here failed, look elsewhere
    assert harness.tick_until(between=world.step, max_ticks=10) == Status.FAILURE
    assert harness.behaviour.feedback_message == "no target left to look for from (-0.5, 0.0)"


def test_a_full_turn_without_a_match_fails_and_records_twelve_headings():
    world = FakeWorld(start=START)
    noise = np.random.default_rng(3).integers(0, 255, (480, 640)).astype(np.uint8)
    harness = scanner(world, TargetImages((TargetView("nowhere", noise, describe(noise)),)))
    assert harness.tick_until(between=world.step, max_ticks=3000) == Status.FAILURE
    assert harness.behaviour.feedback_message.startswith("no target in sight")
    scan = harness.read("/map/scan")
    assert len(scan.headings) == 12 and scan.found == ""
    assert np.degrees(np.unwrap(scan.headings)[-1] - scan.headings[0]) == pytest.approx(330.0, abs=2.0)
    assert harness.read("/map/sighting") is None
    assert abs(math.degrees(wrap_angle(world.true_pose().theta - START.theta))) < 1.0  # unwound: no net turn


def test_targets_already_found_are_not_looked_for():
    world = FakeWorld(start=START)
    found = Roadmap().with_target("centre", Pose2D())
    harness = scanner(world, target_images(world, {"centre": TARGET}), __map__roadmap=found)
    assert harness.tick() == Status.FAILURE
    assert harness.behaviour.feedback_message == "every target is found already"


def test_a_target_sighted_from_here_last_and_not_found_since_is_skipped_from_here_only():
    node = ScanForTargets()
    node.last = ("door", Pose2D(1.0, 1.0))  # homing to the door from (1, 1) failed
    assert node._failed_here("door", Pose2D(1.2, 1.0))  # within 0.3 m: look for the others
    assert not node._failed_here("door", Pose2D(1.4, 1.0))  # from elsewhere: the door again
    assert not node._failed_here("window", Pose2D(1.0, 1.0))
