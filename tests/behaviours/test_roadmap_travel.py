"""GoToPose and ReturnToReference alone: ideal odometry, a hand-made room, the lab's images."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.roadmap import travel as travel_module
from behaviours.roadmap.homing import HomingSettings
from behaviours.roadmap.routine import Failed
from behaviours.roadmap.travel import GoToPose, ReturnToReference, return_to_reference
from behaviours.roadmap.values import TargetView
from behaviours.roadmap.vision import describe
from behaviours.telemetry import Lines, report_sections
from behaviours.testing import BehaviourHarness
from maps.room import RoomEstimate
from perception.geometry import Pose2D
from tests.behaviours.fake_world import FakeWorld, error_to
from tests.behaviours.test_motion import integrate

# a U-shaped room (reference frame): the way from one arm to the other goes round the wall between
U_ROOM = np.array([[0, 0], [4, 0], [4, 3], [2.6, 3], [2.6, 1.0], [1.4, 1.0], [1.4, 3], [0, 3]], dtype=float)


def u_room(reference: Pose2D) -> RoomEstimate:
    return RoomEstimate(U_ROOM, np.array([2.0, 0.5]), reference)


def test_goes_round_the_wall_to_a_pose_in_the_reference_frame():
    reference = Pose2D(1.0, -2.0, math.pi / 2)  # the reference frame as seen in the odometry frame
    room = u_room(reference)
    start = room.to_odometry(Pose2D(0.7, 2.5, 0.0))
    harness = BehaviourHarness(GoToPose(goal="{/mission/goal}", turn=True),
                               blackboard={"/map/room": room, "/robot/odometry": start,
                                           "/mission/goal": Pose2D(3.3, 2.5, -math.pi / 2)})
    assert harness.tick_until(between=integrate, max_ticks=5000) == Status.SUCCESS
    plan = harness.read("/map/plan")
    assert plan.ok and len(plan.waypoints) > 2  # not straight: the wall is in the way
    here = room.to_reference(harness.read("/robot/odometry"))
    assert here.distance_to(Pose2D(3.3, 2.5)) < 0.03 and here.theta == pytest.approx(-math.pi / 2, abs=0.02)
    (path,) = harness.behaviour.drawings()  # the plan, drawn once
    assert isinstance(path, Lines) and path.entity == "roadmap/plan"
    assert path.strips[0].tolist() == [[w.x, w.y] for w in plan.waypoints]
    assert list(harness.behaviour.drawings()) == []


def test_no_path_fails_with_the_planners_reason():
    room = u_room(Pose2D())
    harness = BehaviourHarness(GoToPose(goal="{/mission/goal}"),
                               blackboard={"/map/room": room, "/robot/odometry": Pose2D(0.7, 2.5),
                                           "/mission/goal": Pose2D(8.0, 8.0)})
    assert harness.tick_until(between=integrate) == Status.FAILURE
    assert "no path: the goal is more than" in harness.behaviour.feedback_message


def test_returns_to_the_reference_homes_there_and_reanchors_the_room():
    reference_true = Pose2D(2.0, 2.0, 0.3)  # lab world frame
    world = FakeWorld(start=Pose2D(3.5, 1.5, math.pi / 2))
    image = world.sim.snapshot(reference_true, "front", pan=0.0, tilt=0.0)
    reference_image = TargetView("reference", image.image, describe(image.image), image.camera)
    truth_in_odometry = reference_true.relative_to(world.start)
    drifted = truth_in_odometry.compose(Pose2D(0.15, -0.1, math.radians(3.0)))  # what odometry believes
    corners = np.array([[0.6, 0.6], [7.4, 0.6], [7.4, 2.7], [0.6, 2.7]])  # free floor (world frame) ...
    polygon = np.array([[p.x, p.y] for p in (Pose2D(*c).relative_to(reference_true) for c in corners)])
    room = RoomEstimate(polygon, polygon.mean(axis=0), drifted)  # ... in the reference frame
    harness = BehaviourHarness(ReturnToReference(), blackboard=world.blackboard(
        __map__room=room, __map__reference_image=reference_image))
    assert harness.tick_until(between=world.step, max_ticks=5000) == Status.SUCCESS
    distance, heading = error_to(world, reference_true)
    assert distance < 0.03 and heading < 1.0
    anchored = harness.read("/map/room").reference_pose
    assert anchored.distance_to(truth_in_odometry) < 0.03
    assert abs(math.degrees(anchored.theta - truth_in_odometry.theta)) < 1.0
    section = report_sections(harness.behaviour)["roadmap"]
    assert list(section) == ["reference_drift_m (ReturnToReference)"]
    (drift,) = section["reference_drift_m (ReturnToReference)"]
    assert drift == pytest.approx(math.hypot(0.15, 0.1), abs=0.04) and drift == round(drift, 4)


def test_no_return_no_figure_and_each_return_node_reports_under_its_own_name():
    assert report_sections(ReturnToReference()) == {}
    node = ReturnToReference(name="return at the end")
    node.returns, node.corrections = 2, [0.123456, 0.05]
    assert report_sections(node) == {"roadmap": {"reference_drift_m (return at the end)": [0.1235, 0.05]}}


def finish(step):
    """Run a routine step to its end, as ticks would: its result."""
    try:
        while True:
            next(step)
    except StopIteration as stop:
        return stop.value


@pytest.mark.parametrize(("retries", "travels"), [(0, 1), (1, 2)])
def test_returning_to_the_reference_travels_again_only_as_often_as_told(monkeypatch, retries, travels):
    calls: list[Pose2D] = []

    def travel(host, room, goal, *, turn):
        calls.append(goal)
        assert turn
        if len(calls) == 1:
            raise Failed("stalled")
        yield

    def home(host, reference, settings):
        yield
        return ("homed", reference.name, settings)

    monkeypatch.setattr(travel_module, "travel", travel)
    monkeypatch.setattr(travel_module, "home", home)
    settings = HomingSettings(0.25, 0.08, 5, 25)
    reference = TargetView("reference", np.zeros((4, 4), np.uint8), describe(np.zeros((4, 4), np.uint8)))
    step = return_to_reference(None, u_room(Pose2D()), reference, settings, retries=retries)
    if retries == 0:
        with pytest.raises(Failed, match="stalled"):
            finish(step)
    else:
        assert finish(step) == ("homed", "reference", settings)
    assert calls == [Pose2D()] * travels  # always to the reference pose, the origin of the reference frame
