"""Small exploration maps and views for the tests of :mod:`maps.exploration`."""

from __future__ import annotations

import math

import numpy as np

from maps.exploration.grid import Cell, ExplorationMap, GridFrame
from maps.exploration.head import StereoHead

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
