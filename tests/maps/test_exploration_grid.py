"""The exploration map's grid: frame, read-only arrays, evidence, the robot's disc, borders, clearance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration.grid import Cell, ExplorationMap, GridFrame, borders, mark_traversed
from perception.geometry import Pose2D
from tests.maps.exploration_maps import grid_map, state_at


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


def test_mark_traversed_grows_the_grid_and_marks_a_disc():
    m = mark_traversed(ExplorationMap.empty(resolution=0.1, half_size=1.0), Pose2D(3.0, 0.0), 0.3, chunk_m=1.0)
    assert m.frame.x0 == pytest.approx(-1.0) and m.frame.x0 + m.frame.cols * 0.1 >= 3.4
    assert state_at(m, 3.05, 0.05) == Cell.FREE and state_at(m, 3.25, 0.05) == Cell.FREE
    assert state_at(m, 3.25, 0.25) == Cell.UNKNOWN  # corner of the bounding square, outside the disc
    assert m.explored_area == pytest.approx(math.pi * 0.09, rel=0.15)


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


def test_clearance_is_the_distance_to_the_nearest_obstacle_cell_computed_once():
    cells = np.full((3, 5), Cell.FREE)
    cells[1, 0] = Cell.OBSTACLE
    m = grid_map(cells)
    room = m.clearance
    # by hand: cell (row, col) is sqrt((row - 1)^2 + col^2) cells from the obstacle at (1, 0)
    assert room[1, 0] == 0.0 and room[1, 4] == pytest.approx(0.4) and room[0, 3] == pytest.approx(0.1 * math.sqrt(10))
    assert m.clearance is room  # kept with the frozen map
    with pytest.raises(ValueError):
        room[0, 0] = 1.0
    assert np.all(grid_map(np.full((2, 2), Cell.FREE)).clearance == math.inf)  # no obstacle anywhere
    assert mark_traversed(m, Pose2D(0.25, 0.15), 0.05).clearance is not room  # a new map: computed afresh
