"""Helpers for the LT-map tests: random rows with ids of their own, viewframes as id sets, the tree's invariants.

Every row has an id of its own, so ids name rows across pruning and viewframe sets compare as id sets.
"""

from __future__ import annotations

import numpy as np

from maps.ltmap.arrays import IDS
from maps.ltmap.tree import LandmarkSet, LandmarkTree
from perception.synthetic import unit


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
