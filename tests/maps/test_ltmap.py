"""LT-map tree: its invariants across random learn/prune sequences (hypothesis), and its rules.

The random trees are built with :meth:`LandmarkTree.add_viewframe` directly (ids kind), every row
with an id of its own, so ids name rows across pruning and viewframe sets compare as id sets.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from maps.ltmap.file import decode_ltmap, encode_ltmap
from maps.ltmap.tree import IDS, LandmarkSet, LandmarkTree, attach_level, compensate
from perception.observation import Observation
from perception.similarity import bearing_angles
from perception.synthetic import unit

SHARE = 0.05  # rad: the gate of the random sequences
SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


class Rows:
    """Fresh ids and random unit bearings for new rows."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng, self.next_id = rng, 0

    def make(self, bearings: np.ndarray) -> LandmarkSet:
        ids = np.arange(self.next_id, self.next_id + len(bearings), dtype=np.int64)
        self.next_id += len(bearings)
        return LandmarkSet(np.asarray(bearings, dtype=np.float64).reshape(-1, 3), ids=ids)

    def random(self, count: int) -> LandmarkSet:
        return self.make(unit(self.rng.normal(size=(count, 3))))


def id_set(tree: LandmarkTree, index: int) -> frozenset[int]:
    return frozenset(tree.ids[tree.viewframe(index).landmarks].tolist())


def all_sets(tree: LandmarkTree) -> list[frozenset[int]]:
    return [id_set(tree, i) for i in range(tree.viewframe_count)]


def same_arrays(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) and a[k].dtype == b[k].dtype for k in a)


def check_invariants(tree: LandmarkTree) -> None:
    nodes, views = tree.node_count, tree.viewframe_count
    stored = np.concatenate([tree.node_landmarks(n) for n in range(nodes)] or [np.zeros(0, int)])
    assert np.array_equal(np.sort(stored), np.arange(tree.landmark_count)), "each landmark in exactly one node"
    assert len(np.unique(tree.ids)) == tree.landmark_count  # no row was duplicated
    branches = [tree.branch_nodes(i) for i in range(views)]
    assert set().union(*branches) == set(range(nodes)), "every node lies on some viewframe's branch"
    parents = set(tree.node_parents) - {-1}
    assert set(tree.viewframe_leaves) == set(range(nodes)) - parents and len(set(tree.viewframe_leaves)) == views
    assert {int(tree.depths()[leaf]) for leaf in tree.viewframe_leaves} <= {tree.height}
    for i, branch in enumerate(branches):
        union = np.concatenate([tree.node_landmarks(n) for n in branch])
        assert id_set(tree, i) == frozenset(tree.ids[union].tolist()), "viewframe = union along its branch"
        fresh = tree.viewframe(i, cached=False)  # the cache holds what a rebuild gives
        assert np.array_equal(tree.viewframe(i).landmarks, fresh.landmarks)
        assert np.array_equal(tree.viewframe(i).bearings, fresh.bearings)
    arrays = tree.to_arrays()
    assert tree.memory_bytes() == sum(a.nbytes for a in arrays.values())
    twin = LandmarkTree.from_arrays(arrays, kind=IDS, threshold=tree.threshold)
    assert same_arrays(twin.to_arrays(), arrays) and all_sets(twin) == all_sets(tree)


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


@SETTINGS
@given(st.integers(0, 2**32 - 1), st.integers(1, 12))
def test_memory_never_grows_under_pruning_and_reaches_height_zero(seed, views):
    rng = np.random.default_rng(seed)
    tree, rows = LandmarkTree(IDS), Rows(rng)
    for _ in range(views):
        last = tree.viewframe(-1).landmarks if tree.viewframe_count else np.zeros(0, dtype=np.int64)
        tracked = last[rng.random(len(last)) < 0.6]
        tree.add_viewframe(tracked, rows.make(tree.bearings[tracked]), rows.random(int(rng.integers(0, 40))))
    sizes = [tree.memory_bytes()]
    while tree.prune_level(int(rng.integers(0, 40))) is not None:
        sizes.append(tree.memory_bytes())
    assert all(a > b for a, b in zip(sizes, sizes[1:], strict=False))
    assert tree.height == 0 and len(sizes) - 1 <= views


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
    turned = compensate(tree.bearings[[0]], 0.3)  # one landmark now seen 0.3 rad away from its stored bearing
    sightings = rows.make(np.vstack((turned, tree.bearings[[1]])))
    tree.add_viewframe([0, 1], sightings, rows.make(np.empty((0, 3))), share_angle=0.1)
    shared, stored = id_set(tree, 1), tree.ids[tree.node_landmarks(tree.viewframe_leaves[1])]
    assert 1 in shared and 0 not in shared and list(stored) == [int(sightings.ids[0])]
    assert bearing_angles(tree.bearings[[-1]], turned)[0] < 1e-6  # stored with its bearing now


def test_matching_uses_the_cached_stack_until_the_map_changes():
    rows = Rows(np.random.default_rng(5))
    tree = LandmarkTree(IDS)
    first = rows.random(60)
    tree.add_viewframe([], rows.make(np.empty((0, 3))), first)
    observation = Observation(first.bearings[::2][:, [1, 0, 2]], 0.0, "bearings", ids=first.ids[::2])
    matched = tree.match(0, observation)
    assert np.array_equal(tree.viewframe(0).ids[matched.landmark], first.ids[::2])
    assert np.allclose(matched.ref, first.bearings[::2], atol=1e-6)
    assert np.array_equal(matched.cur, observation.bearings)
    assert tree.viewframe(0) is tree.viewframe(0)  # built once
    stack = tree.viewframe(0)
    tree.add_viewframe(tree.viewframe(0).landmarks[:10], rows.make(tree.bearings[:10]), rows.random(5))
    assert tree.viewframe(0) is not stack  # a change invalidates
    with pytest.raises(ValueError, match="ids"):
        tree.match(0, Observation(first.bearings, 0.0, "cam"))


def test_compensation_turns_body_bearings_into_the_route_frame():
    ahead = np.array([[1.0, 0.0, 0.0]])
    assert np.allclose(compensate(ahead, np.pi / 2), [[0.0, 1.0, 0.0]])  # facing +y, "ahead" is +y


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
