"""People in the simulator: where they walk over time, that they stop for the robot, that the robot
collides with them, that every camera draws them where they are and that they hide landmarks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drivers.sim.people import PASSING_M, PERSONAL_SPACE_M, SIDESTEP_M, position_at
from drivers.sim.scene import free_space_problem
from drivers.sim.world import load_world
from drivers.sim.world_values import Person, TextureSpec
from maps.store import InputError
from perception.geometry import Pose2D
from tests.sim.conftest import drive_for

TEXTURE = TextureSpec(seed=1)
HALL = """
start: {x: 0, y: 0, theta_deg: 0}
robot: {radius: 0.25}
walls: [{points: [[-4, -3], [6, -3], [6, 3], [-4, 3]], closed: true, height: 2.5}]
cameras: [{name: eye, kind: bearings}]
"""


def person(path, **kw) -> Person:
    return Person(tuple(map(tuple, path)), radius=0.25, height=1.75, texture=TEXTURE, **kw)


@pytest.mark.parametrize(("t", "where"), [
    (1.0, (2.0, 0.0)),  # going: 2 m/s for 1 s
    (2.5, (4.0, 0.0)),  # waiting at the last point (arrived at 2 s, leaves at 3 s)
    (3.5, (3.0, 0.0)),  # coming back: 4 - 2 * 0.5
    (5.5, (0.0, 0.0)),  # waiting at the first point (back at 5 s, leaves at 6 s)
    (7.0, (2.0, 0.0)),  # the next period (6 s) like the first
])
def test_back_and_forth_with_a_wait_at_each_end(t, where):
    walker = person([[0, 0], [4, 0]], speed=2.0, wait=1.0)
    assert position_at(walker, t) == pytest.approx(where)


@pytest.mark.parametrize(("t", "where"), [
    (5.0, (3.0, 2.0)),  # 3 m along the first side, 2 m up the second
    (10.0, (1.2, 1.6)),  # 3 m down the way back from (3, 4) to (0, 0): (3, 4) - 3 * (0.6, 0.8)
    (13.0, (0.0, 0.0)),  # the round (12 m) took 12 s: waiting at the first point until 14 s
    (15.0, (1.0, 0.0)),  # the second round
])
def test_a_loop_goes_round_back_to_its_first_point_and_waits_there(t, where):
    walker = person([[0, 0], [3, 0], [3, 4]], speed=1.0, wait=2.0, loop=True)
    assert position_at(walker, t) == pytest.approx(where)


def test_a_person_of_one_point_stands_still():
    assert position_at(person([[1.5, -2.0]]), 123.4) == (1.5, -2.0)


def test_a_walking_person_steps_aside_round_the_robot_and_back_onto_their_path(sim_from):
    # the robot (radius 0.25) stands on the path of a person (radius 0.25) walking from x = 3 to x = -3
    sim = sim_from(HALL + "people: [{path: [[3, 0], [-3, 0]], speed: 1.0, wait_s: 10}]\n")
    nearest, aside = math.inf, 0.0
    for step in range(150):  # 15 s: 6 m at 1 m/s, the wait and the time stepping aside
        sim.step(0.1)
        x, y = sim.people_xy()[0]
        nearest, aside = min(nearest, math.hypot(x, y)), max(aside, abs(y))
        if step == 69:  # 7 s: in front of the robot since 2.4 s, waiting YIELD_S for it to move
            assert x == pytest.approx(0.25 + 0.25 + PERSONAL_SPACE_M, abs=0.1) and y == 0.0
    assert nearest >= 0.25 + 0.25 + PASSING_M - 1e-9  # passed, never nearer the robot's disc than PASSING_M
    assert 0.25 + 0.25 + PASSING_M - 0.1 <= aside <= SIDESTEP_M  # as far aside as passing took (one step's slack)
    x, y = sim.people_xy()[0]
    assert (x, y) == (-3.0, 0.0)  # walked on past the robot, back on their path to its end
    assert sim.ground_truth_report()["collisions"] == 0


def test_a_person_waits_behind_a_robot_that_moves_on(sim_from):
    # the robot backs away along the person's path at 0.1 m/s: they follow at its pace, on their path
    sim = sim_from(HALL + "people: [{path: [[3, 0], [-3, 0]], speed: 1.0}]\n")
    for _ in range(30):  # 3 s: they reached the robot at 2.4 s
        sim.step(0.1)
    drive_for(sim, -0.1, 0.0, 12.0)  # longer than YIELD_S and PATIENCE_S: a moving robot is waited for
    x, y = sim.people_xy()[0]
    assert y == 0.0 and x == pytest.approx(-1.2 + 0.25 + 0.25 + PERSONAL_SPACE_M, abs=0.15)  # behind it, not round
    assert sim.ground_truth_report()["collisions"] == 0


def test_with_no_room_to_pass_a_person_waits_then_turns_back(sim_from):
    # a 1.2 m corridor: passing a robot of radius 0.25 would take the person's centre to |y| >= 0.55,
    # their side to 0.8, through the wall at 0.6; they wait 0.1 m from its disc, aside as far as they can,
    # then go back
    corridor = HALL.replace("walls: [{points: [[-4, -3], [6, -3], [6, 3], [-4, 3]], closed: true, height: 2.5}]",
                            "walls: [{points: [[-4, -0.6], [6, -0.6]], height: 2.5}, {points: [[-4, 0.6], [6, 0.6]], "
                            "height: 2.5}]")
    sim = sim_from(corridor + "people: [{path: [[3, 0], [-3, 0]], speed: 1.0}]\n")
    for _ in range(90):  # 9 s: they reached the robot at 2.4 s, waited YIELD_S, have stepped aside since 7.4 s
        sim.step(0.1)
    x, y = sim.people_xy()[0]
    assert 0.25 + 0.25 + PERSONAL_SPACE_M - 1e-9 <= x <= 0.25 + 0.25 + PERSONAL_SPACE_M + 0.1
    assert 0.0 < abs(y) <= 0.6 - 0.25  # stood aside as far as the wall lets them
    for _ in range(70):  # 16 s: held PATIENCE_S in all by about 12.8 s, walking back since
        sim.step(0.1)
    assert sim.people_xy()[0, 0] > x + 1.0
    report = sim.ground_truth_report()
    assert report["collisions"] == 0 and report["min_clearance_m"] >= PERSONAL_SPACE_M - 1e-9


def test_driving_into_a_standing_person_is_a_collision_with_a_person(sim_from):
    sim = sim_from(HALL + "people: [{path: [[1.5, 0]], radius: 0.3}]\n")
    drive_for(sim, 0.4, 0.0, 6.0)
    assert sim.robot.base.stalled()
    assert sim.true_pose().x == pytest.approx(1.5 - 0.3 - 0.25, abs=0.001)  # stopped at contact
    report = sim.ground_truth_report()
    assert report["collisions"] == 1 and report["collisions_with_people"] == 1
    assert report["min_clearance_m"] == pytest.approx(0.0, abs=0.001)
    # said with its time and place: 0.95 m at 0.4 m/s (the base accelerating at ARIA's 0.3 m/s^2 for the
    # first 1.33 s, 0.267 m of them): (0.95 - 0.267) / 0.4 + 1.33 = 3.04 s
    contact = report["collisions_at"][0]
    assert contact["with"] == "person" and contact["x"] == pytest.approx(0.95, abs=0.001)
    assert contact["t"] == pytest.approx(3.04, abs=0.11)  # within a step
    assert report["min_clearance_at"]["with"] == "person"


def test_a_person_hides_a_landmark_behind_them_from_the_bearings_sensor(sim_from):
    landmark = "landmarks: [{id: 7, position: [5, 0, 1.2]}]\n"
    assert sim_from(HALL + landmark).observe(Pose2D(), "eye").ids.tolist() == [7]
    child = "people: [{path: [[2.5, 0]], height: 1.2}]\n"
    # the line of sight from the eye (0.9 m up) meets the person's front (x = 2.25) at
    # 0.9 + (1.2 - 0.9) * 2.25 / 5 = 1.035 m: below the head (1.2 m), hidden
    assert sim_from(HALL + landmark + child).observe(Pose2D(), "eye").ids.tolist() == []
    # a landmark at 2.4 m: 0.9 + 1.5 * 2.25 / 5 = 1.575 m, seen over the head
    assert sim_from(HALL + landmark.replace("1.2]", "2.4]") + child).observe(Pose2D(), "eye").ids.tolist() == [7]


ROOM_CAMERAS = HALL.replace("cameras: [{name: eye, kind: bearings}]\n", "")


def changed_columns(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.flatnonzero((a != b).any(axis=0))


def test_a_panorama_shows_the_person_in_the_columns_the_cylinder_covers(sim_from):
    empty = sim_from(ROOM_CAMERAS).snapshot(Pose2D(), "panorama").image
    with_person = sim_from(ROOM_CAMERAS + "people: [{path: [[3, 0]]}]\n").snapshot(Pose2D(), "panorama").image
    cols = changed_columns(empty, with_person)
    # column u looks at azimuth (360 - u) * 0.5 deg; the cylinder spans +-asin(0.25 / 3) = +-4.78 deg
    half = math.degrees(math.asin(0.25 / 3.0)) / 0.5
    assert cols.min() >= math.floor(360 - half - 1) and cols.max() <= math.ceil(360 + half)
    assert len(cols) >= 2 * half - 2


SMALL_CAMERAS = ROOM_CAMERAS + """cameras:
  - {name: omni, kind: catadioptric, model: {width: 120, height: 120, cx: 59.5, cy: 59.5, r_inner: 10, r_outer: 58}}
  - {name: front, kind: pinhole, mount: ptu, model: {width: 160, height: 120, fx: 130, fy: 130, cx: 79.5, cy: 59.5}}
  - {name: stereo, kind: stereo, mount: ptu, model: {width: 160, height: 120, fx: 130, fy: 130, cx: 79.5, cy: 59.5}}
"""


@pytest.mark.parametrize("camera", ["omni", "front", "stereo"])
def test_every_image_camera_shows_the_person(sim_from, camera):
    empty = sim_from(SMALL_CAMERAS).snapshot(Pose2D(), camera)
    seen = sim_from(SMALL_CAMERAS + "people: [{path: [[2, 0]]}]\n").snapshot(Pose2D(), camera)
    assert np.mean(empty.image != seen.image) > 0.01
    if seen.right is not None:
        assert np.mean(empty.right != seen.right) > 0.01


def test_a_walking_person_is_drawn_where_they_are_at_the_frames_time(sim_from):
    sim = sim_from(ROOM_CAMERAS + "people: [{path: [[3, 2], [3, -2]], speed: 1.0}]\n")
    first = sim.robot.cameras["panorama"].grab()
    for _ in range(20):  # 2 s: from (3, 2) to (3, 0), straight ahead
        sim.step(0.1)
    later = sim.robot.cameras["panorama"].grab()
    assert first is not None and later is not None and later.stamp == pytest.approx(2.0)
    ahead = sim_from(ROOM_CAMERAS + "people: [{path: [[3, 0]]}]\n").snapshot(Pose2D(), "panorama")
    assert np.array_equal(later.image, ahead.image) and not np.array_equal(first.image, later.image)


def test_people_are_validated_with_located_errors(world_file):
    path = world_file("""\
        start: {x: 0, y: 0}
        people:
          - {path: [[0.3, 0.2]]}
          - {path: [[2, 0], [3, 0], [2, 0]], loop: true}
          - {path: [[2, 0], [3, 0]], speed: 9}
          - {path: [], heigth: 2}
        """)
    with pytest.raises(InputError) as exc:
        load_world(path)
    found = [(d.line, d.message) for d in exc.value.diagnostics]
    for line, fragment in [(4, "a loop walks back to its first point by itself"), (5, "speed must be <= 3"),
                           (6, "at least 1 item"), (6, "did you mean 'height'")]:
        assert any(ln == line and fragment in msg for ln, msg in found), (line, fragment, found)
    fixed = world_file("start: {x: 0, y: 0}\npeople:\n  - {path: [[0.3, 0.2]]}\n", name="on_start.yaml")
    with pytest.raises(InputError, match=r"on_start.yaml:3:5: person 0 starts on the robot's start"):
        load_world(fixed)


def test_a_persons_path_may_cross_a_wall(world_file):
    world = load_world(world_file(HALL + "people: [{path: [[0, 2], [0, 5]], wait_s: 2, texture: {seed: 4}}]\n"))
    assert world.people[0].path == ((0.0, 2.0), (0.0, 5.0)) and world.people[0].wait == 2.0
    assert world.people[0].texture.seed == 4


def test_a_start_pose_on_a_person_is_not_free(world_file):
    world = load_world(world_file(HALL + "people: [{path: [[2, 0], [2, 2]]}]\n"))
    assert free_space_problem(world, Pose2D(0, 0)) is None
    assert "is on person 0 (at (2, 0) at the start): 0.15 m" in free_space_problem(world, Pose2D(1.6, 0))
    assert free_space_problem(world, Pose2D(1.6, 0), people=False) is None
