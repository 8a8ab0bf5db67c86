"""The exploration map drawn for the recording (``--save``): one drawing of it, for whoever shows it.

Odometry frame: the explored, obstacle and border cells as an image placed on the floor and as
points; 3-D: the points (a sample) and the interest edges not yet *never* (red: watch now,
yellow: watch later).
"""

from __future__ import annotations

import numpy as np

from behaviours.telemetry import Drawing, Lines, Picture, Points
from maps.exploration.grid import Cell, ExplorationMap
from maps.exploration.interest import Interest

FREE_COLOUR, OBSTACLE_COLOUR, BORDER_COLOUR = (200, 230, 200), (60, 60, 60), (250, 170, 0)
POINT_COLOUR = (120, 120, 255)
INTEREST_COLOURS = {Interest.WATCH_NOW: (255, 40, 40), Interest.WATCH_LATER: (255, 200, 0)}
MAX_POINTS = 5000  # points drawn at most (every k-th)


def map_drawings(m: ExplorationMap, border: np.ndarray) -> list[Drawing]:
    """The map with its ``border`` cells (bool grid, :func:`maps.exploration.grid.borders`)."""
    f = m.frame
    image = np.zeros((*f.shape, 4), dtype=np.uint8)
    image[m.cells == Cell.FREE] = (*FREE_COLOUR, 255)
    image[m.cells == Cell.OBSTACLE] = (*OBSTACLE_COLOUR, 255)
    image[border] = (*BORDER_COLOUR, 255)
    corners = np.array([[f.x0, f.y0], [f.x0 + f.cols * f.resolution, f.y0 + f.rows * f.resolution]])
    drawings: list[Drawing] = [
        Picture("odometry_frame/exploration/map", image[::-1]),  # row 0 at the top in an image
        Points("odometry_frame/exploration/map_origin", corners, [], radius=0.02),  # the viewer's colour
    ]
    for name, cells, colour in (("explored", m.cells == Cell.FREE, FREE_COLOUR), ("borders", border, BORDER_COLOUR),
                                ("obstacles", m.cells == Cell.OBSTACLE, OBSTACLE_COLOUR)):
        rows, cols = np.nonzero(cells)
        drawings.append(Points(f"odometry_frame/exploration/{name}", f.centre_of(rows, cols), colour,
                               radius=f.resolution / 2))
    drawings.append(Points("exploration_3d/points", m.points[:: max(1, len(m.points) // MAX_POINTS)], POINT_COLOUR,
                           radius=0.02))
    live = m.interest != Interest.NEVER
    if live.any():
        strips = np.stack((m.points[m.edges[live, 0]], m.points[m.edges[live, 1]]), axis=1)
        colours = [INTEREST_COLOURS[Interest(int(s))] for s in m.interest[live]]
        drawings.append(Lines("exploration_3d/interest_edges", strips, colours, radius=0.01))
    return drawings
