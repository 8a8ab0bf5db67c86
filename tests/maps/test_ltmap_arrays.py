"""maps.ltmap.arrays: the canonical node order, the bytes a map takes, and arrays checked whole."""

from __future__ import annotations

import numpy as np
import pytest

from maps.ltmap.arrays import (
    IDS,
    NODE_BYTES,
    VIEWFRAME_BYTES,
    check_kind,
    checked_arrays,
    data_name,
    empty_data,
    preorder,
)


def arrays(parent, size, leaves, ids=None) -> dict[str, np.ndarray]:
    count = int(np.sum(size))
    bearings = np.tile(np.array([1.0, 0.0, 0.0], dtype=np.float32), (count, 1))
    return {"ids": np.arange(count, dtype=np.int64) if ids is None else ids, "bearings": bearings,
            "node_parent": np.array(parent, dtype=np.int32), "node_size": np.array(size, dtype=np.int32),
            "viewframe_leaf": np.array(leaves, dtype=np.int32)}


def test_preorder_visits_children_in_route_order():
    # viewframe 0 ends in node 4 (under 2), viewframe 1 in node 3 (under 1): node 2's subtree comes first
    parent = np.array([-1, 0, 0, 1, 2])
    assert preorder(parent, np.ones(5, dtype=bool), [4, 3]) == [0, 2, 4, 1, 3]
    assert preorder(parent, np.array([True, True, False, True, False]), [3]) == [0, 1, 3]


def test_bytes_per_node_and_viewframe_and_the_data_of_each_kind():
    assert (NODE_BYTES, VIEWFRAME_BYTES) == (8, 4)  # parent + count (2 x int32); a leaf (int32)
    assert empty_data(IDS).shape == (0,) and empty_data(IDS).dtype == np.int64
    assert empty_data("orb").shape == (0, 32) and empty_data("sift").dtype == np.float32
    assert (data_name(IDS), data_name("brisk")) == ("ids", "descriptors")
    with pytest.raises(ValueError, match="unknown landmark kind 'surf'"):
        check_kind("surf")


def test_consistent_arrays_come_back_as_copies():
    given = arrays([-1, 0, 0], [1, 2, 1], [1, 2])
    checked = checked_arrays(given, IDS)
    assert checked.data.tolist() == [0, 1, 2, 3] and checked.viewframe_leaf.tolist() == [1, 2]
    assert not np.shares_memory(checked.bearings, given["bearings"])


@pytest.mark.parametrize(("change", "message"), [
    ({"node_parent": np.array([-1, 0, 0], dtype=np.int64)}, "node_parent must be a 1-d int32"),
    ({"node_parent": np.array([-1, 2, 0], dtype=np.int32)}, "every parent before its children"),
    ({"node_size": np.array([1, 2, 2], dtype=np.int32)}, "node_size"),
    ({"viewframe_leaf": np.array([1, 1], dtype=np.int32)}, "every leaf node once"),
    ({"bearings": np.zeros((4, 3), dtype=np.float32)}, "finite unit vectors"),
    ({"bearings": np.zeros((3, 3), dtype=np.float32)}, "4 x 3 float32"),
    ({"descriptors": np.zeros((4, 32), dtype=np.uint8)}, "unexpected arrays for a ids map: descriptors"),
])  # fmt: skip
def test_the_first_inconsistency_is_named(change, message):
    with pytest.raises(ValueError, match=message):
        checked_arrays({**arrays([-1, 0, 0], [1, 2, 1], [1, 2]), **change}, IDS)


def test_leaves_at_different_depths_and_missing_arrays_are_refused():
    with pytest.raises(ValueError, match="same depth"):  # leaf 2 at depth 1, leaf 3 at depth 2
        checked_arrays(arrays([-1, 0, 0, 1], [1, 1, 1, 1], [2, 3]), IDS)
    with pytest.raises(ValueError, match="viewframes need nodes"):
        checked_arrays(arrays([], [], [0]), IDS)
    with pytest.raises(ValueError, match="'descriptors' is missing"):
        checked_arrays({k: v for k, v in arrays([-1], [1], [0]).items() if k != "ids"}, "orb")
    with pytest.raises(ValueError, match="orb descriptors must be N x 32 uint8"):
        orb = {k: v for k, v in arrays([-1], [1], [0]).items() if k != "ids"}
        checked_arrays({**orb, "descriptors": np.zeros((1, 64), dtype=np.uint8)}, "orb")
