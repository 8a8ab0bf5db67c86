"""Travel cost G of eq. 1 by hand: around walls, through gaps the robot fits, known free space only."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration.grid import Cell, ExplorationMap, mark_traversed
from maps.exploration.travel import travel_cost, traversable
from perception.geometry import Pose2D
from tests.maps.exploration_maps import grid_map


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


def test_traversable_cells_have_clearance_beyond_the_radius_or_are_on_the_trail():
    cells = np.full((1, 6), Cell.FREE)
    cells[0, 0] = Cell.OBSTACLE
    m = grid_map(cells)
    assert traversable(m, 0.25).tolist() == [[False, False, False, True, True, True]]  # clearance 0.3 > 0.25
    trail = mark_traversed(m, Pose2D(0.15, 0.05), 0.0, chunk_m=0.1)
    assert trail.visited[trail.frame.cell_of(np.array([[0.15, 0.05]]))][0]
    assert traversable(trail, 0.25)[trail.frame.cell_of(np.array([[0.15, 0.05]]))][0]  # it fitted there


def test_crossing_goes_through_the_least_of_what_closes_the_way_and_never_the_unknown():
    cells = np.full((5, 12), Cell.FREE, dtype=np.uint8)  # 0.1 m cells, a strip 1.2 m long
    cells[:, 5] = Cell.OBSTACLE  # a wall across it
    cells[0, 8] = Cell.UNKNOWN
    m = grid_map(cells)
    assert not np.isfinite(travel_cost(m, (0.25, 0.25), 0.0).at(np.array([[1.05, 0.25]]))[0])
    across = travel_cost(m, (0.25, 0.25), 0.0, crossing=10.0)
    # hand: 8 steps of 0.1 m; the two into and out of the wall cost the mean weight (1 + 10) / 2 each
    assert across.at(np.array([[1.05, 0.25]]))[0] == pytest.approx(6 * 0.1 + 2 * 0.1 * 5.5)
    assert not np.isfinite(across.at(np.array([[0.85, 0.05]]))[0])  # the unknown is never crossed
    closed = np.zeros(m.frame.shape, dtype=bool)
    closed[:, 5] = True
    assert not np.isfinite(travel_cost(m, (0.25, 0.25), 0.0, crossing=10.0, closed=closed).at(
        np.array([[1.05, 0.25]]))[0])
