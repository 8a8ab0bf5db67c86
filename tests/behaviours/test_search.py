"""SearchPattern in isolation: the lying eight on odometry, and the trail found again."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.route import RouteProgress
from behaviours.search import LOOKAHEAD, SearchPattern, lying_eight
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from drivers.interfaces import VelocityCommand
from perception.geometry import Pose2D
from perception.observation import Observation
from tests.behaviours.routes import IdealBase, taught_map

TREE, PLACES = taught_map()
NOTHING = np.zeros((0, 3))


def blind(harness: BehaviourHarness, base: IdealBase):
    """The base moves, the camera sees nothing (the trail is lost)."""
    def step(h: BehaviourHarness, ahead: float = 0.1) -> None:
        if ahead:
            base(h)
        h.write("/perception/observation", Observation(NOTHING, h.clock.now() + ahead, "bearings",
                                                       ids=np.zeros(0, dtype=np.int64)))
    step(harness, 0.0)
    return step


def test_the_eight_is_width_across_and_ends_where_it_started():
    points = lying_eight(1.2)
    assert np.ptp(points[:, 1]) == pytest.approx(1.2, abs=0.01) and np.allclose(points[-1], 0.0)


def test_search_drives_the_eight_and_fails_when_the_trail_stays_lost():
    progress = RouteProgress(1, 3, TREE.viewframe_count, 0.0)
    node = SearchPattern(eights=1, speed=0.2)
    harness = BehaviourHarness(node, blackboard={"/map/ltmap": TREE, "/map/route_progress": progress})
    base = IdealBase(harness, Pose2D(20.0, 20.0, 0.0))  # far from the route: nothing matches
    status = harness.tick_until(between=blind(harness, base), dt=0.05, max_ticks=2000)
    assert status == Status.FAILURE and "not found" in node.feedback_message
    xy = np.array([(p.x, p.y) for p in base.trail])
    assert np.ptp(xy[:, 1]) == pytest.approx(1.2, abs=0.08)  # across the eight: two circles side by side
    assert math.dist(xy[0], xy[-1]) < 0.1  # back where it started
    assert report_sections(node)["ltmap"] == {"recoveries": 1, "recoveries_found": 0}


def test_after_a_detour_the_search_goes_back_onto_its_eight_and_ends_where_it_started():
    # the avoidance takes over for 40 ticks a quarter of the way round (straight on at 0.2 m/s, up to
    # 0.55 m off the eight): driven open loop, the rest of the eight would be moved by as much
    progress = RouteProgress(1, 3, TREE.viewframe_count, 0.0)
    node = SearchPattern(eights=1, speed=0.2)
    harness = BehaviourHarness(node, blackboard={"/map/ltmap": TREE, "/map/route_progress": progress})
    base = IdealBase(harness, Pose2D(20.0, 20.0, 0.0))
    drive = blind(harness, base)
    ticks = 0

    def detoured(h: BehaviourHarness) -> None:
        nonlocal ticks
        ticks += 1
        if 30 <= ticks < 70:  # a detour straight on, whatever the search asks
            h.write("/robot/command", VelocityCommand(0.2, 0.0))
        drive(h)

    status = harness.tick_until(between=detoured, dt=0.05, max_ticks=3000)
    assert status == Status.FAILURE and "not found" in node.feedback_message
    xy = np.array([(p.x, p.y) for p in base.trail])
    eight = lying_eight(1.2, points=720) + [20.0, 20.0]
    off = np.min(np.hypot(*(xy[:, None, :] - eight[None, :, :]).transpose(2, 0, 1)), axis=1)
    assert off.max() > 0.25  # the detour took it off the eight ...
    assert off[70 + 100 :].max() < 0.06  # ... and 100 ticks after it (a turn back, 0.55 m) was back on it
    assert math.dist(xy[0], xy[-1]) < LOOKAHEAD * 1.2  # it ends where it started


class HeldBase(IdealBase):
    """A base the avoidance takes 2 m off the eight at once and holds there: commands are not driven."""

    def __call__(self, harness: BehaviourHarness) -> None:
        self.pose = Pose2D(20.0, 18.0, 0.0)
        self.trail.append(self.pose)
        self.sense(self.dt)


def test_a_search_kept_off_its_eight_ends_when_the_eight_driven_on_time_would_have():
    # one eight 1.2 m across is two circles 0.6 m across: 3.77 m, at 0.2 m/s 18.8 s; the robot's place
    # may lag the eight driven on time by 1.2 m (6 s), then it is moved on: the search ends at 24.8 s
    progress = RouteProgress(1, 3, TREE.viewframe_count, 0.0)
    node = SearchPattern(eights=1, speed=0.2, width=1.2)
    harness = BehaviourHarness(node, blackboard={"/map/ltmap": TREE, "/map/route_progress": progress})
    base = HeldBase(harness, Pose2D(20.0, 20.0, 0.0))  # the eight is laid here, the robot is held 2 m south
    start = harness.clock.now()
    status = harness.tick_until(between=blind(harness, base), dt=0.05, max_ticks=2000)
    assert status == Status.FAILURE and "not found" in node.feedback_message
    assert harness.clock.now() - start == pytest.approx(2 * math.pi * 0.6 / 0.2 + 1.2 / 0.2, abs=0.2)


def test_search_succeeds_where_the_trail_is_found_and_retargets():
    progress = RouteProgress(1, 3, TREE.viewframe_count, 0.0)
    node = SearchPattern(window=2)
    harness = BehaviourHarness(node, blackboard={"/map/ltmap": TREE, "/map/route_progress": progress})
    IdealBase(harness, PLACES[4])  # where viewframe 4 was taught
    assert harness.tick() == Status.SUCCESS
    assert harness.read("/map/route_progress").target in (3, 4, 5)
    assert harness.read("/robot/command").v == 0.0 and node.found_again == 1


class Sighted:
    """The taught map, with only the viewframes ``seen`` matching anything: what a robot sees when
    people and a detour have pushed it back along the route."""

    def __init__(self, seen: set[int]) -> None:
        self.seen = seen

    def __getattr__(self, name: str):
        return getattr(TREE, name)

    def match(self, index: int, observation: Observation):
        matches = TREE.match(index, observation)
        keep = slice(None) if index in self.seen else slice(0)
        return type(matches)(*(getattr(matches, f)[keep] for f in ("ref", "cur", "feature", "landmark", "distance")))


@pytest.mark.parametrize(("behind", "found"), [(0, None), (3, 7), (1, None)])
def test_search_finds_a_viewframe_already_passed_only_within_behind(behind, found):
    # lost on the way to 9 (forward), the robot sees only 6 and 7: ahead (9, 10, 11) first, then 8, 7, 6
    progress = RouteProgress(1, 9, TREE.viewframe_count, 0.0)
    node = SearchPattern(window=2, behind=behind)
    harness = BehaviourHarness(node, blackboard={"/map/ltmap": Sighted({6, 7}), "/map/route_progress": progress})
    IdealBase(harness, PLACES[7])
    status = harness.tick()
    if found is None:
        assert status == Status.RUNNING and harness.read("/map/route_progress").target == 9
    else:
        assert status == Status.SUCCESS and harness.read("/map/route_progress").target == found


def test_search_fails_at_once_when_the_trail_was_lost_too_often_without_the_route_moving_on():
    # searches=2: a third search from the same target fails without driving; one from farther on starts afresh
    progress = RouteProgress(1, 3, TREE.viewframe_count, 0.0)
    node = SearchPattern(searches=2)
    harness = BehaviourHarness(node, blackboard={"/map/ltmap": TREE, "/map/route_progress": progress})
    base = IdealBase(harness, Pose2D(20.0, 20.0, 0.0))  # far from the route: nothing matches
    step = blind(harness, base)
    for _ in range(2):
        assert harness.tick() == Status.RUNNING and harness.read("/robot/command").v > 0.0
        step(harness)
        node.stop(Status.INVALID)  # the recovery node starts the task again: the trail found and lost again
    assert harness.tick() == Status.FAILURE and "lost 3 times" in node.feedback_message
    assert harness.read("/robot/command").v == 0.0
    node.stop(Status.INVALID)
    harness.write("/map/route_progress", progress.retargeted(5, 1.0))  # the route moved on: counting starts again
    assert harness.tick() == Status.RUNNING and harness.read("/robot/command").v > 0.0
