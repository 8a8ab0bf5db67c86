"""The exploration map's drawings: cells as an image and as points, the points, the live interest edges."""

from __future__ import annotations

import numpy as np
import pytest

from behaviours.exploration.drawing import BORDER_COLOUR, FREE_COLOUR, OBSTACLE_COLOUR, map_drawings
from behaviours.telemetry import Lines, Picture, Points
from maps.exploration.grid import Cell, ExplorationMap, GridFrame, borders
from maps.exploration.interest import Interest

FRAME = GridFrame(1.0, 2.0, 0.5, 2, 3)  # x 1..2.5, y 2..3


def small_map(interest: list[Interest]) -> ExplorationMap:
    cells = np.array([[Cell.FREE, Cell.FREE, Cell.OBSTACLE], [Cell.UNKNOWN, Cell.FREE, Cell.FREE]], dtype=np.uint8)
    points = np.array([[1.0, 0.0, 0.5], [2.0, 0.0, 0.5], [3.0, 1.0, 0.5], [6.0, 1.0, 0.5]])
    edges = np.array([[0, 1], [2, 3]])[: len(interest)]
    return ExplorationMap.from_cells(FRAME, cells, points=points, edges=edges,
                                     interest=np.array(interest, dtype=np.uint8))


def test_the_map_as_an_image_on_the_floor_and_its_cells_as_points():
    m = small_map([Interest.WATCH_NOW, Interest.NEVER])
    border = borders(m)
    drawn = {d.entity: d for d in map_drawings(m, border)}
    picture = drawn["odometry_frame/exploration/map"]
    assert isinstance(picture, Picture) and picture.image.shape == (2, 3, 4)
    assert tuple(picture.image[1, 0, :3]) == FREE_COLOUR or tuple(picture.image[1, 0, :3]) == BORDER_COLOUR
    assert tuple(picture.image[1, 2, :3]) == OBSTACLE_COLOUR  # row 0 of the grid is the image's bottom row
    assert picture.image[0, 0, 3] == 0  # unknown: transparent
    origin = drawn["odometry_frame/exploration/map_origin"]
    assert isinstance(origin, Points) and origin.positions.tolist() == [[1.0, 2.0], [2.5, 3.0]]
    obstacles = drawn["odometry_frame/exploration/obstacles"]
    assert isinstance(obstacles, Points) and obstacles.positions.tolist() == [[2.25, 2.25]]
    assert obstacles.radius == pytest.approx(0.25) and obstacles.colours == OBSTACLE_COLOUR
    assert len(drawn["odometry_frame/exploration/explored"].positions) == 4
    assert len(drawn["odometry_frame/exploration/borders"].positions) == int(border.sum())


def test_only_edges_not_yet_never_are_drawn_coloured_by_interest():
    drawn = {d.entity: d for d in map_drawings(small_map([Interest.WATCH_NOW, Interest.NEVER]), np.zeros((2, 3), bool))}
    edges = drawn["exploration_3d/interest_edges"]
    assert isinstance(edges, Lines) and np.asarray(edges.strips).tolist() == [[[1.0, 0.0, 0.5], [2.0, 0.0, 0.5]]]
    assert edges.colours == [(255, 40, 40)]  # watch now: red
    assert len(drawn["exploration_3d/points"].positions) == 4
    retired = map_drawings(small_map([Interest.NEVER, Interest.NEVER]), np.zeros((2, 3), bool))
    assert "exploration_3d/interest_edges" not in {d.entity for d in retired}
