"""The arrays an LT-map is made of: landmark kinds, dtypes, canonical node order, and their checks.

A map is plain arrays (:meth:`maps.ltmap.tree.LandmarkTree.to_arrays`, what a map file holds
besides its header): ``descriptors`` (N x W) or ``ids`` (N,), ``bearings`` (N x 3 float32),
``node_parent`` and ``node_size`` (M, int32; the root's parent is -1), ``viewframe_leaf``
(V, int32, route order) and, when the teach recorded them, ``viewframe_place`` (V x 2 float32:
where odometry put each viewframe, in the teach's odometry frame, metres). Nodes are in preorder
with children in route order (:func:`preorder`) and landmarks grouped by node, so equal maps give
equal arrays.

- **Memory** (``memory_bytes``) is exactly what these arrays hold: per landmark its descriptor
  row (32 bytes for ORB) or id (8 bytes) and its unit bearing (3 x float32, 12 bytes); per node
  its parent and its landmark count (2 x int32, :data:`NODE_BYTES`); per viewframe its leaf
  (int32, :data:`VIEWFRAME_BYTES`), and its place when the map has places (2 x float32,
  :data:`PLACE_BYTES`). Landmarks are stored grouped by node, so a landmark's node
  costs nothing. Caches and the learner's bookkeeping are not map content.

:func:`checked_arrays` reads them back from a file: a ``ValueError`` naming the first
inconsistency, so a damaged file is one line, never a tree that breaks later.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

IDS = "ids"  # the kind of a map built from the ideal bearings sensor (landmark ids, no descriptors)
DESCRIPTOR_KINDS = {"orb": (32, np.uint8), "brisk": (64, np.uint8), "sift": (128, np.float32)}
BEARING_DTYPE = np.float32
INDEX_DTYPE = np.int32
ID_DTYPE = np.int64
NODE_BYTES = 2 * np.dtype(INDEX_DTYPE).itemsize  # parent + landmark count
VIEWFRAME_BYTES = np.dtype(INDEX_DTYPE).itemsize  # the viewframe's leaf
PLACE_DTYPE = np.float32
PLACE_BYTES = 2 * np.dtype(PLACE_DTYPE).itemsize  # a viewframe's (x, y) in the teach's odometry frame
PLACES = "viewframe_place"
STRUCTURE_ARRAYS = ("bearings", "node_parent", "node_size", "viewframe_leaf")


def check_kind(kind: str) -> None:
    """``ValueError`` unless ``kind`` is :data:`IDS` or a descriptor kind."""
    if kind != IDS and kind not in DESCRIPTOR_KINDS:
        raise ValueError(f"unknown landmark kind {kind!r} (expected {IDS} or one of {', '.join(DESCRIPTOR_KINDS)})")


def data_name(kind: str) -> str:
    """The name of the array holding a map's landmark data: ``ids`` or ``descriptors``."""
    return IDS if kind == IDS else "descriptors"


def empty_data(kind: str) -> np.ndarray:
    """No landmark data of ``kind``: ids (0,) or descriptor rows (0 x W) of the kind's dtype."""
    if kind == IDS:
        return np.zeros(0, dtype=ID_DTYPE)
    width, dtype = DESCRIPTOR_KINDS[kind]
    return np.zeros((0, width), dtype=dtype)


def readonly(array: np.ndarray) -> np.ndarray:
    """A view of ``array`` that cannot be written (what the map hands out of its storage)."""
    view = array.view()
    view.flags.writeable = False
    return view


def preorder(parent: np.ndarray, alive: np.ndarray, ends: Sequence[int]) -> list[int]:
    """The alive nodes in preorder, children ordered by the first viewframe below them (``ends``:
    each viewframe's last node): the canonical node order of a map's arrays. Linear in the nodes
    (the first viewframe below a node is carried up from the leaves in one pass)."""
    up = np.asarray(parent).tolist()
    below = [len(ends)] * len(up)
    for k in range(len(ends) - 1, -1, -1):
        below[ends[k]] = k
    for n in reversed(top_down(up)):  # children before their parents
        if up[n] >= 0 and below[n] < below[up[n]]:
            below[up[n]] = below[n]
    children: dict[int, list[int]] = {}
    roots: list[int] = []
    for n in np.flatnonzero(alive).tolist():
        (roots if up[n] < 0 else children.setdefault(up[n], [])).append(n)
    order: list[int] = []
    stack = sorted(roots, key=lambda n: -below[n])
    while stack:
        node = stack.pop()
        order.append(node)
        stack.extend(sorted(children.get(node, ()), key=lambda c: -below[c]))
    return order


def top_down(parent: Sequence[int] | np.ndarray) -> list[int]:
    """Every node, each after its parent (the learner adds a new root after the old one, so the
    numbering need not be such an order): one pass over the nodes, whatever the tree's height."""
    children: list[list[int]] = [[] for _ in range(len(parent))]
    roots: list[int] = []
    for n, p in enumerate(np.asarray(parent).tolist()):
        (roots if p < 0 else children[p]).append(n)
    order, stack = [], roots[::-1]
    while stack:
        n = stack.pop()
        order.append(n)
        stack.extend(children[n])
    return order


@dataclass(frozen=True, slots=True, eq=False)
class MapArrays:
    """A map's arrays after :func:`checked_arrays`: consistent, and copies of what was given."""

    data: np.ndarray
    bearings: np.ndarray
    node_parent: np.ndarray
    node_size: np.ndarray
    viewframe_leaf: np.ndarray
    viewframe_place: np.ndarray | None = None


def checked_arrays(arrays: Mapping[str, np.ndarray], kind: str) -> MapArrays:
    """The arrays of a ``kind`` map, checked whole; ``ValueError`` naming the first inconsistency."""
    unknown = sorted(set(arrays) - {data_name(kind), *STRUCTURE_ARRAYS, PLACES})
    if unknown:
        raise ValueError(f"unexpected arrays for a {kind} map: {', '.join(unknown)}")
    data = _checked_data(arrays, kind)
    bearings = _checked_bearings(arrays, len(data))
    parent, size, leaves = _checked_structure(arrays, len(data))
    return MapArrays(data, bearings, parent, size, leaves, _checked_places(arrays, len(leaves)))


def _checked_places(arrays: Mapping[str, np.ndarray], count: int) -> np.ndarray | None:
    if PLACES not in arrays:
        return None  # a map taught without odometry, or written before places were kept
    places = np.asarray(arrays[PLACES])
    if places.shape != (count, 2) or places.dtype != PLACE_DTYPE or not np.all(np.isfinite(places)):
        raise ValueError(f"viewframe_place must be {count} x 2 finite float32 (one per viewframe), got "
                         f"{places.dtype} {places.shape}")
    return places.copy()


def _checked_data(arrays: Mapping[str, np.ndarray], kind: str) -> np.ndarray:
    if kind == IDS:
        ids = _required(arrays, IDS)
        if ids.ndim != 1 or ids.dtype != ID_DTYPE:
            raise ValueError(f"ids must be a 1-d int64 array, got {ids.dtype} {ids.shape}")
        return ids.copy()
    descriptors = _required(arrays, "descriptors")
    width, dtype = DESCRIPTOR_KINDS[kind]
    if descriptors.ndim != 2 or descriptors.shape[1] != width or descriptors.dtype != dtype:
        raise ValueError(f"{kind} descriptors must be N x {width} {np.dtype(dtype)}, got {descriptors.dtype} "
                         f"{descriptors.shape}")
    return np.ascontiguousarray(descriptors).copy()


def _checked_bearings(arrays: Mapping[str, np.ndarray], count: int) -> np.ndarray:
    bearings = _required(arrays, "bearings")
    if bearings.shape != (count, 3) or bearings.dtype != BEARING_DTYPE:
        raise ValueError(f"bearings must be {count} x 3 float32 (one per landmark), got {bearings.dtype} "
                         f"{bearings.shape}")
    if not np.all(np.isfinite(bearings)) or np.any(np.abs(np.linalg.norm(bearings, axis=1) - 1.0) > 1e-3):
        raise ValueError("bearings must be finite unit vectors")
    return bearings.copy()


def _checked_structure(arrays: Mapping[str, np.ndarray], count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    parent, size, leaves = (_required(arrays, name) for name in ("node_parent", "node_size", "viewframe_leaf"))
    for name, array in (("node_parent", parent), ("node_size", size), ("viewframe_leaf", leaves)):
        if array.ndim != 1 or array.dtype != INDEX_DTYPE:
            raise ValueError(f"{name} must be a 1-d int32 array, got {array.dtype} {array.shape}")
    if len(size) != len(parent) or np.any(size < 0) or int(size.sum(dtype=np.int64)) != count:
        raise ValueError("node_size must give each node's landmark count (one per node, summing to the landmarks)")
    if len(parent) == 0:
        if len(leaves):
            raise ValueError("viewframes need nodes")
        return parent, size, leaves
    if parent[0] != -1 or np.any(parent[1:] < 0) or np.any(parent[1:] >= np.arange(1, len(parent))):
        raise ValueError("node_parent must list the root first and every parent before its children")
    _check_leaves(parent, leaves)
    return parent, size, leaves


def _check_leaves(parent: np.ndarray, leaves: np.ndarray) -> None:
    has_child = np.zeros(len(parent), dtype=bool)
    has_child[parent[1:]] = True
    actual = np.flatnonzero(~has_child)
    if len(np.unique(leaves)) != len(leaves) or not np.array_equal(np.sort(leaves), actual):
        raise ValueError("viewframe_leaf must name every leaf node once")
    depth = np.zeros(len(parent), dtype=np.int64)
    for n in range(1, len(parent)):
        depth[n] = depth[parent[n]] + 1
    if len(np.unique(depth[actual])) > 1:
        raise ValueError("every leaf must be at the same depth")


def _required(arrays: Mapping[str, np.ndarray], name: str) -> np.ndarray:
    if name not in arrays:
        raise ValueError(f"the array {name!r} is missing")
    return np.asarray(arrays[name])
