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

from maps.ltmap.arrays import preorder, top_down

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
    levels: int = 1  # levels cut: more than one for quiet levels cut at once (:func:`quiet_levels`)


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
        return sum(step.levels for step in self.steps) if self.fits else 0


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
    sizes, deepest = _branch_sums(parent, counts)
    weak = {k for k in range(1, len(ends) - 1) if sizes[ends[k]] < min_landmarks}
    candidates = [e for k, e in enumerate(ends) if k not in weak]
    ends, identical = _merge_identical(deepest, candidates)
    viewframes = _viewframe_index(deepest, old_ends, candidates, ends)
    return _restructure(parent, node, keep, ends, viewframes, merged + identical, len(weak))


def earliest_sources(viewframe_index: np.ndarray) -> list[int]:
    """For each viewframe after a prune (in order), the earliest old viewframe merged into it
    (``viewframe_index``: each old viewframe's new index, -1 when deleted): what it keeps of the
    old ones' own records (the time and the place it was taught)."""
    kept: dict[int, int] = {}
    for old, new in enumerate(np.asarray(viewframe_index).tolist()):
        if new >= 0:
            kept.setdefault(new, old)
    return [kept[k] for k in sorted(kept)]


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
    alive_children = np.bincount(parent[alive & (parent >= 0)], minlength=len(parent))
    only_child = np.full(len(parent), -1, dtype=np.int64)
    only_child[parent[alive & (parent >= 0)]] = np.flatnonzero(alive & (parent >= 0))  # right where it is the only one
    merged_roots = []
    while alive_children[root] == 1:  # a root with one child merges into it (a chain: each once)
        merged_roots.append(root)
        root = int(only_child[root])
    if merged_roots:
        node = np.where(np.isin(node, merged_roots), root, node)
        alive[merged_roots], parent[root] = False, -1
    order = preorder(parent, alive, ends)
    renumber = np.full(len(parent), -1, dtype=np.int64)
    renumber[order] = np.arange(len(order))
    return LevelCut(node_parent=[int(renumber[parent[n]]) if parent[n] >= 0 else -1 for n in order],
                    viewframe_leaves=[int(renumber[e]) for e in ends], keep=keep, landmark_nodes=renumber[node[keep]],
                    landmark_index=np.where(keep, np.cumsum(keep) - 1, -1), viewframe_index=viewframes,
                    merged=merged, deleted=deleted)


def _branch_sums(parent: np.ndarray, counts: np.ndarray) -> tuple[list[int], list[int]]:
    """Per node, the landmarks on its branch (itself and every ancestor) and the deepest non-empty
    node of that branch (-1: none), in one top-down pass. The non-empty nodes of a branch are those
    of the branch ending in its deepest non-empty node, so two branches hold equal landmark sets
    exactly when their deepest non-empty nodes are equal: no walk to the root per viewframe."""
    up, count = parent.tolist(), counts.tolist()
    sizes, deepest = [0] * len(up), [-1] * len(up)
    for n in top_down(up):
        p = up[n]
        sizes[n] = count[n] + (sizes[p] if p >= 0 else 0)
        deepest[n] = n if count[n] else (deepest[p] if p >= 0 else -1)
    return sizes, deepest


def _merge_identical(deepest: Sequence[int], ends: Sequence[int]) -> tuple[list[int], int]:
    """Keep the first of viewframes whose non-empty nodes are the same (their landmark sets are equal)."""
    kept: dict[int, int] = {}
    for end in ends:
        kept.setdefault(deepest[end], end)
    return list(kept.values()), len(ends) - len(kept)


def _viewframe_index(deepest: Sequence[int], old_ends: Sequence[int], candidates: Sequence[int],
                     ends: Sequence[int]) -> np.ndarray:
    """Per old viewframe (its branch now ending in ``old_ends[v]``), the index among the kept ``ends``
    of the viewframe it became (the one with its landmark set), or -1 when it was deleted (its end
    is not among the ``candidates`` that survived the landmark minimum)."""
    kept = {deepest[end]: k for k, end in enumerate(ends)}
    survivors = set(candidates)
    return np.array([kept[deepest[end]] if end in survivors else -1 for end in old_ends],
                    dtype=np.int64).reshape(-1)


# ------------------------------------------------------------------------------------------------
# Several quiet levels at once


def quiet_levels(node_parent: Sequence[int], viewframe_leaves: Sequence[int], landmark_nodes: np.ndarray,
                 min_landmarks: int, *, excess_bytes: int, row_bytes: int, node_bytes: int
                 ) -> tuple[int, list[list[int]]]:
    """How many levels can be cut at once with the outcome of cutting them one by one
    (:func:`cut_lowest_level`), and each viewframe's chain (leaf first).

    A cut is *quiet* when every leaf's parent has that leaf as its only child (so no two
    viewframes meet), no viewframe falls below ``min_landmarks``, no two become identical and the
    root keeps two children: then it only shortens the chains of single-child nodes at the bottom
    of the branches (start and goal carry their landmarks up, the others lose theirs). A tall,
    narrow tree (two branches of 10^6 levels) is cut level by level in one pass here instead of
    10^6 passes over the whole tree. Counted from the tree as it is, in one walk over the chains:

    - a viewframe's chain: its leaf and the single-child nodes above it (``s`` of them: at most
      ``s`` quiet cuts);
    - a viewframe other than start and goal is deleted at the first cut ``i`` that leaves it fewer
      than ``min_landmarks`` (its branch total less the landmarks of its ``i`` lowest chain nodes);
    - two viewframes become identical when both have no landmark left in their chains (from the cut
      after their highest non-empty chain node goes; start and goal keep theirs, carried up) and
      the deepest non-empty node above their chains is the same;
    - the budget: the map fits after cut ``i`` when the landmarks and nodes it removed cover
      ``excess_bytes`` (then no further cut is wanted).

    Returns ``(levels, chains)``: the levels that are quiet (0 when any of this fails at the first
    cut or the tree has fewer than two viewframes).
    """
    parent = np.asarray(node_parent, dtype=np.int64)
    leaves = list(viewframe_leaves)
    views = len(leaves)
    if views < 2 or len(parent) < 2:
        return 0, []
    children = np.bincount(parent[parent >= 0], minlength=len(parent))
    if children[parent < 0].min() < 2:
        return 0, []
    counts = np.bincount(np.asarray(landmark_nodes, dtype=np.int64), minlength=len(parent))
    up, single = parent.tolist(), (children == 1).tolist()
    chains = []
    for leaf in leaves:
        chain = [leaf]
        while single[up[chain[-1]]]:
            chain.append(up[chain[-1]])
        chains.append(chain)
    levels = min(len(chain) for chain in chains) - 1
    if levels < 2:
        return 0, chains
    sizes, deepest = _branch_sums(parent, counts)
    cut = np.array([[counts[n] for n in chain[:levels]] for chain in chains], dtype=np.int64)  # V x levels
    removed = np.cumsum(cut, axis=1)  # removed[v, i - 1]: landmarks of the i lowest nodes of v's chain
    inner = slice(1, views - 1)
    weak = np.asarray(sizes)[leaves][inner, None] - removed[inner] < min_landmarks
    for v in np.flatnonzero(weak.any(axis=1)).tolist():
        levels = min(levels, int(np.argmax(weak[v])))  # cut argmax + 1 deletes it: stop before
    levels = max(0, min(levels, _first_identical(chains, counts, deepest, up) - 1))
    freed = row_bytes * removed[inner].sum(axis=0) + node_bytes * views * np.arange(1, removed.shape[1] + 1)
    fits = np.flatnonzero(freed[:levels] >= excess_bytes)
    if len(fits):
        levels = min(levels, int(fits[0]) + 1)
    return max(levels, 0), chains


def _first_identical(chains: list[list[int]], counts: np.ndarray, deepest: Sequence[int], up: Sequence[int]) -> int:
    """The first cut after which two viewframes hold the same landmarks (see :func:`quiet_levels`)."""
    shared_from: dict[int, list[int]] = {}  # deepest non-empty node above the chains -> cuts from which they show it
    last = len(chains) - 1
    for v, chain in enumerate(chains):
        nonempty = [t for t, n in enumerate(chain) if counts[n]]
        terminal = v in (0, last)  # start and goal carry their landmarks up: their own while they have any
        cut_from = (None if nonempty else 1) if terminal else (nonempty[-1] + 1 if nonempty else 1)
        if cut_from is not None:
            shared_from.setdefault(deepest[up[chain[-1]]], []).append(cut_from)
    firsts = [sorted(cuts)[1] for cuts in shared_from.values() if len(cuts) > 1]
    return min(firsts, default=len(max(chains, key=len)) + 1)


def cut_quiet_levels(node_parent: Sequence[int], viewframe_leaves: Sequence[int], landmark_nodes: np.ndarray,
                     chains: list[list[int]], levels: int) -> LevelCut:
    """Cut ``levels`` quiet levels (:func:`quiet_levels`) at once: the chains lose their lowest
    ``levels`` nodes, start and goal carry those nodes' landmarks to their new leaf, the other
    viewframes lose them; nodes renumbered canonically, landmarks keep their order."""
    parent = np.array(node_parent, dtype=np.int64)
    node = np.array(landmark_nodes, dtype=np.int64)
    for v in {0, len(chains) - 1}:
        node[np.isin(node, chains[v][:levels])] = chains[v][levels]
    keep = ~np.isin(node, [n for chain in chains for n in chain[:levels]])
    ends = [chain[levels] for chain in chains]
    return _restructure(parent, node, keep, ends, np.arange(len(chains), dtype=np.int64), 0, 0)
