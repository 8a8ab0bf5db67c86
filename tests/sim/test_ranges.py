"""The simulated sonar ring and bumpers: ranges to walls and people, nothing heard, missed echoes, the
ring firing in turn, bumpers on contact, the minimum clearance, and the same readings for a seed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drivers.interfaces import RangeSource
from drivers.sim.ranges import FIRING_PERIOD_S, WALL_THICKNESS, wall_ends_in_cones
from tests.sim.conftest import drive_for

WALL_AHEAD = """
start: {x: 0, y: 0, theta_deg: 0}
robot: {radius: 0.25, sonar: p3dx, sonar_noise_m: 0.0, sonar_miss_probability: 0.0}
walls: [{points: [[2, -20], [2, 20]], height: 2}]
cameras: [{name: eye, kind: bearings}]
"""
ROOM = """
start: {x: 0, y: 0, theta_deg: 0}
robot: {radius: 0.25}
walls: [{points: [[-1.5, -1.5], [1.5, -1.5], [1.5, 1.5], [-1.5, 1.5]], closed: true, height: 2}]
cameras: [{name: eye, kind: bearings}]
"""
FULL_RING = 8 * FIRING_PERIOD_S  # every transducer has fired once


def settle(sim, seconds: float = FULL_RING, dt: float = 0.1) -> None:
    for _ in range(math.ceil(seconds / dt - 1e-9)):
        sim.step(dt)


def test_the_simulated_base_has_a_range_source(sim_from):
    sim = sim_from(WALL_AHEAD)
    assert isinstance(sim.robot.ranges, RangeSource)
    assert sim_from(WALL_AHEAD.replace("sonar: p3dx", "sonar: none, bumpers: false")).robot.ranges is None


def test_a_wall_straight_ahead_at_a_known_distance(sim_from):
    sim = sim_from(WALL_AHEAD)
    settle(sim)
    scan = sim.robot.ranges.read()
    # transducers 3 and 4 sit at x = 0.166 m and look 10 deg off the axis; of the 5 rays across
    # their 30 deg cones (10 + 30 * (-1/2, -1/4, 0, 1/4, 1/2)) the nearest to the wall's normal is
    # 2.5 deg off it: (2 - 0.166) / cos(2.5 deg)
    expected = (2.0 - 0.166) / math.cos(math.radians(2.5))
    assert scan.ranges[3] == pytest.approx(expected, abs=1e-9) and scan.ranges[4] == pytest.approx(expected, abs=1e-9)
    assert np.all(np.isinf(scan.ranges[8:]))  # the rear ring hears nothing
    assert not scan.pressed.any()


def test_a_wall_seen_end_on_is_heard_at_its_end(sim_from):
    # a door jamb straight ahead: every ray of the front cones passes beside the line of the wall or
    # meets it nowhere; a real wall is WALL_THICKNESS thick and its end is heard anywhere in the cone
    sim = sim_from(WALL_AHEAD.replace("[[2, -20], [2, 20]]", "[[1.5, 0], [5, 0]]"))
    settle(sim)
    scan = sim.robot.ranges.read()
    expected = math.hypot(1.5 - 0.166, 0.027) - WALL_THICKNESS / 2  # transducers 3 and 4 at (0.166, +-0.027)
    assert scan.ranges[3] == pytest.approx(expected, abs=1e-9) and scan.ranges[4] == pytest.approx(expected, abs=1e-9)
    assert np.isinf(scan.ranges[0]) and np.isinf(scan.ranges[7])  # the side transducers look past it


@pytest.mark.parametrize(("heading_deg", "expected"), [
    (0.0, 1.0 - 0.05),  # on the axis
    (17.0, 1.0 - 0.05),  # off the axis by 17 deg: within 15 deg + asin(0.05 / 1) = 17.87 deg of it
    (18.0, math.inf),  # outside the cone
    (180.0, math.inf),  # behind the transducer
])
def test_a_wall_end_is_heard_where_any_of_its_face_is_in_the_cone(heading_deg, expected):
    ranges = wall_ends_in_cones(np.zeros((1, 2)), np.radians([heading_deg]), np.radians([30.0]), np.array([[1.0, 0.0]]))
    assert ranges[0] == pytest.approx(expected)


def test_noise_scatters_the_range_around_the_true_one(sim_from):
    sim = sim_from(WALL_AHEAD.replace("sonar_noise_m: 0.0", "sonar_noise_m: 0.02"))
    expected = (2.0 - 0.166) / math.cos(math.radians(2.5))
    readings = []
    for _ in range(200):
        settle(sim)
        readings.append(sim.robot.ranges.read().ranges[3])
    assert np.mean(readings) == pytest.approx(expected, abs=0.006)  # 3 sigma of the mean: 0.0042
    assert np.std(readings) == pytest.approx(0.02, rel=0.2)


def test_a_person_ahead_is_heard_at_the_nearest_point_of_their_surface(sim_from):
    sim = sim_from(WALL_AHEAD.replace("[[2, -20], [2, 20]]", "[[9, -20], [9, 20]]")
                   + "people: [{path: [[1.5, 0]], radius: 0.25}]\n")
    settle(sim)
    r = sim.robot.ranges.read().ranges[3]
    # the person's surface is hypot(1.5 - 0.166, 0.027) - 0.25 = 1.0843 m from transducer 3; its
    # nearest ray passes 3.7 deg off the person's centre and meets the cylinder at 1.0965 m
    assert 1.0843 <= r <= 1.0966


def test_nothing_around_reads_inf(sim_from):
    sim = sim_from("robot: {sonar_noise_m: 0.05}\ncameras: [{name: eye, kind: bearings}]\n")
    settle(sim)
    assert np.all(np.isinf(sim.robot.ranges.read().ranges))


def test_the_ring_fires_in_turn_one_transducer_per_ring_every_40_ms(sim_from):
    sim = sim_from(ROOM)
    first = sim.robot.ranges.read()  # t = 0: transducers 0 and 8 have fired
    assert np.flatnonzero(np.isfinite(first.ranges)).tolist() == [0, 8]
    sim.step(0.1)  # slots 1 and 2 (40, 80 ms) are due
    assert np.flatnonzero(np.isfinite(sim.robot.ranges.read().ranges)).tolist() == [0, 1, 2, 8, 9, 10]
    settle(sim, 0.3)
    assert np.all(np.isfinite(sim.robot.ranges.read().ranges))


def test_missed_echoes_come_at_the_set_rate(sim_from):
    sim = sim_from(ROOM.replace("radius: 0.25}", "radius: 0.25, sonar_miss_probability: 0.3}"))
    ranges = sim.robot.ranges
    heard = []
    for _ in range(1000):  # one firing per ring each step: 2000 firings, all facing a wall
        sim.step(FIRING_PERIOD_S)
        scan = ranges.read()
        slot = round(sim.time / FIRING_PERIOD_S) % 8
        heard += [scan.ranges[slot], scan.ranges[slot + 8]]
    missed = float(np.mean(np.isinf(heard)))
    assert missed == pytest.approx(0.3, abs=0.035)  # 3.4 sigma of a 2000-firing binomial


def test_the_front_bumper_presses_on_contact_ahead_and_the_rear_one_behind(sim_from):
    sim = sim_from(ROOM)
    drive_for(sim, 0.3, 0.0, 6.0)
    assert sim.robot.base.stalled()
    scan = sim.robot.ranges.read()
    assert scan.bumped(+1) and not scan.bumped(-1)
    assert scan.pressed.tolist().index(True) == 2  # the middle front segment, straight ahead
    drive_for(sim, -0.3, 0.0, 0.5)
    assert not sim.robot.ranges.read().pressed.any()  # backed off: released
    drive_for(sim, -0.3, 0.0, 12.0)  # on into the wall behind
    scan = sim.robot.ranges.read()
    assert scan.bumped(-1) and not scan.bumped(+1)
    assert scan.pressed.tolist().index(True) == 7  # the middle rear segment, straight behind


def test_a_person_presses_the_bumper_too(sim_from):
    sim = sim_from(WALL_AHEAD + "people: [{path: [[1.2, 0.3]], radius: 0.3}]\n")
    drive_for(sim, 0.3, 0.0, 6.0)
    scan = sim.robot.ranges.read()
    # the person's centre is left of the heading: the contact point is at about 30 deg left
    assert scan.pressed.tolist().index(True) == 1
    assert sim.ground_truth_report()["collisions_with_people"] == 1


def test_min_clearance_against_a_hand_placed_wall(sim_from):
    sim = sim_from(WALL_AHEAD)
    settle(sim, 1.0)  # standing: the disc is 2 - 0.25 m from the wall
    assert sim.ground_truth_report()["min_clearance_m"] == pytest.approx(1.75)
    drive_for(sim, 0.5, 0.0, 2.0)  # on towards the wall
    x = sim.true_pose().x
    assert sim.ground_truth_report()["min_clearance_m"] == pytest.approx(2.0 - 0.25 - x)
    drive_for(sim, 0.5, 0.0, 6.0)
    report = sim.ground_truth_report()
    assert report["collisions"] == 1 and report["collisions_with_people"] == 0
    assert 0.0 <= report["min_clearance_m"] <= 0.001  # stopped at contact
    drive_for(sim, -0.5, 0.0, 2.0)
    assert sim.ground_truth_report()["min_clearance_m"] == report["min_clearance_m"]  # the smallest over the run


def test_the_same_seed_gives_the_same_ranges_and_images(sim_from):
    world = ROOM.replace("cameras: [{name: eye, kind: bearings}]\n", "").replace(
        "robot: {radius: 0.25}", "robot: {radius: 0.25, sonar_noise_m: 0.03, sonar_miss_probability: 0.2}"
    ) + "people: [{path: [[1, -1], [1, 1]], speed: 0.5}]\n"

    def run(seed: int):
        sim = sim_from(world, seed=seed)
        sim.robot.base.drive(0.1, 0.3)
        scans, images = [], []
        for _ in range(10):
            sim.step(0.1)
            scans.append(sim.robot.ranges.read().ranges)
            images.append(sim.robot.cameras["panorama"].grab().image)
        return np.array(scans), np.array(images)

    (a_scans, a_images), (b_scans, b_images), (c_scans, _) = run(3), run(3), run(4)
    assert np.array_equal(a_scans, b_scans, equal_nan=True) and np.array_equal(a_images, b_images)
    assert not np.array_equal(c_scans, a_scans, equal_nan=True)
