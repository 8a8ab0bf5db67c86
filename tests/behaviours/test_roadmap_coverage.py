"""CoverageScoring alone: a known rectangular room, hand-set odometry and scans."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.roadmap.coverage import CoverageScoring
from behaviours.roadmap.values import ScanRecord
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from maps.coverage import choose_next, coverage_grid, image_headings, reachable_positions
from maps.room import RoomEstimate
from perception.geometry import Pose2D

ROOM = RoomEstimate.from_polygon(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 2.0], [0.0, 2.0]]))


def scoring(**ports) -> BehaviourHarness:
    return BehaviourHarness(CoverageScoring(**ports), blackboard={"/map/room": ROOM,
                                                                  "/robot/odometry": Pose2D(1.0, 1.0, 0.0)})


def test_chooses_what_choose_next_chooses_and_heads_there():
    harness = scoring()
    assert harness.tick() == Status.SUCCESS
    grid = coverage_grid(ROOM, ROOM.free, robot_radius=0.28)
    expected = choose_next(grid, candidates=reachable_positions(grid, ROOM.free, 0.28, 1.0, 1.0), min_new=100)
    goal = harness.read("/map/coverage_goal")
    assert (goal.x, goal.y) == pytest.approx((expected.x, expected.y))
    assert goal.theta == pytest.approx(math.atan2(goal.y - 1.0, goal.x - 1.0))
    assert harness.read("/map/coverage").covered.sum() == 0


def test_marks_each_scan_once_with_the_headings_imaged():
    harness = scoring()
    harness.tick()
    first = harness.read("/map/coverage_goal")
    scan = ScanRecord(1, first.x, first.y, tuple(image_headings()[:3]))  # stopped after three images
    harness.write("/map/scan", scan)
    harness.tick()
    covered = harness.read("/map/coverage").covered.copy()
    expected = coverage_grid(ROOM, ROOM.free, robot_radius=0.28).cover(first.x, first.y, scan.headings).covered
    assert np.array_equal(covered, expected)
    harness.tick()  # the same scan again: nothing more
    assert np.array_equal(harness.read("/map/coverage").covered, covered)
    assert report_sections(harness.behaviour)["roadmap"]["search"]["scans"] == 1


def test_fails_when_nothing_worth_a_visit_is_left():
    harness = scoring(min_new=10**9)
    assert harness.tick() == Status.FAILURE
    assert harness.behaviour.feedback_message.startswith("nothing left to cover")


def test_fails_without_a_room_and_waits_for_odometry():
    harness = BehaviourHarness(CoverageScoring())
    assert harness.tick() == Status.FAILURE and harness.behaviour.feedback_message == "no room estimate"
    harness = BehaviourHarness(CoverageScoring(), blackboard={"/map/room": ROOM})
    assert harness.tick() == Status.RUNNING


def test_a_robot_off_the_standable_floor_still_gets_a_goal():
    harness = scoring()
    harness.write("/robot/odometry", Pose2D(0.05, 0.05, 0.0))  # in a corner, where the grid says it cannot stand
    assert harness.tick() == Status.SUCCESS


def test_a_goal_not_followed_by_a_scan_is_not_chosen_again():
    harness = scoring()
    harness.tick()
    first = harness.read("/map/coverage_goal")
    assert harness.tick() == Status.SUCCESS  # asked again without a scan: the robot did not get there
    second = harness.read("/map/coverage_goal")
    assert second.distance_to(first) > 0.3
    assert report_sections(harness.behaviour)["roadmap"]["search"]["unreachable"] == 1
    harness.write("/map/scan", ScanRecord(1, second.x, second.y, tuple(image_headings())))
    harness.tick()  # a scan came: the second goal was reached
    assert report_sections(harness.behaviour)["roadmap"]["search"]["unreachable"] == 1


def test_reports_the_search_and_draws_the_grid_each_time_it_changed():
    harness = scoring()
    node = harness.behaviour
    assert report_sections(node) == {} and list(node.drawings()) == []  # nothing chosen yet
    harness.tick()
    assert report_sections(node) == {"roadmap": {"search": {"positions_chosen": 1, "scans": 0, "unreachable": 0,
                                                            "covered_fraction": 0.0}}}
    (points,) = node.drawings()
    assert points.entity == "roadmap/coverage" and len(points.positions) == harness.read("/map/coverage").valid.sum()
    assert list(node.drawings()) == []  # the same grid: not again
    goal = harness.read("/map/coverage_goal")
    harness.write("/map/scan", ScanRecord(1, goal.x, goal.y, tuple(image_headings())))
    harness.tick()
    grid = harness.read("/map/coverage")
    search = report_sections(node)["roadmap"]["search"]
    assert search == {"positions_chosen": 2, "scans": 1, "unreachable": 0,
                      "covered_fraction": round(grid.fraction_covered, 4)} and search["covered_fraction"] > 0
    assert [d.entity for d in node.drawings()] == ["roadmap/coverage"]  # a new grid: drawn again
