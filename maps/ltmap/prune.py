"""Pruning an LT-map to a memory budget: cut its lowest level, again until it fits (the paper's Table I).

Pure structure: :func:`cut_lowest_level` works on a tree's arrays (node parents, viewframe
leaves, each landmark's node) and says what is left; :meth:`maps.ltmap.tree.LandmarkTree.prune_level`
applies it and reports a :class:`PruneStep`, ``prune_to`` repeats it into a :class:`PruneReport`.

- **Cutting a level.** The lowest level (every leaf) is cut: the first and the last viewframe
  (start and goal) shift their leaf's landmarks into the parent, every other leaf's landmarks
  are deleted; viewframes that now end in the same node are one viewframe (the earliest keeps
  its place in the route).
- **Weak and identical viewframes.** Viewframes left with fewer than ``min_landmarks`` (50, the
  paper's minimum for homing) are deleted, except the first and the last (the route must keep
  its start and goal), and with them every node no viewframe passes through; viewframes whose
  landmark sets became identical (they differ only by empty nodes) are merged.
- **Compression.** A root with a single child is merged into it, which lowers the height again.
- **Budget.** ``prune_to(budget)`` cuts levels until the map fits, or reports that it cannot and
  leaves the map as it was.
- **Indices.** Surviving landmarks keep their order; a prune reports the new index of every old
  landmark and viewframe, so callers holding indices (the learner) can follow.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from maps.ltmap.arrays import preorder

DEFAULT_MIN_LANDMARKS = 50  # the paper's minimum for homing: smaller viewframes are pruned away


@dataclass(frozen=True, slots=True, eq=False)
class PruneStep:
    """One level cut by :meth:`LandmarkTree.prune_level`; ``landmark_index[i]`` is the new index of
    old landmark ``i`` (-1: deleted), ``viewframe_index[v]`` the new index of old viewframe ``v``
    (merged ones: the viewframe they merged into; -1: deleted)."""

    height_before: int
    height_after: int
    bytes_before: int
    bytes_after: int
    landmarks_removed: int
    viewframes_merged: int
    viewframes_deleted: int
    landmark_index: np.ndarray
    viewframe_index: np.ndarray


@dataclass(frozen=True, slots=True, eq=False)
class PruneReport:
    """What :meth:`LandmarkTree.prune_to` did. ``fits`` False: even height 0 exceeds the budget and
    the map was left unchanged (``smallest_bytes`` is what it would have reached)."""

    budget_bytes: int
    fits: bool
    bytes_before: int
    bytes_after: int
    smallest_bytes: int
    steps: tuple[PruneStep, ...]
    landmark_index: np.ndarray
    viewframe_index: np.ndarray

    @property
    def levels_cut(self) -> int:
        return len(self.steps) if self.fits else 0


@dataclass(frozen=True, slots=True, eq=False)
class LevelCut:
    """A tree's structure after its lowest level was cut (:func:`cut_lowest_level`).

    ``node_parent`` and ``viewframe_leaves``: the new nodes (canonical preorder) and viewframes;
    ``keep``: per old landmark whether it survived; ``landmark_nodes``: the new node of each
    survivor (in their old order); ``landmark_index`` and ``viewframe_index`` as in
    :class:`PruneStep`; ``merged`` and ``deleted``: viewframes merged into another, and deleted
    for having fewer than the minimum of landmarks.
    """

    node_parent: list[int]
    viewframe_leaves: list[int]
    keep: np.ndarray
    landmark_nodes: np.ndarray
    landmark_index: np.ndarray
    viewframe_index: np.ndarray
    merged: int
    deleted: int


def cut_lowest_level(node_parent: Sequence[int], viewframe_leaves: Sequence[int], landmark_nodes: np.ndarray,
                     min_landmarks: int) -> LevelCut:
    """Cut the leaves of a tree of height >= 1 (see the module doc): what is left of it."""
    parent = np.array(node_parent, dtype=np.int64)
    leaves = list(viewframe_leaves)
    node = np.array(landmark_nodes, dtype=np.int64)
    for terminal in {leaves[0], leaves[-1]}:  # start and goal keep their landmarks
        node[node == terminal] = parent[terminal]
    keep = ~np.isin(node, leaves)
    old_ends = [int(parent[leaf]) for leaf in leaves]
    ends = list(dict.fromkeys(old_ends))  # same end: one viewframe
    merged = len(leaves) - len(ends)
    counts = np.bincount(node[keep], minlength=len(parent))
    sizes = _branch_sizes(parent, counts, ends)
    weak = {k for k in range(1, len(ends) - 1) if sizes[k] < min_landmarks}
    candidates = [e for k, e in enumerate(ends) if k not in weak]
    ends, identical = _merge_identical(parent, counts, candidates)
    viewframes = _viewframe_index(parent, counts, old_ends, candidates, ends)
    return _restructure(parent, node, keep, ends, viewframes, merged + identical, len(weak))


def follow(index: np.ndarray, step_index: np.ndarray) -> np.ndarray:
    """Indices (-1: gone) carried through one more prune step whose ``step_index`` maps old to new."""
    return np.where(index >= 0, step_index[np.maximum(index, 0)], -1)


def _restructure(parent: np.ndarray, node: np.ndarray, keep: np.ndarray, ends: list[int], viewframes: np.ndarray,
                 merged: int, deleted: int) -> LevelCut:
    """Keep the nodes some viewframe passes through, merge a single-child root, renumber the
    nodes canonically; landmarks keep their order."""
    alive = np.zeros(len(parent), dtype=bool)
    for end in ends:
        n = end
        while n >= 0 and not alive[n]:
            alive[n] = True
            n = parent[n]
    keep = keep & alive[node]
    root = int(np.flatnonzero(alive & (parent < 0))[0])
    while np.count_nonzero(alive & (parent == root)) == 1:  # a root with one child merges into it
        child = int(np.flatnonzero(alive & (parent == root))[0])
        node = np.where(node == root, child, node)
        alive[root], parent[child], root = False, -1, child
    order = preorder(parent, alive, ends)
    renumber = np.full(len(parent), -1, dtype=np.int64)
    renumber[order] = np.arange(len(order))
    return LevelCut(node_parent=[int(renumber[parent[n]]) if parent[n] >= 0 else -1 for n in order],
                    viewframe_leaves=[int(renumber[e]) for e in ends], keep=keep, landmark_nodes=renumber[node[keep]],
                    landmark_index=np.where(keep, np.cumsum(keep) - 1, -1), viewframe_index=viewframes,
                    merged=merged, deleted=deleted)


def _branch_sizes(parent: np.ndarray, counts: np.ndarray, ends: Sequence[int]) -> list[int]:
    sizes = []
    for end in ends:
        total, n = 0, end
        while n >= 0:
            total += int(counts[n])
            n = parent[n]
        sizes.append(total)
    return sizes


def _merge_identical(parent: np.ndarray, counts: np.ndarray, ends: Sequence[int]) -> tuple[list[int], int]:
    """Keep the first of viewframes whose non-empty nodes are the same (their landmark sets are equal)."""
    kept: dict[tuple[int, ...], int] = {}
    for end in ends:
        kept.setdefault(_signature(parent, counts, end), end)
    return list(kept.values()), len(ends) - len(kept)


def _signature(parent: np.ndarray, counts: np.ndarray, end: int) -> tuple[int, ...]:
    """The non-empty nodes of the branch ending in ``end`` (equal signatures: equal landmark sets)."""
    signature, n = [], end
    while n >= 0:
        if counts[n]:
            signature.append(int(n))
        n = parent[n]
    return tuple(signature)


def _viewframe_index(parent: np.ndarray, counts: np.ndarray, old_ends: Sequence[int], candidates: Sequence[int],
                     ends: Sequence[int]) -> np.ndarray:
    """Per old viewframe (its branch now ending in ``old_ends[v]``), the index among the kept ``ends``
    of the viewframe it became (the one with its landmark set), or -1 when it was deleted (its end
    is not among the ``candidates`` that survived the landmark minimum)."""
    kept = {_signature(parent, counts, end): k for k, end in enumerate(ends)}
    survivors = set(candidates)
    return np.array([kept[_signature(parent, counts, end)] if end in survivors else -1 for end in old_ends],
                    dtype=np.int64).reshape(-1)
