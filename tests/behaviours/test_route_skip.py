"""SkipViewframes: past viewframes taught where something now stands; a lost trail is the search's."""

from __future__ import annotations

import numpy as np
from py_trees.common import Status

from behaviours.route import RouteProgress
from behaviours.route_skip import SkipViewframes
from behaviours.telemetry import Event, report_sections
from behaviours.testing import BehaviourHarness
from perception.observation import Observation
from tests.behaviours.routes import IdealBase, taught_map

TREE, PLACES = taught_map()


def harness(target: int, **ports: object) -> tuple[SkipViewframes, BehaviourHarness]:
    node = SkipViewframes(**ports)
    progress = RouteProgress(1, target, TREE.viewframe_count, 0.0)
    return node, BehaviourHarness(node, blackboard={"/map/ltmap": TREE, "/map/route_progress": progress})


def test_beside_the_target_the_route_moves_on_to_the_farthest_viewframe_in_view():
    node, h = harness(3, window=3)
    IdealBase(h, PLACES[4])  # between the target and the next ones: all of them in view
    assert h.tick() == Status.SUCCESS
    progress = h.read("/map/route_progress")
    assert progress.target == 6 and node.feedback_message == "viewframe 3 cannot be reached: on to viewframe 6"
    assert report_sections(node)["ltmap"]["skips"] == [{"from": 3, "to": 6, "time_s": 0.0}]
    assert list(node.drawings()) == [Event("route/events", "viewframe 3 cannot be reached: skipped to 6")]


def test_a_lost_trail_is_the_searchs_job():
    node, h = harness(3)
    nothing = Observation(np.zeros((0, 3)), 0.0, "bearings", ids=np.zeros(0, dtype=np.int64))
    h.write("/perception/observation", nothing)
    assert h.tick() == Status.FAILURE
    assert node.feedback_message == "none of the 5 viewframes past 3 is in view: the trail is lost"
    assert h.read("/map/route_progress").target == 3


def test_the_window_ends_at_the_routes_last_viewframe():
    last = TREE.viewframe_count - 1
    node, h = harness(last - 1, window=10)
    IdealBase(h, PLACES[last])
    assert h.tick() == Status.SUCCESS and h.read("/map/route_progress").target == last
