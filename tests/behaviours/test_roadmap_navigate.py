"""NavigateToTarget alone: a roadmap made by hand from the lab's true poses, an ideal robot."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.roadmap.navigate import NavigateToTarget
from behaviours.roadmap.values import TargetImages, TargetView
from behaviours.roadmap.vision import describe
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from maps.roadmap import EdgeMotion, Roadmap
from perception.geometry import Pose2D
from tests.behaviours.fake_world import FakeWorld, error_to, rope, target_images

A, B = Pose2D(4.0, 3.0, 0.0), Pose2D(4.0, 1.8, math.pi / 2)  # lab world frame
COVARIANCE = np.diag([1e-4, 1e-4, 1e-4])


def roadmap() -> Roadmap:
    """Targets A and B (reference frame = world frame) joined by the exact edge."""
    edge = EdgeMotion.from_relative_pose(B.relative_to(A), COVARIANCE)
    return Roadmap().with_target("A", A).with_target("B", B).with_edge("A", "B", edge)


def navigate(world: FakeWorld, targets: TargetImages, **ports) -> BehaviourHarness:
    return BehaviourHarness(NavigateToTarget(**ports), blackboard=world.blackboard(
        __map__roadmap=roadmap(), __map__target_images=targets))


def test_localises_at_a_target_then_follows_the_edge_and_homes_at_the_goal():
    world = FakeWorld(start=Pose2D(3.3, 2.7, 0.3))
    harness = navigate(world, target_images(world, {"A": A, "B": B}), target="B")
    assert harness.tick_until(between=world.step, max_ticks=8000) == Status.SUCCESS
    distance, heading = error_to(world, B)
    assert distance < 0.03 and heading < 1.0
    result = harness.read("/map/navigation")
    assert result.reached and result.localised_at == "A" and result.visited == ("A", "B")
    assert report_sections(harness.behaviour) == {"roadmap": {"navigation": {
        "goal": "B", "reached": True, "localised_at": "A", "visited": ["A", "B"], "random_moves": 0, "rescans": 0,
        "homed_short": 0, "reason": ""}}}
    assert [d.entity for d in harness.behaviour.drawings()] == ["roadmap/targets",
                                                                "roadmap/graph"]
    assert list(harness.behaviour.drawings()) == []  # the same roadmap: not again


def test_an_unknown_target_fails_at_once():
    world = FakeWorld()
    harness = navigate(world, target_images(world, {"A": A}), target="door")
    assert harness.tick() == Status.FAILURE
    assert harness.behaviour.feedback_message == "no target named 'door' in the roadmap (it has: A, B)"
    assert report_sections(harness.behaviour) == {}  # refused before navigating: nothing to report


def test_random_distance_takes_shortest_then_longest():
    assert NavigateToTarget(target="A", random_distance=[0.2, 0.5]).random_distance == (0.2, 0.5)
    with pytest.raises(ValueError, match=r"random_distance takes \[shortest, longest\], got \[0.5, 0.2\]"):
        NavigateToTarget(target="A", random_distance=[0.5, 0.2])


def test_moves_randomly_while_nothing_matches_then_gives_up():
    world = FakeWorld(start=Pose2D(3.3, 2.7, 0.3))
    noise = np.random.default_rng(5).integers(0, 255, (480, 640)).astype(np.uint8)
    views = tuple(TargetView(n, noise, describe(noise)) for n in ("A", "B"))
    harness = navigate(world, TargetImages(views), target="B", images=2, max_random_moves=2, seed=7)
    assert harness.tick_until(between=world.step, max_ticks=3000) == Status.FAILURE
    assert harness.behaviour.feedback_message == "no target matched after 2 random moves"
    result = harness.read("/map/navigation")
    assert not result.reached and result.random_moves == 2 and result.reason == harness.behaviour.feedback_message
    navigation = report_sections(harness.behaviour)["roadmap"]["navigation"]
    assert navigation["random_moves"] == 2 and navigation["reason"] == result.reason and navigation["visited"] == []
    assert world.true_pose().distance_to(Pose2D(3.3, 2.7)) > 0.3  # it did move


def test_a_drive_held_short_of_the_next_target_still_turns_and_homes_from_there():
    # the monitor holds the robot 0.3 m before B on the edge's straight line (furniture beside B)
    world = FakeWorld(start=Pose2D(3.3, 2.7, 0.3), hold=rope(4.0, 2.1))
    harness = navigate(world, target_images(world, {"A": A, "B": B}), target="B")
    assert harness.tick_until(between=world.step, max_ticks=8000) == Status.SUCCESS
    distance, heading = error_to(world, B)
    assert distance < 0.03 and heading < 1.0
    result = harness.read("/map/navigation")
    assert result.visited == ("A", "B") and result.homed_short == 1 and result.rescans == 0
    assert world.contacts == 0
