"""maps.ltmap.matching: a viewframe's stack (one row per id, the deepest), matching it, and the cache."""

from __future__ import annotations

import numpy as np
import pytest

from maps.ltmap.arrays import IDS
from maps.ltmap.matching import ViewframeCache, match_viewframe, stack_viewframe
from maps.ltmap.tree import LandmarkTree
from perception.observation import Observation
from tests.maps.ltmap_trees import Rows

BEARINGS = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]], dtype=np.float32)


def test_of_two_rows_with_one_id_the_stack_keeps_the_deepest():
    # map rows 0..3 with ids 5, 5, 9, 7; the branch holds rows 0, 1, 2 (row 1 is the leaf's copy of id 5)
    ids = np.array([5, 5, 9, 7], dtype=np.int64)
    stack = stack_viewframe(3, IDS, np.array([0, 1, 2]), BEARINGS, ids, depth=np.array([0, 2, 1]))
    assert stack.index == 3 and len(stack) == 2
    assert stack.ids.tolist() == [5, 9] and stack.landmarks.tolist() == [1, 2]  # sorted by id, the deepest 5
    assert stack.bearings.dtype == np.float64 and np.array_equal(stack.bearings, BEARINGS[[1, 2]])
    assert stack.descriptors is None and stack.matchable is None
    with pytest.raises(ValueError):
        stack.bearings[0, 0] = 2.0  # the stack is read-only: the cache hands out the same arrays
    with pytest.raises(ValueError, match="depth"):
        stack_viewframe(0, IDS, np.array([0, 1]), BEARINGS, ids)


def test_descriptor_stacks_keep_every_copy():
    descriptors = np.arange(4 * 32, dtype=np.uint8).reshape(4, 32)
    descriptors[1] = descriptors[0]  # a landmark stored twice: the ratio test will drop the pair
    stack = stack_viewframe(0, "orb", np.array([0, 1, 3]), BEARINGS, descriptors)
    assert stack.landmarks.tolist() == [0, 1, 3] and stack.ids is None
    assert np.array_equal(stack.descriptors, descriptors[[0, 1, 3]]) and stack.matchable is not None


def test_matching_by_ids_pairs_equal_ids_and_refuses_descriptors():
    ids = np.array([5, 9, 7], dtype=np.int64)
    stack = stack_viewframe(0, IDS, np.array([0, 1, 2]), BEARINGS, ids, depth=np.zeros(3, dtype=np.int64))
    cur = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    seen = Observation(cur, 0.0, "bearings", ids=np.array([9, 5, 4], dtype=np.int64))
    matches = match_viewframe(stack, seen, cur, kind=IDS)
    assert stack.ids[matches.landmark].tolist() == [5, 9] and matches.feature.tolist() == [1, 0]
    assert np.array_equal(matches.ref, stack.bearings[matches.landmark]) and np.array_equal(matches.cur, cur[[1, 0]])
    with pytest.raises(ValueError, match="landmark ids; the observation has descriptors"):
        match_viewframe(stack, Observation(cur, 0.0, "cam"), cur, kind=IDS)


def test_the_cache_builds_each_stack_once_until_cleared():
    built: list[int] = []
    ids = np.array([5, 9, 7], dtype=np.int64)

    def build(index: int):
        built.append(index)
        return stack_viewframe(index, IDS, np.array([0, 1]), BEARINGS, ids, depth=np.zeros(2, dtype=np.int64))

    cache = ViewframeCache()
    first = cache.get(2, build)
    assert cache.get(2, build) is first and built == [2]
    cache.clear()
    assert cache.get(2, build) is not first and built == [2, 2]


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


