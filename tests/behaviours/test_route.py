"""Route following in isolation: StartRoute, FollowRoute, ViewframeSwitch on a synthetic corridor."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.control import Parallel
from behaviours.route import FollowRoute, RouteEstimate, RouteProgress, StartRoute, ViewframeSwitch
from behaviours.telemetry import Arrows, Event, Plot, Points, report_sections
from behaviours.testing import BehaviourHarness
from drivers.interfaces import STOP
from perception.geometry import Pose2D
from perception.observation import Observation
from tests.behaviours.routes import IdealBase, taught_map

TREE, PLACES = taught_map()


def test_start_route_targets_the_first_viewframe_in_either_direction():
    for direction, first in (("forward", 0), ("reverse", TREE.viewframe_count - 1)):
        harness = BehaviourHarness(StartRoute(direction=direction), blackboard={"/map/ltmap": TREE})
        assert harness.tick() == Status.SUCCESS
        progress = harness.read("/map/route_progress")
        assert progress.target == first and progress.remaining == TREE.viewframe_count
    assert BehaviourHarness(StartRoute()).tick() == Status.FAILURE  # no map


def test_progress_advances_and_finishes():
    progress = RouteProgress.start(3, -1, now=0.0)
    assert (progress.target, progress.finished) == (2, False)
    progress = progress.advanced(1.0).advanced(2.0)
    assert (progress.target, progress.switches, progress.switched_at, progress.remaining) == (0, 2, 2.0, 1)
    assert progress.advanced(3.0).finished


def follow_harness(pose: Pose2D, target: int, **ports) -> BehaviourHarness:
    progress = RouteProgress(1, target, TREE.viewframe_count, 0.0)
    return BehaviourHarness(FollowRoute(**ports), blackboard={"/map/ltmap": TREE, "/map/route_progress": progress})


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_follow_route_turns_towards_a_viewframe_off_to_the_side(side):
    target = len(PLACES) // 2
    place = PLACES[target]
    harness = follow_harness(Pose2D(), target, k=1)
    base = IdealBase(harness, Pose2D(place.x - 0.4, place.y + side * 0.3, 0.0))
    assert harness.tick() == Status.RUNNING
    estimate = harness.read("/map/route_estimate")
    assert estimate.viewframe == target and estimate.matched >= 50
    assert estimate.error == pytest.approx(-side * math.atan2(0.3, 0.4), abs=math.radians(8))  # 37 deg off
    command = harness.read("/robot/command")
    assert command.w * side < 0 and command.v > 0
    assert base.pose.x < place.x


def test_follow_route_heading_ignores_the_robots_own_rotation():
    # facing backwards, the direction to the viewframe (its frame) is the same; the error is not
    target = 3
    harness = follow_harness(Pose2D(), target, k=1)
    IdealBase(harness, Pose2D(PLACES[target].x - 0.3, 0.0, math.pi))
    harness.tick()
    estimate = harness.read("/map/route_estimate")
    assert abs(estimate.heading) < math.radians(5) and abs(abs(estimate.error) - math.pi) < math.radians(5)
    assert harness.read("/robot/command").v == 0.0  # turns on the spot first


def test_follow_route_fails_when_lost_for_lost_time_and_keeps_its_last_command_meanwhile():
    harness = follow_harness(Pose2D(), 2, lost_time=0.5)
    nothing = Observation(np.zeros((0, 3)), 0.0, "bearings", ids=np.zeros(0, dtype=np.int64))
    harness.write("/perception/observation", nothing)
    statuses = []
    for step in range(8):
        harness.write("/perception/observation", Observation(nothing.bearings, step * 0.1, "bearings", ids=nothing.ids))
        statuses.append(harness.tick())
        assert harness.read("/robot/command") == STOP  # no estimate yet: nothing to keep on with
        harness.clock.advance(0.1)
    assert statuses[:5] == [Status.RUNNING] * 5 and statuses[5] == Status.FAILURE
    assert "lost: 0 landmarks" in harness.behaviour.feedback_message


def test_follow_route_coasts_over_a_short_gap():
    harness = follow_harness(Pose2D(), 3, k=1, lost_time=0.5)
    base = IdealBase(harness, Pose2D(PLACES[3].x - 0.4, 0.0, 0.0))
    harness.tick()
    moving = harness.read("/robot/command")
    assert moving.v > 0
    nothing = Observation(np.zeros((0, 3)), 1.0, "bearings", ids=np.zeros(0, dtype=np.int64))
    harness.write("/perception/observation", nothing)
    assert harness.tick() == Status.RUNNING and harness.read("/robot/command") == moving
    assert base.pose.x < PLACES[3].x


def test_follow_route_held_behind_an_obstacle_is_not_lost_until_the_way_is_clear():
    # a person in front hides the view (nothing matches) while the avoidance holds the robot: no
    # lost timer, the last command kept for the avoidance to judge; clear again, lost_time counts
    harness = follow_harness(Pose2D(), 3, k=1, lost_time=0.5, held="{/robot/held}")
    IdealBase(harness, Pose2D(PLACES[3].x - 0.4, 0.0, 0.0))
    harness.write("/robot/held", False)
    assert harness.tick() == Status.RUNNING
    moving = harness.read("/robot/command")
    assert moving.v > 0

    def hidden() -> None:
        harness.clock.advance(0.1)
        harness.write("/perception/observation", Observation(np.zeros((0, 3)), harness.clock.now(), "bearings",
                                                             ids=np.zeros(0, dtype=np.int64)))

    harness.write("/robot/held", True)
    for _ in range(30):  # 3 s held, six times lost_time
        hidden()
        assert harness.tick() == Status.RUNNING and harness.read("/robot/command") == moving
    message = "lost: 0 landmarks match viewframe 3 (lost), held by an obstacle in the way"
    assert harness.behaviour.feedback_message == message
    harness.write("/robot/held", False)  # the way is clear, still nothing matches: lost from now on
    statuses = []
    for _ in range(6):
        hidden()
        statuses.append(harness.tick())
    assert statuses == [Status.RUNNING] * 5 + [Status.FAILURE]


def test_follow_route_fails_when_stalled():
    harness = follow_harness(Pose2D(), 2)
    harness.write("/robot/stalled", True)
    assert harness.tick() == Status.FAILURE and harness.read("/robot/command") == STOP


def estimate(viewframe: int, stamp: float, delta: float, heading: float = 0.0) -> RouteEstimate:
    return RouteEstimate(viewframe, stamp, 100, "ok", delta, heading, heading, 0.9)


def switch_harness(progress: RouteProgress, **ports) -> BehaviourHarness:
    return BehaviourHarness(ViewframeSwitch(**ports), blackboard={"/map/ltmap": TREE, "/map/route_progress": progress})


def test_switch_moves_on_when_delta_t_falls_under_the_threshold():
    harness = switch_harness(RouteProgress(1, 2, 5, 0.0))
    harness.write("/map/route_estimate", estimate(2, 1.0, TREE.threshold * 2))
    assert harness.tick() == Status.RUNNING and harness.read("/map/route_progress").target == 2
    harness.clock.set(1.5)
    harness.write("/map/route_estimate", estimate(2, 1.5, TREE.threshold / 2))
    assert harness.tick() == Status.RUNNING
    progress = harness.read("/map/route_progress")
    assert (progress.target, progress.switches, progress.switched_at) == (3, 1, 1.5)
    assert report_sections(harness.behaviour) == {"ltmap": {
        "switches": 1, "switches_by_flip": 0, "reached": [{"viewframe": 2, "time_s": 1.5, "rule": "delta_t"}]}}


def test_flip_rule_is_blocked_for_a_half_turn_after_a_switch():
    harness = switch_harness(RouteProgress(1, 2, 5, 0.0), turn_rate=45.0)  # 4 s to turn 180 deg
    assert harness.behaviour.block_time == pytest.approx(4.0)
    near = TREE.threshold * 2
    for t, heading in ((1.0, 0.1), (2.0, 3.0)):  # a flip at 2 s: blocked
        harness.clock.set(t)
        harness.write("/map/route_estimate", estimate(2, t, near, heading))
        harness.tick()
    assert harness.read("/map/route_progress").target == 2
    for t, heading in ((4.5, 3.0), (5.0, 0.2)):  # after the block, a flip switches
        harness.clock.set(t)
        harness.write("/map/route_estimate", estimate(2, t, near, heading))
        harness.tick()
    assert harness.read("/map/route_progress").target == 3
    assert report_sections(harness.behaviour)["ltmap"]["switches_by_flip"] == 1


def test_a_flip_far_from_the_viewframe_is_noise():
    # near: under the eq. 1 cost of flip_near = 2.7 times the threshold's 3 deg, 8.1 deg: x = 1 - cos(8.1 deg) =
    # 9.976342e-3, x / b = 16.376863, sqrt(1 + 268.201633) - 1 = 15.407365, times 2 b^2 = 7.421836e-7:
    # 1.143509e-5, 10.54 thresholds of 1.085038e-6
    for delta, switched in ((20.0, False), (10.0, True)):
        harness = switch_harness(RouteProgress(1, 2, 5, 0.0), turn_rate=90.0)
        for t, heading in ((5.0, 0.1), (5.5, 3.0)):
            harness.clock.set(t)
            harness.write("/map/route_estimate", estimate(2, t, TREE.threshold * delta, heading))
            harness.tick()
        assert harness.read("/map/route_progress").target == (3 if switched else 2)


def test_the_goal_needs_a_tighter_delta_t_and_ends_the_route():
    # the goal: under the eq. 1 cost of goal_fraction = 0.34 of the threshold's 3 deg, 1.02 deg:
    # x = 1 - cos(1.02 deg) = 1.584578e-4, x / b = 0.260120, sqrt(1 + 0.067662) - 1 = 0.033277,
    # times 2 b^2 = 7.421836e-7: 2.469793e-8, 0.0228 of the threshold (1.085038e-6)
    harness = switch_harness(RouteProgress(-1, 0, 5, 0.0))  # reverse: viewframe 0 is the last
    harness.write("/map/route_estimate", estimate(0, 1.0, TREE.threshold * 0.5))
    assert harness.tick() == Status.RUNNING  # under the threshold, not under the goal's
    harness.write("/map/route_estimate", estimate(0, 1.1, TREE.threshold * 0.03))
    assert harness.tick() == Status.RUNNING
    harness.write("/map/route_estimate", estimate(0, 1.2, TREE.threshold * 0.02))
    assert harness.tick() == Status.SUCCESS and harness.read("/map/route_progress").finished


def test_an_estimate_for_another_viewframe_or_seen_before_is_ignored():
    harness = switch_harness(RouteProgress(1, 2, 5, 0.0))
    harness.write("/map/route_estimate", estimate(1, 1.0, 0.0))
    harness.tick()
    assert harness.read("/map/route_progress").target == 2


@pytest.mark.parametrize("direction", ["forward", "reverse"])
def test_following_the_whole_route_reaches_its_end(direction):
    start = Pose2D(0.0, 0.05, 0.1) if direction == "forward" else Pose2D(PLACES[-1].x, -0.05, math.pi - 0.1)
    progress = RouteProgress.start(TREE.viewframe_count, 1 if direction == "forward" else -1, 0.0)
    tree = Parallel(name="follow", policy="one", children=[FollowRoute(speed=0.3), ViewframeSwitch()])
    harness = BehaviourHarness(tree, blackboard={"/map/ltmap": TREE, "/map/route_progress": progress})
    base = IdealBase(harness, start)
    assert harness.tick_until(between=base, max_ticks=400) == Status.SUCCESS
    goal = PLACES[-1] if direction == "forward" else PLACES[0]
    assert base.pose.distance_to(goal) < 0.1
    assert max(abs(p.y) for p in base.trail) < 0.1  # along the taught line
    assert harness.read("/map/route_progress").switches == TREE.viewframe_count


def test_follow_route_draws_its_estimate_while_it_follows():
    target = len(PLACES) // 2
    harness = follow_harness(Pose2D(), target, k=1)
    IdealBase(harness, Pose2D(PLACES[target].x - 0.4, 0.0, 0.0))
    node = harness.behaviour
    assert list(node.drawings()) == []  # nothing estimated yet
    harness.tick()
    drawn = {d.entity: d for d in node.drawings()}
    estimate = harness.read("/map/route_estimate")
    assert drawn["route/target_viewframe"] == Plot("route/target_viewframe", float(target))
    assert drawn["route/matched"].value == estimate.matched and drawn["route/delta_t"].value <= 1.0
    arrow = drawn["route/robot_frame/direction"]
    assert isinstance(arrow, Arrows) and arrow.colours == (255, 80, 0)
    assert np.allclose(arrow.vectors, [[math.cos(estimate.error), math.sin(estimate.error)]])
    matched = drawn["route/robot_frame/matched_landmarks"]
    assert isinstance(matched, Points) and len(matched.positions) == estimate.matched and matched.radius == 0.02


def counted(**counts: int) -> dict:
    rules = ("zinf_1deg", "zinf_2deg", "zinf_4deg", "zinf_8deg", "compass", "no_rotation", "lost")
    return {"ltmap": {"estimates": {rule: counts.get(rule, 0) for rule in rules},
                      "odometry_drives": 0, "found_by_odometry": 0, "passed_by_odometry": 0,
                      "odometry_m": 0.0}}


def test_follow_route_counts_every_estimate_by_the_rule_that_made_it():
    target = len(PLACES) // 2
    harness = follow_harness(Pose2D(), target, k=1)
    IdealBase(harness, Pose2D(PLACES[target].x - 0.4, 0.0, 0.0))
    node = harness.behaviour
    assert report_sections(node) == counted()  # every rule, counted from zero
    harness.tick()  # the corridor's far landmarks stay within 1 deg: the paper's rung
    assert harness.read("/map/route_estimate").rule == "zinf_1deg"
    nothing = Observation(np.zeros((0, 3)), 9.0, "bearings", ids=np.zeros(0, dtype=np.int64))
    harness.write("/perception/observation", nothing)
    harness.tick()
    assert harness.read("/map/route_estimate").rule == "" and report_sections(node) == counted(zinf_1deg=1, lost=1)
    node.initialise()  # a recovery runs the node again: the counts go on
    assert report_sections(node) == counted(zinf_1deg=1, lost=1)
    compass = follow_harness(Pose2D(), target, k=1, rotation="compass")
    IdealBase(compass, Pose2D(PLACES[target].x - 0.4, 0.0, 0.0))
    compass.tick()
    assert compass.read("/map/route_estimate").status == "ok"  # asked for, not a fallback
    assert report_sections(compass.behaviour) == counted(compass=1)


def test_switch_draws_each_switch_once():
    harness = switch_harness(RouteProgress(1, 2, 5, 0.0))
    harness.write("/robot/odometry", Pose2D(1.0, 0.5, 0.0))
    harness.write("/map/route_estimate", estimate(2, 1.0, TREE.threshold / 2))
    harness.tick()
    drawn = list(harness.behaviour.drawings())
    assert drawn[0] == Event("route/events", "viewframe 2 reached (delta_t)")
    assert drawn[1].entity == "odometry_frame/route/reached_viewframes" and drawn[1].positions.tolist() == [[1.0, 0.5]]
    assert list(harness.behaviour.drawings()) == []  # nothing new: nothing drawn
