"""maps.ltmap.gaps: landmarks found again fill the tree's gaps, routes back past a place are loops.

Hand-built trees for the rules, a property test (hypothesis) of random teach sequences with far
landmarks that drop out and come back, and the learner on synthetic routes.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from maps.ltmap.arrays import IDS
from maps.ltmap.gaps import GapConfig, Loop, common_node, found_again, node_cover, plan_shifts
from maps.ltmap.learner import LearnConfig, RouteLearner
from maps.ltmap.tree import LandmarkSet, LandmarkTree
from perception.geometry import Pose2D
from perception.similarity import bearing_angles
from perception.synthetic import unit
from perception.synthetic_route import make_route_world, observe_route, straight_route

SHARE = math.radians(3.0)

# A hand-built tree of 5 viewframes (height 2):      0
#                                                  /    \
#                                                 1      2
#                                               / | \   / \
#                                              3  4  5 6   7     leaves: viewframes 0 1 2 | 3 4
PARENT = [-1, 0, 0, 1, 1, 1, 2, 2]
LEAVES = [3, 4, 5, 6, 7]


def test_node_cover_and_common_node_worked_out_by_hand():
    first, last = node_cover(PARENT, LEAVES)
    assert first.tolist() == [0, 0, 3, 0, 1, 2, 3, 4] and last.tolist() == [4, 2, 4, 0, 1, 2, 3, 4]
    assert common_node(PARENT, 3, 5) == 1 and common_node(PARENT, 4, 7) == 0 and common_node(PARENT, 6, 2) == 2


def test_a_gap_of_one_viewframe_is_filled_a_longer_one_or_an_extension_is_not():
    # rows: 0 in leaf 3 (viewframe 0), 1 in leaf 5 (viewframe 2): common node 1 covers 0..2, viewframe 1 in the gap
    nodes = np.array([3, 5, 4, 6, 7, 3])
    shifted = plan_shifts(PARENT, LEAVES, nodes, np.array([[0, 1]]), GapConfig(max_gap=1))
    assert (shifted.keep.tolist(), shifted.drop.tolist(), shifted.node.tolist()) == ([0], [1], [1])
    assert len(plan_shifts(PARENT, LEAVES, nodes, np.array([[0, 1]]), GapConfig(max_gap=0)).drop) == 0
    # rows 2 (viewframe 1) and 3 (viewframe 3): common node 0 covers 0..4, beyond the sightings 1..3: no shift
    assert len(plan_shifts(PARENT, LEAVES, nodes, np.array([[2, 3]]), GapConfig(max_gap=5)).drop) == 0
    # rows 3 and 4 (viewframes 3 and 4, no gap): their common node 2 covers just them
    assert plan_shifts(PARENT, LEAVES, nodes, np.array([[3, 4]]), GapConfig()).node.tolist() == [2]
    # a chain: 5 merges into 0, then 0 (moved to node 1) with 1: one landmark, kept as row 0
    chain = plan_shifts(PARENT, LEAVES, nodes, np.array([[0, 5], [0, 1]]), GapConfig(max_gap=1))
    assert chain.keep.tolist() == [0, 0] and sorted(chain.drop.tolist()) == [1, 5]


def test_landmarks_found_again_from_far_back_make_a_loop():
    # 8 landmarks seen at viewframe 0 only, found again at viewframe 4 (3 viewframes between): a loop (0, 4)
    nodes = np.concatenate((np.full(8, 3), np.full(8, 7)))
    pairs = np.column_stack((np.arange(8), np.arange(8, 16)))
    plan = plan_shifts(PARENT, LEAVES, nodes, pairs, GapConfig(max_gap=2, min_loop=8))
    assert plan.loop == Loop(earlier=0, later=4, shared=8) and len(plan.drop) == 0
    assert plan_shifts(PARENT, LEAVES, nodes, pairs[:7], GapConfig(min_loop=8)).loop is None


def test_found_again_by_id_or_descriptor_within_the_share_angle():
    bearings = unit(np.array([[1.0, 0, 0], [1.0, 0.03, 0], [1.0, 0.2, 0], [0, 1.0, 0], [0, 1.0, 0.01]]))
    ids = np.array([7, 7, 7, 9, 9])  # 0.03 rad apart: the same; 0.2 rad: moved
    assert found_again(IDS, ids, bearings, np.array([1, 4]), SHARE).tolist() == [[0, 1], [3, 4]]
    rng = np.random.default_rng(0)
    rows = rng.integers(0, 256, size=(5, 32), dtype=np.uint8)
    rows[1], rows[4] = rows[0], rows[3]  # copies of rows 0 and 3
    rows[1, 0] ^= 1
    assert found_again("orb", rows, bearings, np.array([1, 4]), SHARE).tolist() == [[0, 1], [3, 4]]
    assert found_again("orb", rows, bearings, np.array([2]), SHARE).tolist() == []  # no copy of row 2


# ----- a property test: random teach sequences with far landmarks that drop out and come back ------------

FAR = unit(np.random.default_rng(11).normal(size=(30, 3)))  # far landmark i: id i, the same bearing everywhere
SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def teach_step(tree: LandmarkTree, visible_far: np.ndarray, fresh: int, next_id: int,
               rng: np.random.Generator) -> int:
    """One viewframe as the learner makes it: far landmarks of the last viewframe seen again are
    tracked, the others and ``fresh`` local landmarks are new; then gap filling. Returns the next free id."""
    tracked = np.zeros(0, dtype=np.int64)
    if tree.viewframe_count:
        stack = tree.viewframe(-1)
        tracked = stack.landmarks[np.isin(stack.ids, visible_far)]
    noise = rng.normal(0.0, 0.002, (len(tracked), 3))
    sightings = LandmarkSet(unit(FAR[tree.ids[tracked]] + noise), ids=tree.ids[tracked].copy())
    again = np.setdiff1d(visible_far, tree.ids[tracked])
    local = unit(rng.normal(size=(fresh, 3)))
    new = LandmarkSet(np.vstack((FAR[again], local)), ids=np.concatenate((again, np.arange(next_id, next_id + fresh))))
    tree.add_viewframe(tracked, sightings, new, share_angle=SHARE)
    stored = tree.landmark_count
    filled = tree.fill_gaps(SHARE, GapConfig(max_gap=2))
    assert tree.landmark_count == stored - filled.shifted, "each shift deletes one row"
    kept = filled.landmark_index
    assert len(kept) == stored and kept.min(initial=0) >= 0 and kept.max(initial=-1) < tree.landmark_count
    return next_id + fresh


def rows_in(tree: LandmarkTree, index: int) -> set[int]:
    branch = tree.branch_nodes(index)
    return set(np.flatnonzero(np.isin(tree.landmark_nodes, branch)).tolist())


def check_gap_invariants(tree: LandmarkTree, saw: list[set[int]], max_gap: int) -> None:
    views = tree.viewframe_count
    depths = tree.depths()
    assert {int(depths[leaf]) for leaf in tree.viewframe_leaves} == {tree.height}, "uniform leaf depth"
    branches = [set(tree.branch_nodes(i)) for i in range(views)]
    assert set().union(*branches) == set(range(tree.node_count))
    holds = [rows_in(tree, i) for i in range(views)]
    for i in range(views):  # the cache holds what a rebuild gives (one row per id: the deepest)
        assert np.array_equal(tree.viewframe(i).landmarks, tree.viewframe(i, cached=False).landmarks)
    for row in range(tree.landmark_count):
        under = [i for i in range(views) if row in holds[i]]
        assert under == list(range(under[0], under[-1] + 1)), "a landmark's viewframes are consecutive"
        first_seen = min((i for i in range(views) if int(tree.ids[row]) in saw[i]), default=under[0])
        assert under[0] >= first_seen, "no viewframe holds a landmark it had not seen yet"
    for a in range(tree.landmark_count):  # no far landmark stored twice where a common node fills the gap
        for b in np.flatnonzero(tree.ids == tree.ids[a]).tolist():
            if b <= a or bearing_angles(tree.bearings[a], tree.bearings[b])[0] > SHARE:
                continue
            seen = {i for i in range(views) if a in holds[i] or b in holds[i]}
            common = {i for i in range(views) if holds[i] >= {a, b}}
            lowest = max(common_nodes(tree, a, b), key=lambda n: depths[n])
            covered = {i for i in range(views) if lowest in branches[i]}
            within = min(covered) >= min(seen) and max(covered) <= max(seen)
            assert not (within and len(covered - seen) <= max_gap) or common, f"rows {a} and {b} could be one"


def common_nodes(tree: LandmarkTree, a: int, b: int) -> set[int]:
    def ancestors(node: int) -> set[int]:
        out = set()
        while node >= 0:
            out.add(node)
            node = tree.node_parents[node]
        return out
    return ancestors(int(tree.landmark_nodes[a])) & ancestors(int(tree.landmark_nodes[b]))


@SETTINGS
@given(st.data(), st.integers(0, 2**32 - 1))
def test_after_any_teach_sequence_with_gap_filling_the_invariants_hold(data, seed):
    rng, tree, saw, next_id = np.random.default_rng(seed), LandmarkTree(IDS), [], 1000
    steps = data.draw(st.integers(3, 14), label="viewframes")
    for _ in range(steps):
        dropout = data.draw(st.sampled_from([0.0, 0.1, 0.3]), label="far dropout")
        region = data.draw(st.sampled_from([(0, 30), (0, 15), (15, 30)]), label="far landmarks in view")
        visible_far = np.arange(*region)[rng.random(region[1] - region[0]) >= dropout]
        saw.append(set(visible_far.tolist()) | set(range(next_id, next_id + 6)))
        next_id = teach_step(tree, visible_far, 6, next_id, rng)
        check_gap_invariants(tree, saw, max_gap=2)


# ----- the learner ------------------------------------------------------------------------------------------

WORLD = make_route_world(4, length=4.0, n_far=60, n_near=300)


def teach(poses, *, gap_filling: bool, hidden=lambda k: np.zeros(0, dtype=np.int64)):
    rng, learner, shifted, loops = np.random.default_rng(2), RouteLearner(LearnConfig(gap_filling=gap_filling)), 0, []
    for k, pose in enumerate(poses):
        seen = observe_route(WORLD, pose, rng, noise_deg=0.1)
        keep = ~np.isin(seen.ids, hidden(k))
        step = learner.observe(type(seen)(seen.bearings[keep], seen.stamp, "bearings", ids=seen.ids[keep]), pose.theta)
        shifted += step.shifted
        loops += [step.loop] if step.loop else []
    step = learner.finish()
    return learner.tree, shifted + step.shifted, loops + ([step.loop] if step.loop else [])


def test_far_landmarks_hidden_for_a_few_frames_are_stored_once_with_gap_filling():
    far = np.flatnonzero(WORLD.far)[:20]  # a person walks past: 20 far landmarks hidden for 0.3 m

    def hidden(k: int) -> np.ndarray:
        return far if 30 <= k < 36 else np.zeros(0, dtype=np.int64)

    route = straight_route(4.0, 0.05)
    filled, shifted, _ = teach(route, gap_filling=True, hidden=hidden)
    plain, none, _ = teach(route, gap_filling=False, hidden=hidden)
    copies = [np.count_nonzero(tree.ids[np.isin(tree.ids, far)] == i) for tree in (filled, plain) for i in far]
    assert none == 0 and max(copies[:20]) == 1 and min(copies[20:]) >= 2, "stored again without, once with"
    assert shifted >= 20 and filled.memory_bytes() < plain.memory_bytes()


def test_a_route_back_past_its_start_closes_a_loop():
    out = straight_route(3.0, 0.05)
    back = [Pose2D(3.0 - p.x, 0.0, math.pi, stamp=out[-1].stamp + 0.1 + p.stamp) for p in out[1:31]]
    tree, _, loops = teach(out + back, gap_filling=True)
    assert loops, "coming back past taught places is a loop"
    assert all(loop.later > loop.earlier + 2 and loop.shared >= 8 for loop in loops)
    assert tree.viewframe_count > loops[-1].later
    plain, _, none = teach(out + back, gap_filling=False)
    assert none == []  # without gap filling nothing is looked for
    assert pytest.approx(tree.threshold) == plain.threshold
