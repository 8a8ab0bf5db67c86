"""Teaching and map nodes in isolation: LearnRoute around a scripted drive, LoadMap, PruneMap."""

from __future__ import annotations

import numpy as np
import py_trees
import pytest
from py_trees.common import Status

from behaviours.landmark_tree import LoadMap, PruneMap
from behaviours.teach import LearnRoute
from behaviours.testing import BehaviourHarness
from maps.ltmap.file import load_ltmap, save_ltmap
from perception.synthetic_route import observe_route, straight_route
from tests.behaviours.routes import WORLD, taught_map


class Scripted(py_trees.behaviour.Behaviour):
    """A drive that runs for ``ticks`` ticks, then ends with ``result``."""

    def __init__(self, ticks: int, result: Status = Status.SUCCESS) -> None:
        super().__init__(name="drive")
        self.ticks, self.result, self.count = ticks, result, 0

    def update(self) -> Status:
        self.count += 1
        return self.result if self.count >= self.ticks else Status.RUNNING


def teach(harness: BehaviourHarness, poses) -> Status:
    rng = np.random.default_rng(4)
    status = Status.INVALID
    for pose in poses:
        harness.write("/robot/odometry", pose)
        harness.write("/perception/observation", observe_route(WORLD, pose, rng, noise_deg=0.1))
        status = harness.tick()
        harness.clock.advance(0.1)
    return status


def test_learn_route_saves_the_map_when_the_drive_succeeds(tmp_path):
    path = tmp_path / "route.ltmap"
    poses = straight_route(3.0, 0.05)
    node = LearnRoute(name="learn", child=Scripted(len(poses)), path=str(path))
    harness = BehaviourHarness(node)
    assert teach(harness, poses[:-1]) == Status.RUNNING
    assert not path.exists() and harness.read("/map/ltmap").viewframe_count > 3  # on the blackboard meanwhile
    assert teach(harness, poses[-1:]) == Status.SUCCESS
    saved = load_ltmap(path)
    assert saved.viewframe_count == harness.read("/map/ltmap").viewframe_count
    section = node.report_sections()["ltmap"]
    assert section["saved"] and section["viewframes"] == saved.viewframe_count
    times = [entry["time_s"] for entry in section["taught"]]
    assert len(times) == saved.viewframe_count and times == sorted(times) and times[-1] == pytest.approx(6.0)


def test_learn_route_saves_nothing_when_the_drive_fails(tmp_path):
    path = tmp_path / "route.ltmap"
    path.write_bytes(b"the previous file")
    poses = straight_route(1.0, 0.05)
    harness = BehaviourHarness(LearnRoute(name="learn", child=Scripted(len(poses), Status.FAILURE), path=str(path)))
    assert teach(harness, poses) == Status.FAILURE
    assert path.read_bytes() == b"the previous file"


def test_learn_route_without_observations_fails():
    harness = BehaviourHarness(LearnRoute(name="learn", child=Scripted(1)))
    assert harness.tick() == Status.FAILURE
    assert "nothing was observed" in harness.behaviour.feedback_message


def test_learn_route_prunes_online_to_its_budget_and_keeps_the_taught_times():
    poses = straight_route(3.0, 0.05)
    whole = BehaviourHarness(LearnRoute(name="learn", child=Scripted(len(poses))))
    teach(whole, poses)
    budget = whole.read("/map/ltmap").memory_bytes() // 2
    node = LearnRoute(name="learn", child=Scripted(len(poses)), budget=budget, min_landmarks=5)
    harness = BehaviourHarness(node)
    assert teach(harness, poses) == Status.SUCCESS
    tree = harness.read("/map/ltmap")
    section = node.report_sections()["ltmap"]
    assert tree.memory_bytes() <= budget and section["online_prunes"] > 0
    assert len(section["taught"]) == tree.viewframe_count and section["taught"][0]["time_s"] == pytest.approx(0.1)


def test_load_map_puts_the_file_on_the_blackboard_and_fails_on_a_bad_file(tmp_path):
    tree, _ = taught_map()
    good, bad = tmp_path / "good.ltmap", tmp_path / "bad.ltmap"
    save_ltmap(good, tree)
    bad.write_bytes(good.read_bytes()[:-10])
    harness = BehaviourHarness(LoadMap(path=str(good)))
    assert harness.tick() == Status.SUCCESS
    assert harness.read("/map/ltmap").viewframe_count == tree.viewframe_count
    assert harness.behaviour.report_sections()["ltmap"]["bytes"] == tree.memory_bytes()
    failing = BehaviourHarness(LoadMap(path=str(bad)))
    assert failing.tick() == Status.FAILURE and "bad.ltmap" in failing.behaviour.feedback_message
    assert BehaviourHarness(LoadMap(path=str(tmp_path / "none.ltmap"))).tick() == Status.FAILURE


def test_prune_map_to_a_fraction_reports_where_its_viewframes_came_from(tmp_path):
    tree, _ = taught_map()
    harness = BehaviourHarness(PruneMap(fraction=0.6, min_landmarks=5, path=str(tmp_path / "pruned.ltmap")),
                               blackboard={"/map/ltmap": tree})
    assert harness.tick() == Status.SUCCESS
    pruned = harness.read("/map/ltmap")
    section = harness.behaviour.report_sections()["ltmap"]
    assert pruned.memory_bytes() <= 0.6 * tree.memory_bytes() and section["memory_fraction"] <= 0.6
    assert len(section["viewframe_source"]) == pruned.viewframe_count
    assert section["viewframe_source"][0] == 0 and section["viewframe_source"][-1] == tree.viewframe_count - 1
    assert tree.viewframe_count > pruned.viewframe_count  # the input map was not changed in place
    assert load_ltmap(tmp_path / "pruned.ltmap").viewframe_count == pruned.viewframe_count


def test_prune_map_fails_when_the_budget_cannot_be_met_and_passes_a_map_without_one():
    tree, _ = taught_map()
    harness = BehaviourHarness(PruneMap(budget=10), blackboard={"/map/ltmap": tree})
    assert harness.tick() == Status.FAILURE and "over the 10 byte budget" in harness.behaviour.feedback_message
    whole = BehaviourHarness(PruneMap(), blackboard={"/map/ltmap": tree})
    assert whole.tick() == Status.SUCCESS and whole.read("/map/ltmap").memory_bytes() == tree.memory_bytes()
