"""One stereo observation into the exploration map: explored floor, obstacles, evidence, points, edges."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration.grid import Cell, ExplorationMap, mark_traversed
from maps.exploration.integrate import clear_rays, integrate_observation, integrate_stereo, observe, scan_cells
from maps.exploration.interest import Interest, closer_points
from perception.geometry import Pose2D
from tests.maps.exploration_maps import SIMPLE, apart, state_at


def wall_observation(x: float = 2.05, z: float = 0.0) -> np.ndarray:
    """Camera-frame points of a wall across the view at ``x`` (lens 1 m up, so world z = z + 1)."""
    ys = np.linspace(-2.2, 2.2, 441)
    return np.column_stack((np.full_like(ys, x), ys, np.full_like(ys, z)))


def test_a_wall_explores_the_floor_between_the_footprint_and_the_wall():
    m = ExplorationMap.empty(resolution=0.1, half_size=5.0)
    points = wall_observation()
    m = integrate_stereo(m, points, apart(points), SIMPLE.view(Pose2D(), 0.0, 0.0))
    assert state_at(m, 1.55, 0.05) == Cell.FREE
    assert state_at(m, 1.55, 1.05) == Cell.FREE  # inside the 90 degree field: |y| < x
    assert state_at(m, 1.25, 1.65) == Cell.UNKNOWN  # outside the field
    assert state_at(m, 0.55, 0.05) == Cell.UNKNOWN  # nearer than the footprint (lens 1 m up, 45 deg down)
    assert state_at(m, 2.05, 0.05) == Cell.OBSTACLE
    assert state_at(m, 2.05, 1.55) == Cell.OBSTACLE
    assert state_at(m, 2.55, 0.05) == Cell.UNKNOWN  # behind the wall
    # hand: the trapezoid 1 <= x <= 2.05, |y| <= x has 2.05^2 - 1 = 3.2 m^2
    assert m.explored_area == pytest.approx(3.2025, rel=0.1)


def test_floor_points_explore_up_to_the_explore_range_only():
    xs, ys = np.meshgrid(np.linspace(1.0, 5.0, 81), np.linspace(-0.5, 0.5, 21))
    floor = np.column_stack((xs.ravel(), ys.ravel(), np.full(xs.size, -1.0)))  # world z = 0
    m = integrate_stereo(ExplorationMap.empty(resolution=0.1), floor, apart(floor), SIMPLE.view(Pose2D(), 0.0, 0.0))
    assert state_at(m, 2.85, 0.05) == Cell.FREE
    assert state_at(m, 3.25, 0.05) == Cell.UNKNOWN
    assert not np.any(m.cells == Cell.OBSTACLE)
    assert len(m.points) > 0 and m.points[:, 2] == pytest.approx(np.zeros(len(m.points)))


def test_points_above_the_robot_mark_nothing_but_are_kept():
    ceiling = wall_observation(z=1.5)  # world z = 2.5, above obstacle_height
    m = integrate_stereo(ExplorationMap.empty(resolution=0.1), ceiling, apart(ceiling), SIMPLE.view(Pose2D(), 0.0, 0.0))
    assert not np.any(m.cells != Cell.UNKNOWN)
    assert len(m.points) == 45  # 441 points 1 cm apart in 0.1 m voxels


def test_observations_use_the_odometry_pose_and_pan():
    points = wall_observation()
    view = SIMPLE.view(Pose2D(1.0, 1.0, math.pi / 2), pan=-math.pi / 2, tilt=0.0)  # looking along +x
    m = integrate_stereo(ExplorationMap.empty(resolution=0.1), points, apart(points), view)
    assert state_at(m, 2.55, 1.05) == Cell.FREE
    assert state_at(m, 3.05, 1.05) == Cell.OBSTACLE
    assert m.points[:, 2] == pytest.approx(np.ones(len(m.points)))


def floor_patch(x_far: float, half_width: float = 0.3) -> np.ndarray:
    """Camera-frame points of the floor from 1 m ahead out to ``x_far`` (lens 1 m up: z = -1)."""
    xs, ys = np.meshgrid(np.arange(1.0, x_far + 1e-9, 0.05), np.linspace(-half_width, half_width, 13))
    return np.column_stack((xs.ravel(), ys.ravel(), np.full(xs.size, -1.0)))


def test_obstacle_evidence_near_the_end_of_the_seen_floor_clears_slowly():
    # a wall smeared by drift: the floor seen again up to 0.15 m beyond its cell (less than see_past)
    points = wall_observation()
    view = SIMPLE.view(Pose2D(), 0.0, 0.0)
    m = integrate_stereo(ExplorationMap.empty(resolution=0.1), points, apart(points), view)
    assert m.evidence[m.frame.cell_of(np.array([[2.05, 0.05]]))][0] == pytest.approx(0.85)
    floor = floor_patch(2.2)
    for sightings, expected in ((1, Cell.OBSTACLE), (2, Cell.OBSTACLE), (3, Cell.FREE)):  # 0.85 - n * 0.4
        m = integrate_stereo(m, floor, apart(floor), view)
        assert state_at(m, 2.05, 0.05) == expected, sightings
    assert state_at(m, 2.05, 0.55) == Cell.OBSTACLE  # outside the floor patch: still the wall


def test_a_person_seen_and_then_seen_past_is_gone_at_once():
    # a person 2 m ahead, seen in 10 views (a look-around while they wait): evidence at its clamp
    person = np.array([[2.05, y, z] for y in (-0.15, -0.05, 0.05, 0.15) for z in (-0.5, 0.0, 0.5)])
    view = SIMPLE.view(Pose2D(), 0.0, 0.0)
    m = ExplorationMap.empty(resolution=0.1)
    for _ in range(10):
        m = integrate_stereo(m, person, apart(person), view)
    assert m.evidence[m.frame.cell_of(np.array([[2.05, 0.05]]))][0] == pytest.approx(3.5)
    floor = floor_patch(2.9)  # they walked away: the floor there and 0.85 m beyond it is seen
    m = integrate_stereo(m, floor, apart(floor), view)
    assert state_at(m, 2.05, 0.05) == Cell.FREE and state_at(m, 2.05, -0.15) == Cell.FREE
    assert state_at(m, 2.85, 0.05) == Cell.FREE


def test_a_wall_seen_once_and_never_seen_past_stays():
    points = wall_observation()
    ahead = SIMPLE.view(Pose2D(), 0.0, 0.0)
    m = integrate_stereo(ExplorationMap.empty(resolution=0.1), points, apart(points), ahead)
    # views elsewhere (the floor to the left, seen past) and the floor up to the wall ahead again
    left = SIMPLE.view(Pose2D(), math.pi / 2, 0.0)
    floor = floor_patch(2.9)
    short = floor_patch(1.95)  # ends in front of the wall
    for _ in range(20):
        m = integrate_stereo(m, floor, apart(floor), left)
        m = integrate_stereo(m, short, apart(short), ahead)
    assert state_at(m, 2.05, 0.05) == Cell.OBSTACLE
    assert state_at(m, 2.05, 1.55) == Cell.OBSTACLE
    assert state_at(m, 1.45, 0.05) == Cell.FREE and state_at(m, 0.05, 2.45) == Cell.FREE


def test_the_robots_disc_is_free_whatever_was_seen_there():
    points = wall_observation()
    m = integrate_stereo(ExplorationMap.empty(resolution=0.1), points, apart(points), SIMPLE.view(Pose2D(), 0.0, 0.0))
    m = mark_traversed(m, Pose2D(2.05, 0.05), 0.26)
    assert state_at(m, 2.05, 0.05) == Cell.FREE and state_at(m, 2.05, 0.25) == Cell.FREE
    assert state_at(m, 2.05, 0.45) == Cell.OBSTACLE


def test_the_same_observation_twice_adds_nothing():
    # a near wall on the right, a far one on the left, every point 5 px from the next in the image
    near, far = wall_observation(2.05), wall_observation(4.05)
    points = np.concatenate([near[near[:, 1] < 0], far[far[:, 1] >= 0]])
    uv = np.column_stack((np.arange(len(points)) * 5.0, np.zeros(len(points))))
    view = SIMPLE.view(Pose2D(), 0.0, 0.0)
    once = integrate_stereo(ExplorationMap.empty(resolution=0.1), points, uv, view)
    twice = integrate_stereo(once, points, uv, view)
    assert len(twice.points) == len(once.points) == 22 + 23  # 0.1 m voxels of y in [-2.2, 0) and [0, 2.2]
    # only the neighbours across the depth jump make an edge (r = 2.05 / 4.05); along a wall r ~ 1
    assert once.edges.tolist() == twice.edges.tolist() == [[21, 22]]
    assert np.array_equal(twice.cells, once.cells)


def test_image_neighbours_become_edges_with_their_interest():
    # A and B are 5 px apart in the image but 2 m and 5 m away; C is far from both in the image
    points = np.array([[2.0, 0.0, 0.0], [5.0, 0.0, 0.0], [3.0, -1.0, 0.0]])
    uv = np.array([[320.0, 240.0], [325.0, 240.0], [500.0, 240.0]])
    m = integrate_stereo(ExplorationMap.empty(resolution=0.1), points, uv, SIMPLE.view(Pose2D(), 0.0, 0.0))
    assert m.edges.tolist() == [[0, 1]]
    assert m.interest.tolist() == [Interest.WATCH_NOW]  # r = 2/5, straight ahead
    assert closer_points(m, np.array([0.0, 0.0, 1.0]))[0] == pytest.approx([2.0, 0.0, 1.0])


def test_sightings_count_the_observations_of_each_voxel():
    m = ExplorationMap.empty(resolution=0.1, half_size=2.0)
    view = SIMPLE.view(Pose2D(), 0.0, math.radians(-45.0))
    pts = np.array([[2.0, 0.0, -0.5], [2.01, 0.0, -0.5], [2.5, 0.5, -0.2]])  # the first two share a voxel
    uv = np.array([[0.0, 0.0], [100.0, 0.0], [200.0, 0.0]])
    once = integrate_stereo(m, pts, uv, view)
    assert once.sightings.tolist() == [1, 1]
    twice = integrate_stereo(once, pts[:1], uv[:1], view)
    assert twice.sightings.tolist() == [2, 1]
    assert ExplorationMap(m.frame, m.evidence, points=pts).sightings.tolist() == [1, 1, 1]


def test_the_scan_of_an_observation_draws_again_what_was_explored():
    """The range scan kept with an observation (the report's ``scans``) gives the same explored cells."""
    points = wall_observation()
    view = SIMPLE.view(Pose2D(), 0.0, 0.0)
    seen = observe(points, apart(points), view)
    assert len(seen.ranges) == 90 and seen.ranges[45] == pytest.approx(2.05, abs=1e-3)  # 1-degree bins; the wall ahead
    m = integrate_observation(ExplorationMap.empty(resolution=0.1, half_size=5.0), seen)
    drawn = scan_cells(m.frame, view, seen.scan_edges, seen.ranges)
    assert np.array_equal(m.cells == Cell.FREE, drawn & (m.cells != Cell.OBSTACLE))  # the wall's cells are hits
    assert np.array_equal(m.cells, integrate_stereo(ExplorationMap.empty(resolution=0.1), points, apart(points),
                                                    view).cells)


def test_an_echo_clears_the_obstacle_cells_before_it_and_explores_nothing():
    m = ExplorationMap.empty(resolution=0.1)
    evidence = m.evidence.copy()
    rows, cols = m.frame.cell_of(np.array([[0.55, 0.05], [1.05, 0.05], [1.75, 0.05], [0.55, 0.55]]))
    evidence[rows, cols] = 3.5  # a person's cells 0.5 and 1 m ahead, the echo's own, one off the axis
    evidence[m.frame.cell_of(np.array([[0.25, 0.05]]))] = -1.0  # free floor stays as it was
    m = clear_rays(m.replaced(evidence=evidence), np.array([[0.0, 0.05]]), np.array([[1.8, 0.05]]))
    assert state_at(m, 0.55, 0.05) == Cell.FREE and state_at(m, 1.05, 0.05) == Cell.FREE
    assert state_at(m, 1.75, 0.05) == Cell.OBSTACLE  # within see_past of the echo: its own cell
    assert state_at(m, 0.55, 0.55) == Cell.OBSTACLE  # off the axis
    assert m.evidence[m.frame.cell_of(np.array([[0.25, 0.05]]))][0] == pytest.approx(-1.0)
    assert state_at(m, 1.35, 0.05) == Cell.UNKNOWN  # the sonar explores nothing


def test_an_echo_does_not_clear_what_hangs_above_the_sonar():
    # cells 0.5 m, 0.8 m and 1.05 m ahead hold obstacle evidence; the stereo's stored points there: a
    # table top's edge (0.72 m, nothing lower near it), a person (1.5 m and, 0.07 m off, 0.3 m), and a
    # person seen only at 1.2 m but with their legs 0.3 m up in the next cell (0.1 m off)
    m = ExplorationMap.empty(resolution=0.05)
    evidence = m.evidence.copy()
    ahead = np.array([[0.525, 0.025], [0.825, 0.025], [1.075, 0.025], [0.325, 0.025]])
    evidence[m.frame.cell_of(ahead)] = 3.5
    points = np.array([[0.53, 0.02, 0.72],                      # the table top, alone
                       [0.83, 0.02, 1.5], [0.83, 0.09, 0.3],     # a person: head, and legs 0.07 m off
                       [1.07, 0.02, 1.2], [1.17, 0.02, 0.3],     # high here, low 0.1 m on
                       [0.33, 0.02, 1.4]])                       # a shelf, 1.4 m up: above obstacle_height
    m = clear_rays(m.replaced(evidence=evidence, points=points), np.array([[0.0, 0.025]]), np.array([[1.6, 0.025]]))
    assert state_at(m, 0.525, 0.025) == Cell.OBSTACLE  # the sonar passed under the table top
    assert state_at(m, 0.825, 0.025) == Cell.FREE and state_at(m, 1.075, 0.025) == Cell.FREE
    assert state_at(m, 0.325, 0.025) == Cell.FREE  # points above obstacle_height are no obstacle at all
    lower = clear_rays(m.replaced(evidence=evidence, points=points * [1.0, 1.0, 0.5]), np.array([[0.0, 0.025]]),
                       np.array([[1.6, 0.025]]))
    assert state_at(lower, 0.525, 0.025) == Cell.FREE  # the same at 0.36 m: the sonar hears it, and saw past
