"""maps.ltmap.learner: teaching an LT-map on synthetic routes whose truth is known (perception.synthetic_route)."""

from __future__ import annotations

import numpy as np
import pytest

from maps.ltmap.arrays import IDS
from maps.ltmap.learner import LearnConfig, RouteLearner, compensate, threshold_angle
from perception.geometry import Pose2D
from perception.observation import Observation
from perception.similarity import bearing_angles, delta_t
from perception.synthetic import unit
from perception.synthetic_route import (
    CLUTTER_ID_BASE,
    make_route_world,
    observe_route,
    straight_route,
    visible,
)
from perception.zinf import estimate_motion

WORLD = make_route_world(0, length=6.0, n_far=60, n_near=500)


def teach(poses, *, kind=IDS, config=None, heading=None, seed=1, finish=True, **noise):
    """Teach along ``poses`` (then finish at the last); the learner, the steps, where each viewframe was made."""
    rng = np.random.default_rng(seed)
    learner, steps, places = RouteLearner(config), [], []
    for pose in poses:
        observation = observe_route(WORLD, pose, rng, kind=kind, **noise)
        steps.append(learner.observe(observation, pose.theta if heading is None else heading))
        if steps[-1].created:
            places.append(pose)
    if finish and learner.finish().created:
        places.append(poses[-1])
    return learner, steps, places


@pytest.fixture(scope="module")
def corridor():
    return teach(straight_route(6.0, 0.05), noise_deg=0.1, dropout=0.05, clutter=5)


def test_standing_still_makes_one_viewframe():
    learner, steps, _ = teach([Pose2D(1.0, 0.0, 0.3, stamp=0.1 * k) for k in range(20)], noise_deg=0.1, finish=False)
    assert learner.tree.viewframe_count == 1 and steps[1].created
    assert max(s.delta_t for s in steps[2:]) < learner.threshold


def test_turning_on_the_spot_makes_no_viewframe_with_or_without_the_heading():
    # the heading compensates the turn; without it, Z-infinity's rotation is removed from delta_t as when following
    turning = [Pose2D(1.0, 0.0, 0.05 * k, stamp=0.1 * k) for k in range(40)]  # two radians in place
    for heading in (None, 0.0):
        learner, steps, _ = teach(turning, heading=heading, finish=False)
        assert learner.tree.viewframe_count == 1
        assert max(s.delta_t for s in steps[2:]) < learner.threshold


def test_a_mismatched_landmark_alone_makes_no_viewframe():
    # standing still, one tracked landmark is seen at the opposite bearing each time (a mismatch): eq. 1 over
    # every tracked landmark passes the threshold (that one costs about 4 b = 2245 thresholds of 3 deg, over
    # a few hundred landmarks), over Z-infinity's inliers it stays under it
    rng = np.random.default_rng(5)
    learner, steps, pose = RouteLearner(), [], Pose2D(1.0, 0.0, 0.0)
    for k in range(12):
        seen = observe_route(WORLD, Pose2D(1.0, 0.0, 0.0, stamp=0.1 * k), rng, noise_deg=0.1)
        bearings = seen.bearings.copy()
        if k >= 2:
            bearings[k] = -bearings[k]
        steps.append(learner.observe(Observation(bearings, seen.stamp, "bearings", ids=seen.ids), pose.theta))
        if k >= 2:
            matched = learner.tree.match(0, Observation(bearings, seen.stamp, "bearings", ids=seen.ids))
            assert delta_t(matched.ref, matched.cur) > learner.threshold
    assert learner.tree.viewframe_count == 1 and max(s.delta_t for s in steps[2:]) < learner.threshold


def test_the_heading_sets_the_frame_not_the_map():
    sideways = straight_route(3.0, 0.05, heading=0.7)  # the camera looks 40 deg left of the travel
    ahead, _, _ = teach(straight_route(3.0, 0.05))
    turned, _, _ = teach(sideways)
    a, b = ahead.tree.to_arrays(), turned.tree.to_arrays()
    assert all(np.array_equal(a[k], b[k]) for k in a if k != "bearings")
    assert np.allclose(a["bearings"], b["bearings"], atol=1e-5)


def test_a_viewframe_is_made_when_delta_t_passes_the_threshold(corridor):
    learner, steps, places = corridor
    threshold = learner.threshold
    made = [s for s in steps if s.created][1:]  # the first one is made from the first two images
    assert len(made) >= 10 and all(s.delta_t > threshold for s in made)
    assert all(s.delta_t <= threshold for s in steps[1:] if not s.created)
    spacing = np.diff([p.x for p in places])
    assert 0.05 <= np.median(spacing) < 1.0 and spacing.max() < 3 * np.median(spacing)


def test_viewframes_hold_what_was_seen_from_their_place(corridor):
    learner, _, places = corridor
    tree = learner.tree
    assert len(places) == tree.viewframe_count
    share = threshold_angle(learner.threshold)
    for index, place in enumerate(places):
        found = tree.viewframe(index)
        seen = np.isin(found.ids, visible(WORLD, place))
        truth = unit(WORLD.positions[found.ids[seen]] - [place.x, place.y, 0.0])
        error = bearing_angles(truth, found.bearings[seen])
        assert seen.mean() > 0.95, f"viewframe {index} holds landmarks invisible from its place"
        assert np.mean(error < share + np.radians(0.5)) > 0.97


def test_following_can_switch_at_every_viewframe(corridor):
    # at a viewframe's own place, turned, eq. 1 against it (de-rotated by Z-infinity) is under the
    # threshold: shared landmarks keep bearings within share_angle, so the switch rule can fire
    learner, _, places = corridor
    rng = np.random.default_rng(8)
    for index, place in enumerate(places):
        observation = observe_route(WORLD, Pose2D(place.x, place.y, 0.6), rng, noise_deg=0.1, dropout=0.05)
        matched = learner.tree.match(index, observation)
        motion = estimate_motion(matched.ref, matched.cur)
        assert motion.rotation_ok and abs(motion.yaw + 0.6) < np.radians(1.0)
        assert delta_t(matched.ref, matched.cur, rotation=motion.rotation) < learner.tree.threshold / 2


def test_volatile_landmarks_never_enter_the_map(corridor):
    learner, steps, _ = corridor
    assert learner.tree.ids.max() < CLUTTER_ID_BASE
    assert sum(s.volatile for s in steps if s.created) > 0  # there was clutter to reject


def test_only_new_landmarks_go_into_a_new_leaf():
    rng = np.random.default_rng(2)
    learner, previous = RouteLearner(), None
    for pose in straight_route(4.0, 0.05):
        before = learner.tree.landmark_count if learner.tree else 0
        observation = observe_route(WORLD, pose, rng, noise_deg=0.1, dropout=0.1)
        step = learner.observe(observation, pose.theta)
        if step.created:
            tree = learner.tree
            leaf_rows = tree.node_landmarks(tree.viewframe_leaves[-1])
            assert leaf_rows.min(initial=before) >= before and len(leaf_rows) == step.stored
            in_both = set(np.intersect1d(observation.ids, previous.ids))
            assert in_both <= set(tree.ids[tree.viewframe(-1).landmarks]), "what is not volatile is in the viewframe"
            assert set(tree.ids[leaf_rows]) <= set(observation.ids)
        previous = observation


def test_far_landmarks_are_stored_once_at_the_root_and_local_ones_in_the_leaves():
    learner, _, _ = teach(straight_route(6.0, 0.05), noise_deg=0.05)
    tree = learner.tree
    far = np.flatnonzero(WORLD.far)
    root = tree.node_landmarks(tree.root)
    assert set(far) <= set(tree.ids[root])
    assert np.array_equal(np.sort(tree.ids[np.isin(tree.ids, far)]), far), "stored once"
    depth = tree.depths()[tree.landmark_nodes]
    views = np.zeros(tree.landmark_count)
    for i in range(tree.viewframe_count):
        views[tree.viewframe(i).landmarks] += 1
    assert tree.height >= 2
    assert np.all(views[depth == tree.height] == 1), "a leaf landmark belongs to one viewframe"
    assert views[depth == 0].mean() > 3 * views[depth == tree.height - 1].mean()


def test_descriptors_are_learned_like_ids():
    orb, _, orb_places = teach(straight_route(2.5, 0.05), kind="orb", noise_deg=0.1)
    ids, _, id_places = teach(straight_route(2.5, 0.05), noise_deg=0.1)
    assert orb.tree.kind == "orb" and orb.tree.descriptors.shape[1] == 32
    assert abs(orb.tree.viewframe_count - ids.tree.viewframe_count) <= 0.25 * ids.tree.viewframe_count
    rng = np.random.default_rng(9)
    at_goal = observe_route(WORLD, orb_places[-1], rng, kind="orb", noise_deg=0.1)
    matched = orb.tree.match(-1, at_goal)
    assert len(matched) > 0.8 * at_goal.count  # the goal's own view matches its viewframe
    assert np.median(bearing_angles(matched.ref, matched.cur)) < np.radians(1.0)


def test_finish_makes_the_goal_a_viewframe():
    learner, steps, places = teach(straight_route(1.0, 0.05))
    assert places[-1] == straight_route(1.0, 0.05)[-1]
    assert learner.finish().created is False  # once is enough


def test_online_pruning_keeps_the_map_within_the_budget():
    budget = 40_000
    learner, steps, _ = teach(straight_route(6.0, 0.05), config=LearnConfig(budget_bytes=budget), noise_deg=0.1)
    pruned = [s.pruned for s in steps if s.pruned is not None]
    assert pruned and all(p.fits for p in pruned)
    assert learner.tree.memory_bytes() <= budget
    full, _, _ = teach(straight_route(6.0, 0.05), noise_deg=0.1)
    assert full.tree.memory_bytes() > 2 * budget
    assert learner.tree.viewframe_count >= 2  # start and goal survive


def test_a_budget_too_small_is_reported_not_met():
    learner, steps, _ = teach(straight_route(1.0, 0.05), config=LearnConfig(budget_bytes=100))
    assert any(s.over_budget for s in steps)
    assert learner.tree.viewframe_count >= 1


def test_bad_configurations_and_inputs_are_refused():
    with pytest.raises(ValueError, match="threshold"):
        LearnConfig(threshold=0.0)
    with pytest.raises(ValueError, match="budget"):
        LearnConfig(budget_bytes=0)
    with pytest.raises(ValueError, match="nothing was observed"):
        RouteLearner().finish()
    learner = RouteLearner()
    rng = np.random.default_rng(0)
    learner.observe(observe_route(WORLD, Pose2D(), rng), 0.0)
    with pytest.raises(ValueError, match="mix|descriptors|ids"):
        learner.observe(observe_route(WORLD, Pose2D(), rng, kind="orb"), 0.0)


def test_a_blind_spell_makes_no_empty_viewframes():
    rng = np.random.default_rng(3)
    learner = RouteLearner()
    poses = straight_route(1.0, 0.05)
    for pose in poses[:5]:
        learner.observe(observe_route(WORLD, pose, rng), pose.theta)
    count = learner.tree.viewframe_count
    blind = Observation(np.zeros((0, 3)), 1.0, "bearings", ids=np.zeros(0, dtype=np.int64))  # lights out
    steps = [learner.observe(blind, 0.0) for _ in range(10)]
    assert learner.tree.viewframe_count == count and not any(s.created for s in steps)
    assert all(s.delta_t == np.inf and s.tracked == 0 for s in steps)


def test_compensation_turns_body_bearings_into_the_route_frame():
    ahead = np.array([[1.0, 0.0, 0.0]])
    assert np.allclose(compensate(ahead, np.pi / 2), [[0.0, 1.0, 0.0]])  # facing +y, "ahead" is +y
