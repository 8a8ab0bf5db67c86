"""Planned paths in the room estimate: snapping to standable floor, planning, driving the waypoints."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.roadmap.paths import PLAN_PORTS, SNAP, nearest_standable, plan, reanchored, travel
from behaviours.roadmap.routine import ROBOT_RADIUS, ROUTINE_PORTS, RoutineBehaviour, Step
from behaviours.testing import BehaviourHarness
from maps.planning import PlanResult
from maps.room import RoomEstimate
from perception.geometry import Pose2D
from tests.behaviours.test_motion import integrate

# a U-shaped room (reference frame): the way from one arm to the other goes round the wall between
U_ROOM = np.array([[0, 0], [4, 0], [4, 3], [2.6, 3], [2.6, 1.0], [1.4, 1.0], [1.4, 3], [0, 3]], dtype=float)
REFERENCE = Pose2D(1.0, -2.0, math.pi / 2)  # the reference frame as seen in the odometry frame


def u_room(reference: Pose2D = REFERENCE) -> RoomEstimate:
    return RoomEstimate(U_ROOM, np.array([2.0, 0.5]), reference)


class Traveller(RoutineBehaviour):
    """Travels to ``goal`` (reference frame) in ``room``: a test host with the plan ports (not registered)."""

    PORTS = (ROBOT_RADIUS, *PLAN_PORTS, *ROUTINE_PORTS)

    def __init__(self, room: RoomEstimate, goal: Pose2D, *, turn: bool = False, **ports: Any) -> None:
        super().__init__(name=None, **ports)
        self.room, self.goal, self.turn = room, goal, turn
        self.path: PlanResult | None = None

    def routine(self) -> Step[None]:
        self.path = yield from travel(self, self.room, self.goal, turn=self.turn)


class Planner(RoutineBehaviour):
    """Only plans, and has no plan ports: the path is kept here, not written."""

    PORTS = (ROBOT_RADIUS, *ROUTINE_PORTS)

    def __init__(self, room: RoomEstimate, goal: Pose2D) -> None:
        super().__init__(name=None)
        self.room, self.goal = room, goal
        self.path: PlanResult | None = None

    def routine(self) -> Step[None]:
        self.path = yield from plan(self, self.room, self.goal)


def start(room: RoomEstimate, x: float, y: float, theta: float = 0.0) -> dict[str, Pose2D]:
    return {"/robot/odometry": room.to_odometry(Pose2D(x, y, theta))}


def test_travel_goes_round_the_wall_and_ends_on_the_goal_facing_it():
    room = u_room()
    goal = Pose2D(3.3, 2.5, -math.pi / 2)
    harness = BehaviourHarness(Traveller(room, goal, turn=True), blackboard=start(room, 0.7, 2.5))
    assert harness.tick_until(between=integrate, max_ticks=5000) == Status.SUCCESS
    path = harness.behaviour.path
    assert path is not None and path.ok and len(path.waypoints) > 2  # not straight: the wall is in the way
    assert harness.read("/map/plan") is path  # the host has the plan port: the path is written
    here = room.to_reference(harness.read("/robot/odometry"))
    assert here.distance_to(goal) < 0.03 and here.theta == pytest.approx(goal.theta, abs=0.02)


def test_without_turn_the_robot_keeps_the_heading_it_arrived_with():
    room = u_room()
    harness = BehaviourHarness(Traveller(room, Pose2D(3.3, 0.5, math.pi)), blackboard=start(room, 0.7, 0.5))
    assert harness.tick_until(between=integrate, max_ticks=5000) == Status.SUCCESS
    here = room.to_reference(harness.read("/robot/odometry"))
    assert here.distance_to(Pose2D(3.3, 0.5)) < 0.03
    assert abs(math.remainder(here.theta, 2 * math.pi)) < math.radians(10)  # arrived heading +x, not turned to pi


def test_a_host_without_plan_ports_plans_and_writes_nothing():
    room = u_room()
    harness = BehaviourHarness(Planner(room, Pose2D(3.3, 2.5)), blackboard=start(room, 0.7, 2.5))
    assert harness.tick_until(between=integrate) == Status.SUCCESS
    assert harness.behaviour.path is not None and harness.behaviour.path.ok
    assert harness.read("/map/plan") is None


def test_a_start_off_the_standable_floor_is_planned_from_the_nearest_standable_point():
    room = u_room()
    harness = BehaviourHarness(Planner(room, Pose2D(3.3, 2.5)), blackboard=start(room, 0.1, 2.5))  # by a wall
    assert harness.tick_until(between=integrate) == Status.SUCCESS
    first = harness.behaviour.path.waypoints[0]
    assert (first.x, first.y) == nearest_standable(room.free, 0.1, 2.5, 0.28)
    assert (first.x, first.y) != (0.1, 2.5)


def test_a_goal_far_from_standable_floor_fails_saying_so():
    room = u_room()
    harness = BehaviourHarness(Traveller(room, Pose2D(8.0, 8.0)), blackboard=start(room, 0.7, 2.5))
    assert harness.tick_until(between=integrate) == Status.FAILURE
    assert harness.behaviour.feedback_message == (f"no path: the goal is more than {SNAP} m from floor where the "
                                                  "robot may stand")


def test_nearest_standable_snaps_within_reach_only():
    free = u_room().free
    assert nearest_standable(free, 0.7, 2.5, 0.28) == (0.7, 2.5)
    snapped = nearest_standable(free, 0.05, 2.5, 0.28)
    assert snapped is not None and free.can_stand(np.array([snapped]), 0.28)[0]
    assert nearest_standable(free, 2.0, 2.5, 0.28, snap=0.2) is None  # inside the wall, too far from floor


def test_reanchoring_moves_the_reference_only():
    room = u_room(Pose2D())
    free = room.free
    moved = reanchored(room, Pose2D(0.3, 0.1, 0.2))
    assert moved.free is free and moved.reference_pose == Pose2D(0.3, 0.1, 0.2)
    assert np.array_equal(moved.polygon, room.polygon)
    origin = moved.to_reference(Pose2D(0.3, 0.1, 0.2))  # the new reference pose is the frame's origin
    assert (origin.x, origin.y, origin.theta) == pytest.approx((0.0, 0.0, 0.0))


# two 2 x 2 m rooms joined by a neck 0.4 m wide (x 2-2.5): two free regions for a 0.28 m disc
DUMBBELL = np.array([[0, 0], [2, 0], [2, 0.8], [2.5, 0.8], [2.5, 0], [4.5, 0], [4.5, 2], [2.5, 2], [2.5, 1.2],
                     [2, 1.2], [2, 2], [0, 2]], dtype=float)


def test_a_robot_cut_off_from_the_goal_plans_from_the_nearest_floor_joined_to_it():
    """The robot stands in the west room (it got there by homing, or the cut was a person who has
    gone); the goal is in the east room. The plan starts on the east room's floor nearest the
    robot: just inside the neck's east end, 0.28 m (the radius) and a cell's margin past x = 2.5,
    level with the robot."""
    room = RoomEstimate(DUMBBELL, np.array([1.0, 1.0]), Pose2D())
    free = room.free
    assert free.region_at(np.array([[1.0, 1.0]]), 0.28)[0] != free.region_at(np.array([[3.5, 1.0]]), 0.28)[0]
    harness = BehaviourHarness(Planner(room, Pose2D(3.5, 1.0)), blackboard=start(room, 1.0, 1.0))
    assert harness.tick_until(between=integrate) == Status.SUCCESS
    first = harness.behaviour.path.waypoints[0]
    assert free.region_at(np.array([[first.x, first.y]]), 0.28)[0] == free.region_at(np.array([[3.5, 1.0]]), 0.28)[0]
    assert 2.78 < first.x < 2.95 and first.y == pytest.approx(1.0, abs=0.05)
    # a goal in the robot's own room: planned from where it stands, as before
    harness = BehaviourHarness(Planner(room, Pose2D(0.6, 1.5)), blackboard=start(room, 1.0, 1.0))
    assert harness.tick_until(between=integrate) == Status.SUCCESS
    first = harness.behaviour.path.waypoints[0]
    assert (first.x, first.y) == pytest.approx((1.0, 1.0))
