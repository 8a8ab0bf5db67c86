"""Route following by the taught odometry while the view is hidden: the anchor a switch makes, the
drive to the target's place, and where it ends (behaviours/route_anchor.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.route import FollowRoute, RouteEstimate, RouteProgress, ViewframeSwitch
from behaviours.route_anchor import RouteAnchor
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from drivers.interfaces import STOP
from perception.geometry import Pose2D
from perception.observation import Observation
from tests.behaviours.routes import IdealBase, taught_map

TREE, PLACES = taught_map()
NOTHING = np.zeros((0, 3))


def test_a_place_is_carried_into_the_repeats_odometry_by_the_turn_between_the_frames():
    # facing +x in the teach's frame while odometry says +y: the frames differ by +90 deg;
    # a place 1 m ahead in the teach's frame lies 1 m along +y of the anchor's odometry (1, 2)
    anchor = RouteAnchor(3, Pose2D(1.0, 2.0, math.pi / 2), heading=0.0)
    assert anchor.to_odometry(np.array([0.0, 0.0]), np.array([1.0, 0.0])) == pytest.approx([1.0, 3.0])
    # heading +90 deg in the teach's frame, 0 in odometry: -90 deg; (0, 1) ahead becomes (1, 0)
    anchor = RouteAnchor(3, Pose2D(5.0, 5.0, 0.0), heading=math.pi / 2)
    assert anchor.to_odometry(np.array([2.0, 2.0]), np.array([2.0, 3.0])) == pytest.approx([6.0, 5.0])


def test_a_skip_or_a_search_unties_the_frames():
    anchor = RouteAnchor(2, Pose2D(), heading=0.0)
    progress = RouteProgress(1, 3, 5, 0.0, switches=1, anchor=anchor)
    assert progress.advanced(1.0).anchor == anchor  # on along the route: the tie holds
    assert progress.retargeted(4, 1.0).anchor is None


def test_the_switch_ties_the_frames_where_the_viewframe_was_reached():
    harness = BehaviourHarness(ViewframeSwitch(), blackboard={"/map/ltmap": TREE,
                                                               "/map/route_progress": RouteProgress(1, 2, 5, 0.0)})
    pose = Pose2D(4.0, -1.0, 0.5)
    harness.write("/robot/odometry", pose)
    harness.write("/map/route_estimate", RouteEstimate(2, 1.0, 100, "ok", 0.0, 0.0, 0.0, 0.9, "zinf_1deg", 0.2))
    harness.tick()
    progress = harness.read("/map/route_progress")
    assert progress.target == 3 and progress.anchor == RouteAnchor(2, pose, 0.2)
    harness.write("/map/route_estimate", RouteEstimate(3, 2.0, 100, "ok", 0.0, 0.0, 0.0, 0.9))  # no rotation
    harness.tick()
    assert harness.read("/map/route_progress").anchor == RouteAnchor(2, pose, 0.2)  # kept until the next tie


class Blind:
    """A base that moves by the command and sees nothing: odometry only (the view hidden)."""

    def __init__(self, harness: BehaviourHarness, pose: Pose2D) -> None:
        self.harness, self.pose, self.driven = harness, pose, 0.0
        self.step = 0
        self.sense()

    def sense(self) -> None:
        self.step += 1
        self.harness.write("/robot/odometry", self.pose)
        self.harness.write("/perception/observation", Observation(NOTHING, self.step * 0.1, "bearings",
                                                                  ids=np.zeros(0, dtype=np.int64)))

    def __call__(self, harness: BehaviourHarness) -> None:
        cmd = harness.read("/robot/command") or STOP
        p = self.pose
        self.pose = Pose2D(p.x + cmd.v * 0.1 * math.cos(p.theta), p.y + cmd.v * 0.1 * math.sin(p.theta),
                           p.theta + cmd.w * 0.1)
        self.driven += abs(cmd.v) * 0.1
        self.sense()


def run(harness: BehaviourHarness, base, ticks: int) -> Status:
    """Tick up to ``ticks`` times, moving ``base`` between ticks; the last status."""
    status = Status.INVALID
    for _ in range(ticks):
        status = harness.tick()
        if status != Status.RUNNING:
            break
        base(harness)
        harness.clock.advance(0.1)
    return status


def lost_harness(target: int, anchor: RouteAnchor | None, **ports) -> BehaviourHarness:
    """FollowRoute lost for 0.5 s before it drives by odometry, up to 4 m on unless ``ports`` say otherwise."""
    progress = RouteProgress(1, target, TREE.viewframe_count, 0.0, switches=1, anchor=anchor)
    return BehaviourHarness(FollowRoute(**{"lost_time": 0.5, "odometry_reach": 4.0, **ports}),
                            blackboard={"/map/ltmap": TREE, "/map/route_progress": progress})


def test_lost_after_a_switch_it_drives_by_odometry_through_the_taught_places_within_its_reach():
    # taught along +x, a viewframe every 0.15 m: viewframe 2 at 0.35 m, 5 at 0.8 m, 8 at 1.25 m, 9 at 1.4 m
    assert [round(float(TREE.place(i)[0]), 2) for i in (2, 5, 8, 9)] == [0.35, 0.8, 1.25, 1.4]
    # the repeat's odometry is turned +90 deg against the teach's: the places lie straight along +y;
    # within 1 m of viewframe 2's place: up to viewframe 8's (0.9 m), not 9's (1.05 m)
    anchor = RouteAnchor(2, Pose2D(10.0, 10.0, math.pi / 2), heading=0.0)
    harness = lost_harness(5, anchor, odometry_reach=1.0)
    base = Blind(harness, anchor.odometry)
    assert run(harness, base, 5) == Status.RUNNING and base.driven == 0.0  # lost_time: it keeps its last command (none)
    status = run(harness, base, 200)
    assert status == Status.FAILURE  # at the last place within reach and still nothing seen: lost
    assert base.pose.x == pytest.approx(10.0, abs=0.02) and base.pose.y == pytest.approx(10.9, abs=0.26)
    assert harness.read("/map/route_progress").target == 8  # 5, 6 and 7 passed by odometry; 8 reached, not passed
    figures = report_sections(harness.behaviour)["ltmap"]
    assert figures["odometry_drives"] == 1 and figures["found_by_odometry"] == 0
    assert figures["passed_by_odometry"] == 3
    assert figures["odometry_m"] == pytest.approx(base.driven, abs=0.05)


def test_the_goal_is_never_passed_by_odometry():
    last = TREE.viewframe_count - 1
    anchor = RouteAnchor(last - 2, Pose2D(), heading=0.0)
    harness = lost_harness(last - 1, anchor)
    base = Blind(harness, Pose2D())
    assert run(harness, base, 100) == Status.FAILURE
    assert harness.read("/map/route_progress").target == last and not harness.read("/map/route_progress").finished


def test_without_a_tie_or_beyond_the_reach_or_by_default_lost_is_lost():
    assert FollowRoute().get_input(FollowRoute.ODOMETRY_REACH) == 0.0  # the paper's rule unless asked
    far = RouteAnchor(0, Pose2D(), heading=0.0)
    for anchor, ports in ((None, {}), (far, {"odometry_reach": 1.0}), (far, {"odometry_reach": 0.0})):
        harness = lost_harness(TREE.viewframe_count - 1, anchor, **ports)  # the goal, 3 m from viewframe 0
        base = Blind(harness, Pose2D())
        assert run(harness, base, 20) == Status.FAILURE
        assert base.driven == 0.0


def test_the_drive_gives_up_after_odometry_time():
    anchor = RouteAnchor(0, Pose2D(), heading=0.0)
    harness = lost_harness(TREE.viewframe_count - 1, anchor, odometry_time=2.0)
    base = Blind(harness, Pose2D())
    assert run(harness, base, 100) == Status.FAILURE
    assert 0.4 < base.driven < 0.8  # 2 s at 0.3 m/s after the 0.5 s lost_time


def test_the_view_back_ends_the_drive_and_vision_steers_again():
    reached, target = 2, 5
    anchor = RouteAnchor(reached, Pose2D(0.0, 0.0, 0.0), heading=0.0)  # the same frame as the teach's...
    harness = lost_harness(target, anchor)
    start = Pose2D(float(TREE.place(reached)[0]), 0.0, 0.0)
    anchor = RouteAnchor(reached, start, heading=0.0)  # ...and the robot where viewframe 2 was taught
    harness.write("/map/route_progress", RouteProgress(1, target, TREE.viewframe_count, 0.0, 1, anchor))
    blind = Blind(harness, start)
    run(harness, blind, 10)
    assert blind.driven > 0.05  # driving by odometry
    IdealBase(harness, blind.pose)  # the view is back
    harness.tick()
    figures = report_sections(harness.behaviour)["ltmap"]
    assert figures["odometry_drives"] == 1 and figures["found_by_odometry"] == 1 and figures["passed_by_odometry"] == 0
    assert harness.read("/map/route_estimate").usable
