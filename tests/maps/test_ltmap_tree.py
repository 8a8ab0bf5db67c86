"""maps.ltmap.tree: the tree's invariants across random learn/prune sequences (hypothesis), and its rules.

The random trees are built with :meth:`LandmarkTree.add_viewframe` directly (ids kind), every row
with an id of its own, so ids name rows across pruning and viewframe sets compare as id sets.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from maps.ltmap.arrays import IDS
from maps.ltmap.file import decode_ltmap, encode_ltmap
from maps.ltmap.tree import LandmarkTree, attach_level
from perception.similarity import bearing_angles
from perception.synthetic import unit
from tests.maps.ltmap_trees import Rows, all_sets, check_invariants, id_set, same_arrays

SHARE = 0.05  # rad: the gate of the random sequences
SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def add_step(tree: LandmarkTree, rows: Rows, data: st.DataObject) -> None:
    rng = rows.rng
    before_sets, before_count = all_sets(tree), tree.landmark_count
    tracked = np.zeros(0, dtype=np.int64)
    if tree.viewframe_count:
        last = tree.viewframe(-1).landmarks
        tracked = last[rng.random(len(last)) < data.draw(st.floats(0.0, 1.0), label="tracked fraction")]
    turn = data.draw(st.sampled_from([0.0, 0.02, 0.5]), label="sighting noise (rad)")
    sightings = rows.make(unit(tree.bearings[tracked] + rng.normal(0.0, turn, (len(tracked), 3))))
    new = rows.random(data.draw(st.integers(0, 25), label="new"))
    index = tree.add_viewframe(tracked, sightings, new, share_angle=SHARE)

    assert index == tree.viewframe_count - 1 == len(before_sets)
    assert all_sets(tree)[:-1] == before_sets, "earlier viewframes keep exactly their landmarks"
    appended = np.arange(before_count, tree.landmark_count)
    assert np.array_equal(tree.node_landmarks(tree.viewframe_leaves[-1]), appended), "only new rows in the new leaf"
    turned = bearing_angles(tree.bearings[tracked], sightings.bearings) > SHARE
    now = id_set(tree, -1)
    not_shared = np.array([int(tree.ids[t]) not in now for t in tracked], dtype=bool)
    assert len(appended) == len(new) + np.count_nonzero(turned | not_shared), "a tracked landmark is shared or stored"
    assert frozenset(new.ids.tolist()) <= now


def prune_step(tree: LandmarkTree, data: st.DataObject) -> None:
    minimum = data.draw(st.integers(0, 30), label="min landmarks")
    before_sets, before_bytes, before_height = all_sets(tree), tree.memory_bytes(), tree.height
    before_ids, before_arrays = tree.ids.copy(), tree.to_arrays()
    step = tree.prune_level(minimum)
    if before_height == 0:
        assert step is None and same_arrays(tree.to_arrays(), before_arrays)
        return
    sets = all_sets(tree)
    assert tree.memory_bytes() < before_bytes and step.bytes_after == tree.memory_bytes()
    assert tree.height < before_height
    assert before_sets[0] <= sets[0] and before_sets[-1] <= sets[-1], "start and goal keep their landmarks"
    ends = before_sets[0] | before_sets[-1]  # start and goal merged into one viewframe keep both
    assert all(any(s <= old for old in before_sets) or s <= ends for s in sets), "pruning adds no landmark"
    assert all(len(s) >= minimum for s in sets[1:-1]), "weak viewframes are deleted"
    assert len(set(sets)) == len(sets), "identical viewframes are merged"
    kept = step.landmark_index >= 0
    assert np.array_equal(tree.ids[step.landmark_index[kept]], before_ids[kept])
    assert np.count_nonzero(kept) == tree.landmark_count
    check_viewframe_index(step.viewframe_index, before_sets, tree)


def check_viewframe_index(index: np.ndarray, before_sets: list[frozenset[int]], tree: LandmarkTree) -> None:
    """Every old viewframe maps to the one it became (its surviving landmarks are there) or to -1."""
    sets, surviving = all_sets(tree), frozenset(tree.ids.tolist())
    assert len(index) == len(before_sets) and index[0] == 0, "the start stays the start"
    assert set(index[index >= 0].tolist()) == set(range(len(sets))), "every new viewframe comes from an old one"
    for old, new in enumerate(index.tolist()):
        assert new < 0 or before_sets[old] & surviving <= sets[new]


def budget_step(tree: LandmarkTree, data: st.DataObject) -> None:
    budget = int(tree.memory_bytes() * data.draw(st.floats(0.0, 1.2), label="budget fraction"))
    before, before_sets = tree.to_arrays(), all_sets(tree)
    report = tree.prune_to(budget, data.draw(st.integers(0, 30), label="min landmarks"))
    if report.fits:
        assert tree.memory_bytes() <= budget and report.bytes_after == tree.memory_bytes()
        check_viewframe_index(report.viewframe_index, before_sets, tree)
    else:
        assert same_arrays(tree.to_arrays(), before), "a budget it cannot meet leaves the map as it was"
        assert report.smallest_bytes > budget and report.bytes_after == report.bytes_before


@SETTINGS
@given(st.data(), st.integers(0, 2**32 - 1))
def test_invariants_hold_across_random_learn_and_prune_sequences(data, seed):
    tree, rows = LandmarkTree(IDS), Rows(np.random.default_rng(seed))
    operations = data.draw(st.lists(st.sampled_from(["add"] * 5 + ["prune", "budget"]), min_size=6, max_size=24))
    for operation in ["add", *operations]:
        if operation == "add":
            add_step(tree, rows, data)
        elif operation == "prune":
            prune_step(tree, data)
        else:
            budget_step(tree, data)
        check_invariants(tree)
    decoded = decode_ltmap(encode_ltmap(tree), file="route.ltmap")
    assert same_arrays(decoded.to_arrays(), tree.to_arrays()) and decoded.threshold == tree.threshold


def test_the_branch_leaves_where_the_fewest_landmarks_go_wrong():
    # nothing lost above the leaf: the new viewframe is the last one's sibling (tracked move one level up)
    assert attach_level(lost=[0, 0, 5], tracked=[9, 4, 7], leaves=[6, 1, 1]) == 2
    # the root's landmarks are mostly lost: a new root, the tracked few go up with the old root's
    assert attach_level(lost=[10, 0], tracked=[0, 3], leaves=[5, 1]) == 0
    # a run that started at the last viewframe: the leaf's tracked landmarks join it exactly
    assert attach_level(lost=[0, 2, 0], tracked=[0, 0, 4], leaves=[5, 1, 1]) == 2
    # moving the leaf's 8 tracked landmarks under a node of 4 viewframes would be wrong in 3 of them:
    # closing that node costs its 2 lost landmarks, storing them again would cost 8
    assert attach_level(lost=[0, 2, 0], tracked=[0, 0, 8], leaves=[9, 4, 1]) == 1
    assert attach_level(lost=[0, 0], tracked=[0, 0], leaves=[3, 1]) == 1  # ties: the deepest


def test_only_bearings_within_the_share_angle_are_shared():
    rows = Rows(np.random.default_rng(3))
    tree = LandmarkTree(IDS)
    tree.add_viewframe([], rows.make(np.empty((0, 3))), rows.random(10))
    turned = Rotation.from_euler("z", 0.3).apply(tree.bearings[[0]])  # one landmark now seen 0.3 rad away
    sightings = rows.make(np.vstack((turned, tree.bearings[[1]])))
    tree.add_viewframe([0, 1], sightings, rows.make(np.empty((0, 3))), share_angle=0.1)
    shared, stored = id_set(tree, 1), tree.ids[tree.node_landmarks(tree.viewframe_leaves[1])]
    assert 1 in shared and 0 not in shared and list(stored) == [int(sightings.ids[0])]
    assert bearing_angles(tree.bearings[[-1]], turned)[0] < 1e-6  # stored with its bearing now


def test_bad_updates_are_refused():
    rows = Rows(np.random.default_rng(0))
    tree = LandmarkTree(IDS)
    with pytest.raises(ValueError, match="empty"):
        tree.add_viewframe([0], rows.random(1), rows.random(3))
    tree.add_viewframe([], rows.make(np.empty((0, 3))), rows.random(3))
    with pytest.raises(ValueError, match="last viewframe"):
        tree.add_viewframe([7], rows.random(1), rows.random(0))
    with pytest.raises(ValueError, match="distinct"):
        tree.add_viewframe([1, 1], rows.random(2), rows.random(0))
    with pytest.raises(ValueError, match="descriptors"):
        LandmarkTree("orb").add_viewframe([], rows.random(0), rows.random(2))
    with pytest.raises(ValueError, match="kind"):
        LandmarkTree("surf")
