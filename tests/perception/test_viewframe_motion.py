"""perception.viewframe_motion: when a viewframe is lost, and Z-infinity down its threshold ladder."""

from __future__ import annotations

import math

import numpy as np

from perception.geometry import Pose2D
from perception.synthetic import make_scene, rotation_error_deg
from perception.synthetic_route import make_route_world, observe_route
from perception.viewframe_motion import FAR_THRESHOLDS, RULES, compass_motion, lost_threshold, zinf_motion
from perception.zinf import ZinfStatus, estimate_motion

WORLD = make_route_world(0, length=3.0, n_far=60, n_near=400)


def test_lost_threshold_is_the_papers_50_unless_the_viewframe_is_small():
    assert lost_threshold(400, 50) == 50
    assert lost_threshold(100, 50) == 50  # exactly 2 x 50: not small
    assert lost_threshold(24, 50) == 12  # the ideal sensor in a room: half the viewframe
    assert lost_threshold(25, 50) == 13  # half, rounded up
    assert lost_threshold(6, 50) == 8  # never under Z-infinity's minimum


def test_with_far_landmarks_the_first_rung_is_the_papers_one_degree():
    scene = make_scene(1)
    ruled = zinf_motion(scene.ref, scene.cur, np.random.default_rng(0))
    paper = estimate_motion(scene.ref, scene.cur, rng=np.random.default_rng(0), far_threshold=math.radians(1.0))
    assert ruled.rule == "zinf_1deg" and ruled.motion.ok and np.array_equal(ruled.motion.rotation, paper.rotation)
    assert tuple(np.radians((1.0, 2.0, 4.0, 8.0))) == FAR_THRESHOLDS
    assert RULES == ("zinf_1deg", "zinf_2deg", "zinf_4deg", "zinf_8deg", "compass")


def test_without_landmarks_unmoved_within_one_degree_a_wider_rung_finds_the_rotation():
    # every landmark 3-6 m away, 0.3 m of travel: none stays within 1 degree, the farthest within 2
    scene = make_scene(5, n_far=0, n_near=300, yaw_deg=25.0, position=(0.3, 0.1, 0.0), near_range=(3.0, 6.0))
    tight = estimate_motion(scene.ref, scene.cur, rng=np.random.default_rng(0), far_threshold=FAR_THRESHOLDS[0])
    assert tight.status is ZinfStatus.NO_ROTATION
    ruled = zinf_motion(scene.ref, scene.cur, np.random.default_rng(0))
    assert ruled.rule in ("zinf_2deg", "zinf_4deg", "zinf_8deg") and not ruled.compass
    assert ruled.motion.rotation_ok and rotation_error_deg(ruled.motion.rotation, scene.rotation) < 3.0


def test_when_no_rung_separates_a_rotation_the_compass_takes_over():
    # landmarks within a metre, a metre of travel: every bearing moves by more than 8 degrees
    scene = make_scene(5, n_far=0, n_near=300, yaw_deg=25.0, position=(1.0, 0.3, 0.0), near_range=(0.5, 1.0))
    ruled = zinf_motion(scene.ref, scene.cur, np.random.default_rng(0))
    assert ruled.compass and ruled.rule == "compass"
    assert ruled.motion.rotation_ok and ruled.motion.far.all()  # the compass fits all landmarks


def test_the_compass_needs_z_infinitys_minimum_of_landmarks():
    scene = make_scene(2, n_far=4, n_near=3)
    assert compass_motion(scene.ref, scene.cur, np.random.default_rng(0)).status is ZinfStatus.NOT_ENOUGH_LANDMARKS


def test_zinf_keeps_the_rotation_where_a_compass_of_near_landmarks_is_pulled_off():
    rng = np.random.default_rng(3)
    place = Pose2D(1.5, 0.0, 0.0)
    ref = observe_route(WORLD, place, rng)
    cur = observe_route(WORLD, Pose2D(place.x + 0.3, place.y + 0.3, 0.5), rng)
    _, a, b = np.intersect1d(ref.ids, cur.ids, return_indices=True)
    ruled = zinf_motion(ref.bearings[a], cur.bearings[b], rng)
    zinf = ruled.motion
    assert not ruled.compass
    compass = compass_motion(ref.bearings[a], cur.bearings[b], rng)
    assert abs(zinf.yaw + 0.5) < math.radians(0.5)
    assert abs(compass.yaw + 0.5) > abs(zinf.yaw + 0.5)
