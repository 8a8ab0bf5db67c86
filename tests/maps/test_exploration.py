"""The exploration map: grid, camera geometry, stereo integration, interest edges (eq. 2), borders, G."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration import (
    Cell,
    ExplorationMap,
    GridFrame,
    Interest,
    StereoHead,
    borders,
    classify_interest,
    closer_points,
    edge_geometry,
    footprint,
    image_edges,
    integrate_stereo,
    mark_traversed,
    reevaluate_interest,
    travel_cost,
)
from perception.camera import PinholeCamera
from perception.geometry import Pose2D

# a lens 1 m above the floor right on the pan axis, 90 x 90 degrees: footprints are easy to draw
SIMPLE = StereoHead(ptu=(0.0, 0.0, 1.0), camera=(0.0, 0.0, 0.0), vertical_fov=math.pi / 2, horizontal_fov=math.pi / 2)


def grid_map(cells: np.ndarray, resolution: float = 0.1, **arrays: np.ndarray) -> ExplorationMap:
    """A map whose cell (row, col) has its lower-left corner at (col * res, row * res)."""
    frame = GridFrame(0.0, 0.0, resolution, *cells.shape)
    return ExplorationMap.from_cells(frame, cells, **arrays)


def apart(points: np.ndarray) -> np.ndarray:
    """Pixels far apart from each other: observations without image-neighbour edges."""
    return np.column_stack((np.arange(len(points)) * 100.0, np.zeros(len(points))))


def state_at(m: ExplorationMap, x: float, y: float) -> Cell:
    return Cell(int(m.cell_state(np.array([[x, y]]))[0]))


# --------------------------------------------------------------------------------------------
# Grid and camera geometry


def test_grid_frame_cells_centres_and_growth():
    frame = GridFrame(-1.0, -1.0, 0.5, 4, 4)
    rows, cols = frame.cell_of(np.array([[0.1, -0.9], [-1.2, 0.0]]))
    assert rows.tolist() == [0, 2] and cols.tolist() == [2, -1]
    assert frame.inside(rows, cols).tolist() == [True, False]
    assert frame.centre_of(np.array([0]), np.array([2]))[0] == pytest.approx([0.25, -0.75])
    grown, down, left = frame.grown((-2.2, 0.0), (0.0, 0.0), chunk=2)
    assert (down, left) == (0, 4)  # 3 columns needed, rounded up to the chunk
    assert (grown.x0, grown.y0, grown.rows, grown.cols) == (-3.0, -1.0, 4, 8)


def test_map_arrays_are_read_only_and_cells_follow_the_evidence():
    m = ExplorationMap.empty(resolution=0.1, half_size=1.0)
    with pytest.raises(ValueError):
        m.evidence[0, 0] = -1.0
    with pytest.raises(ValueError):
        m.cells[0, 0] = Cell.FREE
    evidence = np.array([[-0.4, 0.0, 0.45]], dtype=np.float32)
    assert ExplorationMap(GridFrame(0, 0, 0.1, 1, 3), evidence).cells.tolist() == [[1, 0, 2]]


def test_head_view_places_the_left_camera_like_the_simulator():
    head = StereoHead(ptu=(0.1, 0.0, 1.0), camera=(0.05, 0.0, 0.08))
    view = head.view(Pose2D(1.0, 2.0, math.pi / 2), pan=0.0, tilt=0.0)
    assert view.eye == pytest.approx([1.0, 2.15, 1.08])
    assert view.rotation @ np.array([1.0, 0.0, 0.0]) == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)
    panned = head.view(Pose2D(1.0, 2.0, math.pi / 2), pan=math.pi / 2, tilt=0.0)
    assert panned.eye == pytest.approx([0.95, 2.1, 1.08])
    lifted = head.view(Pose2D(), pan=0.0, tilt=math.radians(30))
    # camera offset (0.05, 0, 0.08) lifted by 30 degrees about the tilt axis
    assert lifted.eye == pytest.approx(
        [0.1 + 0.05 * math.cos(math.pi / 6) - 0.04, 0.0, 1.0 + 0.025 + 0.08 * math.cos(math.pi / 6)]
    )
    assert lifted.rotation @ np.array([1.0, 0.0, 0.0]) == pytest.approx([math.cos(math.pi / 6), 0.0, 0.5])


def test_head_fields_of_view_from_the_rig_camera():
    cam = PinholeCamera(640, 480, 320.0, 320.0, 319.5, 239.5)
    head = StereoHead.for_rig(type("Rig", (), {"left": cam})(), (0.1, 0.0, 1.0), (0.05, 0.0, 0.08))
    assert head.horizontal_fov == pytest.approx(math.pi / 2)  # 640 px across at f = 320
    assert head.vertical_fov == pytest.approx(2 * math.atan(240 / 320))


def test_footprint_near_and_far_edges():
    direction, near, far = footprint(SIMPLE.view(Pose2D(), 0.0, 0.0))
    assert direction == pytest.approx([1.0, 0.0]) and near == pytest.approx(1.0) and far == math.inf
    _, near, far = footprint(SIMPLE.view(Pose2D(), 0.0, math.radians(-60)))  # top row 15 deg down
    assert near == pytest.approx(0.0, abs=1e-9) and far == pytest.approx(1.0 / math.tan(math.radians(15)))
    _, near, _ = footprint(SIMPLE.view(Pose2D(), 0.0, math.radians(50)))  # bottom row above the horizon
    assert near == math.inf


# --------------------------------------------------------------------------------------------
# Integration


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


def test_obstacle_evidence_clears_when_the_floor_is_seen_there_again():
    points = wall_observation()
    view = SIMPLE.view(Pose2D(), 0.0, 0.0)
    m = integrate_stereo(ExplorationMap.empty(resolution=0.1), points, apart(points), view)
    assert m.evidence[m.frame.cell_of(np.array([[2.05, 0.05]]))][0] == pytest.approx(0.85)
    xs, ys = np.meshgrid(np.linspace(1.0, 2.9, 39), np.linspace(-0.3, 0.3, 13))
    floor = np.column_stack((xs.ravel(), ys.ravel(), np.full(xs.size, -1.0)))
    for sightings, expected in ((1, Cell.OBSTACLE), (2, Cell.OBSTACLE), (3, Cell.FREE)):  # 0.85 - n * 0.4
        m = integrate_stereo(m, floor, apart(floor), view)
        assert state_at(m, 2.05, 0.05) == expected, sightings
    assert state_at(m, 2.55, 0.05) == Cell.FREE
    assert state_at(m, 2.05, 0.55) == Cell.OBSTACLE  # outside the floor patch: still the wall


def test_the_robots_disc_is_free_whatever_was_seen_there():
    points = wall_observation()
    m = integrate_stereo(ExplorationMap.empty(resolution=0.1), points, apart(points), SIMPLE.view(Pose2D(), 0.0, 0.0))
    m = mark_traversed(m, Pose2D(2.05, 0.05), 0.26)
    assert state_at(m, 2.05, 0.05) == Cell.FREE and state_at(m, 2.05, 0.25) == Cell.FREE
    assert state_at(m, 2.05, 0.45) == Cell.OBSTACLE


def test_mark_traversed_grows_the_grid_and_marks_a_disc():
    m = mark_traversed(ExplorationMap.empty(resolution=0.1, half_size=1.0), Pose2D(3.0, 0.0), 0.3, chunk_m=1.0)
    assert m.frame.x0 == pytest.approx(-1.0) and m.frame.x0 + m.frame.cols * 0.1 >= 3.4
    assert state_at(m, 3.05, 0.05) == Cell.FREE and state_at(m, 3.25, 0.05) == Cell.FREE
    assert state_at(m, 3.25, 0.25) == Cell.UNKNOWN  # corner of the bounding square, outside the disc
    assert m.explored_area == pytest.approx(math.pi * 0.09, rel=0.15)


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


# --------------------------------------------------------------------------------------------
# Interest edges (eq. 2)


def test_eq2_r_and_phi_by_hand():
    eye = np.zeros(3)
    a, b = np.array([[3.0, 4.0, 0.0]]), np.array([[6.0, 8.0, 0.0]])  # 5 m and 10 m away
    r, phi, a_closer = edge_geometry(a, b, eye, heading=0.0)
    assert r == pytest.approx([0.5]) and phi == pytest.approx([math.atan2(4, 3)]) and a_closer.tolist() == [True]
    r, phi, a_closer = edge_geometry(b, a, eye, heading=math.radians(30))
    assert r == pytest.approx([0.5]) and phi == pytest.approx([math.atan2(4, 3) - math.radians(30)])
    assert a_closer.tolist() == [False]


def test_eq2_interest_states_at_the_thresholds():
    r = np.array([0.5, 0.5, 0.5000001, 0.2, 0.94, 0.95, 0.99])
    phi = np.array([math.pi / 6, math.pi / 6 + 1e-6, 0.0, 0.0, 0.0, 0.0, 1.0])
    assert classify_interest(r, phi).tolist() == [
        Interest.WATCH_NOW,
        Interest.WATCH_LATER,  # a big depth jump off to the side: later
        Interest.WATCH_LATER,
        Interest.WATCH_NOW,
        Interest.WATCH_LATER,
        Interest.NEVER,
        Interest.NEVER,
    ]


def test_image_neighbours_become_edges_with_their_interest():
    # A and B are 5 px apart in the image but 2 m and 5 m away; C is far from both in the image
    points = np.array([[2.0, 0.0, 0.0], [5.0, 0.0, 0.0], [3.0, -1.0, 0.0]])
    uv = np.array([[320.0, 240.0], [325.0, 240.0], [500.0, 240.0]])
    m = integrate_stereo(ExplorationMap.empty(resolution=0.1), points, uv, SIMPLE.view(Pose2D(), 0.0, 0.0))
    assert m.edges.tolist() == [[0, 1]]
    assert m.interest.tolist() == [Interest.WATCH_NOW]  # r = 2/5, straight ahead
    assert closer_points(m, np.array([0.0, 0.0, 1.0]))[0] == pytest.approx([2.0, 0.0, 1.0])
    assert image_edges(uv, 5.0).tolist() == [[0, 1]] and image_edges(uv, 4.9).tolist() == []


def test_reevaluation_follows_the_robot_but_never_stays_never():
    points = np.array(
        [[2.0, 0.0, 1.0], [5.0, 0.0, 1.0], [2.0, 3.0, 1.0], [2.05, 3.0, 1.0], [30.0, 0.0, 1.0], [60.0, 0.0, 1.0]]
    )
    edges = np.array([[0, 1], [2, 3], [4, 5]])
    states = np.array([Interest.WATCH_NOW, Interest.NEVER, Interest.WATCH_NOW], dtype=np.uint8)
    m = grid_map(np.zeros((2, 2)), points=points, edges=edges, interest=states)
    turned = reevaluate_interest(m, np.array([0.0, 0.0, 1.0]), heading=math.pi / 2)
    # edge 0: r = 0.4 but 90 degrees off the heading; edge 2: 30 m away, beyond max_range: not touched
    assert turned.interest.tolist() == [Interest.WATCH_LATER, Interest.NEVER, Interest.WATCH_NOW]
    beside = reevaluate_interest(m, np.array([1.95, 3.0, 1.0]), heading=0.0)  # r = 0.05 / 0.1 = 0.5 ahead
    assert beside.interest[1] == Interest.NEVER
    away = reevaluate_interest(m, np.array([-100.0, 0.0, 1.0]), heading=0.0, max_range=200.0)
    assert away.interest[0] == Interest.NEVER  # r = 102 / 105 > 0.95
    assert reevaluate_interest(away, np.array([0.0, 0.0, 1.0]), 0.0).interest[0] == Interest.NEVER


# --------------------------------------------------------------------------------------------
# Borders and travel cost


def test_borders_are_free_cells_next_to_unknown():
    cells = np.zeros((10, 10))
    cells[2:8, 2:8] = Cell.FREE
    cells[1, 2:8] = Cell.OBSTACLE  # the bottom side is walled off
    cells[9, 9] = Cell.FREE  # an isolated speck
    border = borders(grid_map(cells))
    assert border[2:8, 2:8].sum() == 20 - 6 + 2  # the ring, minus the walled side but its two corners
    assert border[7, 2:8].all() and border[2:8, 2].all() and border[2:8, 7].all()
    assert not border[2, 3:7].any() and border[9, 9]
    assert not borders(grid_map(cells), min_cells=2)[9, 9]


def test_travel_cost_goes_around_a_wall_by_hand():
    cells = np.full((5, 10), Cell.FREE)
    cells[0:4, 5] = Cell.OBSTACLE  # a wall with a one-cell gap at the top row
    m = grid_map(cells)
    cost = travel_cost(m, (0.45, 0.05), robot_radius=0.0)
    # up 3, diagonal through the gap, diagonal down, down 3: 6 * 0.1 + 2 * 0.1 * sqrt(2)
    assert cost.at(np.array([[0.65, 0.05]]))[0] == pytest.approx(0.6 + 0.2 * math.sqrt(2))
    assert cost.at(np.array([[0.05, 0.45]]))[0] == pytest.approx(0.4 * math.sqrt(2))
    assert cost.at(np.array([[0.55, 0.05]]))[0] == math.inf  # the wall itself
    path = cost.path_to((0.65, 0.05))
    assert len(path) == 9 and path[0] == pytest.approx([0.45, 0.05]) and path[-1] == pytest.approx([0.65, 0.05])
    assert np.all(np.linalg.norm(np.diff(path, axis=0), axis=1) <= 0.1 * math.sqrt(2) + 1e-9)


def test_a_gap_narrower_than_the_robot_is_not_passable():
    cells = np.full((5, 10), Cell.FREE)
    cells[0:4, 5] = Cell.OBSTACLE
    cost = travel_cost(grid_map(cells), (0.15, 0.05), robot_radius=0.15)
    assert cost.at(np.array([[0.95, 0.05]]))[0] == math.inf
    assert cost.at(np.array([[0.15, 0.35]]))[0] == pytest.approx(0.3)
    assert cost.path_to((0.95, 0.05)).shape == (0, 2)


def test_travel_cost_only_crosses_known_free_space_and_snaps_the_start():
    cells = np.full((3, 12), Cell.FREE)
    cells[:, 6] = Cell.UNKNOWN
    cells[1, 0] = Cell.OBSTACLE
    cost = travel_cost(grid_map(cells), (0.15, 0.15), robot_radius=0.1)  # 0.1 m from the obstacle cell
    assert cost.at(np.array([[1.05, 0.15]]))[0] == math.inf  # beyond the unknown column
    # the start cell is too close to the obstacle: it snaps to the nearest traversable cell, 0.1 m away
    assert cost.at(np.array([[0.25, 0.05]]))[0] == pytest.approx(0.2)
    assert cost.at(np.array([[0.55, 0.05]]))[0] == pytest.approx(0.1 + 0.4)


def test_steps_near_obstacles_cost_more_with_a_margin():
    cells = np.array([[Cell.FREE, Cell.FREE, Cell.FREE], [Cell.UNKNOWN, Cell.OBSTACLE, Cell.UNKNOWN]])
    m = grid_map(cells)
    assert travel_cost(m, (0.05, 0.05), 0.05).at(np.array([[0.25, 0.05]]))[0] == pytest.approx(0.2)
    # clearance 0.1 * sqrt 2 at the ends, 0.1 in the middle: weights 1 + (0.25 - clearance) / 0.2
    end, middle = 1 + (0.25 - 0.1 * math.sqrt(2)) / 0.2, 1 + (0.25 - 0.1) / 0.2
    slow = travel_cost(m, (0.05, 0.05), 0.05, margin=0.2, penalty=1.0)
    assert slow.at(np.array([[0.25, 0.05]]))[0] == pytest.approx(2 * 0.1 * (end + middle) / 2)


def test_the_robots_trail_stays_traversable_through_a_squeeze():
    m = grid_map(np.full((3, 12), Cell.FREE))
    for x in np.arange(0.15, 1.1, 0.05):  # the robot drove along the middle row
        m = mark_traversed(m, Pose2D(x, 0.15), 0.05, chunk_m=0.1)
    evidence = m.evidence.copy()
    evidence[m.frame.cell_of(np.array([[0.55, 0.05], [0.55, 0.25], [0.65, 0.05], [0.65, 0.25]]))] = 1.0
    squeezed = ExplorationMap(m.frame, evidence, visited=m.visited)  # obstacles seen since on both sides
    target = np.array([[1.05, 0.15]])
    assert travel_cost(squeezed, (0.15, 0.15), robot_radius=0.1).at(target)[0] == pytest.approx(0.9)
    forgotten = ExplorationMap(m.frame, evidence)  # the same map without the trail
    assert travel_cost(forgotten, (0.15, 0.15), robot_radius=0.1).at(target)[0] == math.inf


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
