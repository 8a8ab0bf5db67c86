"""The exploration map's queries (maps/exploration/queries.py) on hand-set grids, values worked by hand.

The grid: 0.1 m cells, x 0-3, y 0-1, free floor; a wall is a column of obstacle cells whose
centres lie at x = 1.05 (y 0.05, 0.15, ..., 0.95).
"""

from __future__ import annotations

import numpy as np
import pytest

from maps.exploration.grid import Cell
from maps.exploration.queries import blocking_cells, disc_cells, free_travel, moved_onto
from perception.geometry import Pose2D
from tests.maps.exploration_maps import grid_map


def floor(wall: Cell | None = Cell.OBSTACLE, row_wall: bool = False):
    cells = np.full((10, 30), Cell.FREE, dtype=np.uint8)
    if wall is not None:
        cells[:, 10] = wall  # x 1.0-1.1
    if row_wall:
        cells[8, :] = Cell.OBSTACLE  # y 0.8-0.9: centres at y 0.85
    return grid_map(cells)


def test_disc_cells_are_those_whose_centres_lie_within_the_radius():
    # a disc of 0.08 m round the corner (0.5, 0.5) holds the four cells round it (centres 0.071 m away)
    assert sorted(disc_cells(floor(), np.array([[0.5, 0.5]]), 0.08).tolist()) == [Cell.FREE] * 4
    # from (0.9, 0.5): the wall cells at y 0.45, 0.55 lie 0.158 m away, those at y 0.35, 0.65 0.212 m
    near = disc_cells(floor(), np.array([[0.9, 0.5]]), 0.2)
    assert np.count_nonzero(near == Cell.OBSTACLE) == 2
    corner = disc_cells(floor(), np.array([[2.98, 0.98]]), 0.1)  # the grid ends at (3, 1): unknown beyond
    assert np.count_nonzero(corner == Cell.UNKNOWN) > 0 and np.count_nonzero(corner == Cell.FREE) > 0


def test_the_cells_blocking_a_path_are_the_obstacle_cells_within_the_radius_of_it():
    path = np.array([[0.5, 0.5], [0.7, 0.5], [0.9, 0.5]])
    blocking = blocking_cells(floor(), path, 0.2)
    assert sorted(map(tuple, np.round(blocking, 3))) == [(1.05, 0.45), (1.05, 0.55)]
    assert blocking_cells(floor(wall=None), path, 0.2).shape == (0, 2)
    assert blocking_cells(floor(), np.zeros((0, 2)), 0.2).shape == (0, 2)


def test_beside_the_trail_only_obstacle_cells_on_the_trail_block_it():
    # the robot drove along y = 0.45 (row 4 visited); the wall column x = 1.05 lies 0.2 m from (0.85, 0.45)
    visited = np.zeros((10, 30), dtype=bool)
    visited[4, :10] = True  # x 0-1: up to the wall, not through it
    m = grid_map(floor().cells, visited=visited)
    on_trail = np.array([[0.85, 0.45]])
    assert len(blocking_cells(m, on_trail, 0.25)) > 0  # without the trail's rule: the wall blocks
    assert blocking_cells(m, on_trail, 0.25, trail=True).shape == (0, 2)  # it fitted there
    off_trail = np.array([[0.85, 0.25]])  # beside the trail: judged as ever
    assert len(blocking_cells(m, off_trail, 0.25, trail=True)) == len(blocking_cells(m, off_trail, 0.25)) > 0
    visited[4, 10] = True  # something stands on the trail itself now (the wall cell (1.05, 0.45))
    stands = blocking_cells(grid_map(floor().cells, visited=visited), on_trail, 0.25, trail=True)
    assert sorted(map(tuple, np.round(stands, 3))) == [(1.05, 0.45)]


def test_moved_onto_when_every_blocking_cell_was_free_floor_before():
    blocking = blocking_cells(floor(), np.array([[0.9, 0.5]]), 0.2)
    assert moved_onto(floor(wall=None), blocking)  # free floor then: someone stepped there
    assert not moved_onto(floor(), blocking)  # an obstacle then too: it was always there
    assert not moved_onto(floor(wall=Cell.UNKNOWN), blocking)  # not seen then: a wall just seen
    assert not moved_onto(floor(wall=None), np.zeros((0, 2)))  # nothing blocks


def test_free_travel_stops_where_an_obstacle_comes_within_the_room_and_not_along_a_wall():
    # straight on from (0.5, 0.5), samples every 0.05 m: at s = 0.25 the wall cell (1.05, 0.45) lies
    # sqrt(0.30^2 + 0.05^2) = 0.304 m from the centre, at s = 0.30 sqrt(0.25^2 + 0.05^2) = 0.255 m < 0.3
    assert free_travel(floor(), Pose2D(0.5, 0.5, 0.0), 0.0, 0.3, 2.0) == pytest.approx(0.3)
    assert free_travel(floor(wall=None), Pose2D(0.5, 0.5, 0.0), 0.0, 0.3, 2.0) == 2.0  # nothing: the reach
    # a wall alongside 0.35 m away, already within a room of 0.4 m: grazing along it is not closing in
    assert free_travel(floor(wall=None, row_wall=True), Pose2D(0.5, 0.5, 0.0), 0.0, 0.4, 1.0) == 1.0
