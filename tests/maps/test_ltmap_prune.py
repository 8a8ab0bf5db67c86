"""maps.ltmap.prune: cutting the lowest level, worked out by hand on small trees, and budgets."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from maps.ltmap.arrays import IDS
from maps.ltmap.prune import cut_lowest_level, earliest_sources, follow
from maps.ltmap.tree import LandmarkTree
from tests.maps.ltmap_trees import Rows, same_arrays

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def test_start_and_goal_keep_their_leaf_a_weak_viewframe_goes_and_a_shared_end_merges():
    # root 0; nodes 1, 2, 3 under it; leaves 4 (start), 5, 6, 7 (goal) under 1, 2, 3, 3
    parent = [-1, 0, 0, 0, 1, 2, 3, 3]
    rows = np.array([0, 1, 1, 2, 3, 3, 3, 4, 5, 5, 6, 7, 7])
    cut = cut_lowest_level(parent, [4, 5, 6, 7], rows, min_landmarks=3)
    # start's row 7 moves up to node 1, goal's rows 11-12 to node 3; rows 8-10 (inner leaves) are cut;
    # viewframes 2 and 3 now both end in node 3 (merged); viewframe 1 keeps 2 landmarks < 3 (deleted,
    # and node 2 with its row 3)
    assert cut.landmark_index.tolist() == [0, 1, 2, -1, 3, 4, 5, 6, -1, -1, -1, 7, 8]
    assert cut.viewframe_index.tolist() == [0, -1, 1, 1]
    assert (cut.merged, cut.deleted) == (1, 1)
    assert cut.node_parent == [-1, 0, 0] and cut.viewframe_leaves == [1, 2]  # nodes 0, 1, 3 renumbered
    assert cut.landmark_nodes.tolist() == [0, 1, 1, 2, 2, 2, 1, 2, 2]


def test_viewframes_left_with_the_same_landmarks_are_merged():
    # root 0 (2 rows); empty nodes 1-4 under it; leaves 5-8, one row each
    cut = cut_lowest_level([-1, 0, 0, 0, 0, 1, 2, 3, 4], [5, 6, 7, 8], np.array([0, 0, 5, 6, 7, 8]),
                           min_landmarks=0)
    # viewframes 1 and 2 are left with the root's landmarks only: one viewframe, the earlier
    assert cut.viewframe_index.tolist() == [0, 1, 1, 2] and (cut.merged, cut.deleted) == (1, 0)
    assert cut.node_parent == [-1, 0, 0, 0] and cut.viewframe_leaves == [1, 2, 3]
    assert cut.landmark_index.tolist() == [0, 1, 2, -1, -1, 3] and cut.landmark_nodes.tolist() == [0, 0, 1, 3]


def test_a_root_with_one_child_merges_into_it():
    # root 0, its only child 1, leaves 2 (start) and 3 (goal): after the cut both end in node 1
    cut = cut_lowest_level([-1, 0, 1, 1], [2, 3], np.array([0, 1, 2, 3]), min_landmarks=0)
    assert cut.node_parent == [-1] and cut.viewframe_leaves == [0]  # height 2 -> 0
    assert cut.landmark_nodes.tolist() == [0, 0, 0, 0] and cut.landmark_index.tolist() == [0, 1, 2, 3]
    assert cut.viewframe_index.tolist() == [0, 0] and cut.merged == 1


def test_indices_follow_through_steps():
    assert follow(np.array([0, 2, -1, 1]), np.array([1, -1, 0])).tolist() == [1, 0, -1, -1]


def small_tree(views: int = 5) -> LandmarkTree:
    rows, tree = Rows(np.random.default_rng(7)), LandmarkTree(IDS)
    for _ in range(views):
        last = tree.viewframe(-1).landmarks if tree.viewframe_count else np.zeros(0, dtype=np.int64)
        tracked = last[: len(last) // 2]
        tree.add_viewframe(tracked, rows.make(tree.bearings[tracked]), rows.random(20))
    return tree


def test_a_budget_is_met_by_whole_levels_or_the_map_is_left_as_it_was():
    tree = small_tree()
    before = tree.memory_bytes()
    report = tree.prune_to(before - 1, min_landmarks=0)
    assert report.fits and report.levels_cut >= 1 and tree.memory_bytes() == report.bytes_after < before
    assert report.bytes_before == before and len(report.viewframe_index) == 5
    arrays = tree.to_arrays()
    failed = tree.prune_to(10, min_landmarks=0)
    assert not failed.fits and failed.levels_cut == 0 and failed.smallest_bytes > 10
    assert all(np.array_equal(arrays[k], v) for k, v in tree.to_arrays().items())  # unchanged
    assert failed.landmark_index.tolist() == list(range(tree.landmark_count))


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




def _comb(rng: np.random.Generator) -> LandmarkTree:
    """A random top tree with chains of single-child nodes under its leaves, some nodes empty: the
    shape whose levels are cut several at once."""
    parent, level = [-1], [0]
    for _ in range(int(rng.integers(1, 4))):
        below = []
        for above in level:
            for _ in range(int(rng.integers(1, 3))):
                parent.append(above)
                below.append(len(parent) - 1)
        level = below
    leaves = []
    for top in level:
        for _ in range(int(rng.integers(0, 10))):
            parent.append(top)
            top = len(parent) - 1
        leaves.append(top)
    depth = [0] * len(parent)
    for n in range(1, len(parent)):
        depth[n] = depth[parent[n]] + 1
    deepest = max(depth[leaf] for leaf in leaves)
    for k, leaf in enumerate(leaves):  # every leaf at the same depth
        while depth[leaf] < deepest:
            parent.append(leaf)
            depth.append(depth[leaf] + 1)
            leaf = len(parent) - 1
        leaves[k] = leaf
    size = (rng.random(len(parent)) < rng.random()) * rng.integers(0, 5, size=len(parent))
    bearings = np.zeros((int(size.sum()), 3), np.float32)
    bearings[:, 0] = 1
    return LandmarkTree.from_arrays({"ids": np.arange(len(bearings), dtype=np.int64), "bearings": bearings,
                                     "node_parent": np.array(parent, np.int32), "node_size": size.astype(np.int32),
                                     "viewframe_leaf": np.array(leaves, np.int32)}, kind=IDS)


@SETTINGS
@given(st.integers(0, 2**32 - 1))
def test_levels_cut_at_once_give_what_cutting_them_one_by_one_gives(seed):
    rng = np.random.default_rng(seed)
    tree = _comb(rng)
    min_landmarks, budget = int(rng.integers(0, 12)), int(rng.integers(0, tree.memory_bytes() + 1))
    one_by_one, index, views, cuts = tree.copy(), np.arange(tree.landmark_count), np.arange(tree.viewframe_count), 0
    while one_by_one.memory_bytes() > budget and (step := one_by_one.prune_level(min_landmarks)) is not None:
        index, views, cuts = follow(index, step.landmark_index), follow(views, step.viewframe_index), cuts + 1
    report = tree.prune_to(budget, min_landmarks)
    assert report.fits == (one_by_one.memory_bytes() <= budget)
    if report.fits:
        assert report.levels_cut == cuts and report.bytes_after == one_by_one.memory_bytes()
        assert same_arrays(tree.to_arrays(), one_by_one.to_arrays())
        assert np.array_equal(report.landmark_index, index) and np.array_equal(report.viewframe_index, views)


def test_each_kept_viewframe_comes_from_the_earliest_one_merged_into_it():
    # the first test's cut: viewframe 1 deleted, 2 and 3 merged into new viewframe 1 (the earlier, 2)
    assert earliest_sources(np.array([0, -1, 1, 1])) == [0, 2]
    assert earliest_sources(np.array([0, 0])) == [0] and earliest_sources(np.array([-1, 0, 1])) == [1, 2]


def test_pruning_to_a_budget_carries_each_kept_viewframes_place_and_the_file_arrays_hold_them():
    rows, tree = Rows(np.random.default_rng(7)), LandmarkTree(IDS)
    for view in range(6):
        last = tree.viewframe(-1).landmarks if tree.viewframe_count else np.zeros(0, dtype=np.int64)
        tracked = last[: len(last) // 2]
        tree.add_viewframe(tracked, rows.make(tree.bearings[tracked]), rows.random(20), place=(0.5 * view, 0.0))
    before = tree.memory_bytes()
    assert before == sum(a.nbytes for a in tree.to_arrays().values())  # 8 bytes a place, counted as map content
    report = tree.prune_to(before // 2, min_landmarks=0)
    assert report.fits and tree.has_places
    kept = [min(np.flatnonzero(report.viewframe_index == new)) for new in range(tree.viewframe_count)]
    assert [tree.place(i).tolist() for i in range(tree.viewframe_count)] == [[0.5 * old, 0.0] for old in kept]
    assert tree.to_arrays()["viewframe_place"].shape == (tree.viewframe_count, 2)
    assert LandmarkTree.from_arrays(tree.to_arrays(), kind=IDS).place(-1).tolist() == tree.place(-1).tolist()


def test_a_map_has_a_place_for_every_viewframe_or_for_none():
    rows, tree = Rows(np.random.default_rng(7)), LandmarkTree(IDS)
    tree.add_viewframe(np.zeros(0, dtype=np.int64), rows.make(np.zeros((0, 3))), rows.random(5))
    assert not tree.has_places and tree.place(0) is None and "viewframe_place" not in tree.to_arrays()
    with np.testing.assert_raises(ValueError):
        tree.add_viewframe(np.zeros(0, dtype=np.int64), rows.make(np.zeros((0, 3))), rows.random(5), place=(1.0, 0.0))
