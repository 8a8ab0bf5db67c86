"""LoadMap and PruneMap in isolation: the LT-map from a file onto the blackboard, pruned to a budget."""

from __future__ import annotations

import pytest
from py_trees.common import Status

from behaviours.landmark_tree import LoadMap, PruneMap
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from maps.ltmap.arrays import IDS
from maps.ltmap.file import load_ltmap, save_ltmap
from maps.ltmap.tree import LandmarkTree
from tests.behaviours.routes import taught_map


def test_load_map_puts_the_file_on_the_blackboard_and_fails_on_a_bad_file(tmp_path):
    tree, _ = taught_map()
    good, bad = tmp_path / "good.ltmap", tmp_path / "bad.ltmap"
    save_ltmap(good, tree)
    bad.write_bytes(good.read_bytes()[:-10])
    harness = BehaviourHarness(LoadMap(path=str(good)))
    assert harness.tick() == Status.SUCCESS
    assert harness.read("/map/ltmap").viewframe_count == tree.viewframe_count
    assert report_sections(harness.behaviour)["ltmap"]["bytes"] == tree.memory_bytes()
    failing = BehaviourHarness(LoadMap(path=str(bad)))
    assert failing.tick() == Status.FAILURE and "bad.ltmap" in failing.behaviour.feedback_message
    assert BehaviourHarness(LoadMap(path=str(tmp_path / "none.ltmap"))).tick() == Status.FAILURE


def test_prune_map_to_a_fraction_reports_where_its_viewframes_came_from(tmp_path):
    tree, _ = taught_map()
    harness = BehaviourHarness(PruneMap(fraction=0.6, min_landmarks=5, path=str(tmp_path / "pruned.ltmap")),
                               blackboard={"/map/ltmap": tree})
    assert harness.tick() == Status.SUCCESS
    pruned = harness.read("/map/ltmap")
    section = report_sections(harness.behaviour)["ltmap"]
    assert pruned.memory_bytes() <= 0.6 * tree.memory_bytes() and section["memory_fraction"] <= 0.6
    assert len(section["viewframe_source"]) == pruned.viewframe_count
    assert section["viewframe_source"][0] == 0 and section["viewframe_source"][-1] == tree.viewframe_count - 1
    assert tree.viewframe_count > pruned.viewframe_count  # the input map was not changed in place
    assert load_ltmap(tmp_path / "pruned.ltmap").viewframe_count == pruned.viewframe_count
    # what was asked and what the nearest level cut gave are both said, at the end of the run too
    assert section["memory_fraction_asked"] == pytest.approx(0.6, abs=1e-3)
    assert f"{section['memory_fraction']:.1%} of the map for 60.0% asked" in harness.behaviour.feedback_message
    headline = [f.name for f in harness.behaviour.figures() if f.headline]
    assert headline == ["memory_fraction", "memory_fraction_asked"]


def test_prune_map_fails_when_the_budget_cannot_be_met_and_passes_a_map_without_one():
    tree, _ = taught_map()
    harness = BehaviourHarness(PruneMap(budget=10), blackboard={"/map/ltmap": tree})
    assert harness.tick() == Status.FAILURE and "over the 10 byte budget" in harness.behaviour.feedback_message
    whole = BehaviourHarness(PruneMap(), blackboard={"/map/ltmap": tree})
    assert whole.tick() == Status.SUCCESS and whole.read("/map/ltmap").memory_bytes() == tree.memory_bytes()


def test_load_map_reports_the_file_and_the_maps_shape(tmp_path):
    tree, _ = taught_map()
    path = tmp_path / "route.ltmap"
    save_ltmap(path, tree)
    node = LoadMap(path=str(path))
    assert report_sections(node) == {}  # nothing loaded yet
    BehaviourHarness(node).tick()
    summary = tree.summary()
    assert report_sections(node) == {"ltmap": {
        "map_file": str(path), "landmark_kind": "ids", "viewframes": summary.viewframes,
        "landmarks": summary.landmarks, "nodes": summary.nodes, "height": summary.height,
        "bytes": summary.memory_bytes, "landmarks_per_level": list(summary.landmarks_per_level),
        "threshold": summary.threshold}}


def test_a_map_without_viewframes_is_not_loaded(tmp_path):
    path = tmp_path / "empty.ltmap"
    save_ltmap(path, LandmarkTree(IDS))
    harness = BehaviourHarness(LoadMap(path=str(path)))
    assert harness.tick() == Status.FAILURE and "no viewframes" in harness.behaviour.feedback_message
    assert harness.read("/map/ltmap") is None


def test_prune_map_takes_the_smaller_of_its_budgets_and_fails_without_a_map():
    node = PruneMap(budget=500, fraction=0.5)
    assert node.budget_bytes(2000) == 500 and node.budget_bytes(600) == 300
    assert PruneMap().budget_bytes(2000) is None  # 0 and 1: no limit
    harness = BehaviourHarness(PruneMap(fraction=0.5))
    assert harness.tick() == Status.FAILURE and harness.behaviour.feedback_message == "no LT-map to prune"
    assert report_sections(harness.behaviour) == {}
