"""The reachable free floor of a simulated world: the reference for "how much was explored".

The walls, box outlines (filled: a box is solid) and pillars of a
:class:`~drivers.sim.world_values.World` are rasterised at ``resolution`` (``cv2`` lines, polygons and
circles, on cell centres), the robot's radius is inflated around them with a Euclidean distance
transform, and the cells its centre can reach from the start pose are one connected component
(``scipy.ndimage.label``, 4-connected). Two masks come out:

- ``reachable``: where the robot's centre can go (clearance to the nearest occupied cell above the
  radius, connected to the start). The exploration criterion (>= 95 % explored) is measured on it.
- ``floor``: the free floor the robot's disc covers while its centre stays in ``reachable``
  (``reachable`` grown by the radius, within free floor): stricter, including the strips along
  the walls.

Accuracy: occupied cells stand for surfaces within half a cell diagonal, so areas are right to
about ``perimeter * resolution``. A world whose reachable part touches the edge of the raster
(no enclosing walls, e.g. ``outdoor``) has no finite reachable floor: ``bounded`` is False there.
This module reads only the :class:`World` value (walls with their points and ``two_sided``,
pillars, start, robot radius, bounds).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from scipy import ndimage

from drivers.sim.world_values import World

_SHIFT = 4  # sub-cell precision (bits) of the cv2 drawing


@dataclass(frozen=True, slots=True)
class FloorGrid:
    """Masks over a grid in the WORLD frame: cell ``(row, col)`` has its centre at
    ``(x0 + (col + 0.5) * resolution, y0 + (row + 0.5) * resolution)``."""

    x0: float
    y0: float
    resolution: float
    free: np.ndarray  # not inside or on a wall, box or pillar
    reachable: np.ndarray  # where the robot's centre can go from the start
    floor: np.ndarray  # the free floor the robot's disc can cover
    bounded: bool  # False: the reachable part runs off the raster (an open world)

    @property
    def reachable_area(self) -> float:
        """m^2 of :attr:`reachable`."""
        return float(np.count_nonzero(self.reachable)) * self.resolution**2

    @property
    def floor_area(self) -> float:
        """m^2 of :attr:`floor`."""
        return float(np.count_nonzero(self.floor)) * self.resolution**2

    def cells_of(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rows, columns and whether inside, of world points (N x 2)."""
        pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        cols = np.floor((pts[:, 0] - self.x0) / self.resolution).astype(np.int64)
        rows = np.floor((pts[:, 1] - self.y0) / self.resolution).astype(np.int64)
        inside = (rows >= 0) & (rows < self.free.shape[0]) & (cols >= 0) & (cols < self.free.shape[1])
        return rows, cols, inside

    def reachable_at(self, xy: np.ndarray) -> np.ndarray:
        """Whether each world point (N x 2) is on :attr:`reachable` (False off the grid)."""
        rows, cols, inside = self.cells_of(xy)
        ok = np.zeros(len(rows), dtype=bool)
        ok[inside] = self.reachable[rows[inside], cols[inside]]
        return ok

    def coverage(self, explored_xy: np.ndarray, mask: str = "reachable") -> float:
        """Fraction of ``mask`` (``reachable`` or ``floor``) with an explored world point in its cell.

        Pass the centres of the explored cells transformed to the world frame, at a resolution no
        coarser than this grid's (coarser leaves cells without a point).
        """
        target = self.reachable if mask == "reachable" else self.floor
        rows, cols, inside = self.cells_of(explored_xy)
        hit = np.zeros(target.shape, dtype=bool)
        hit[rows[inside], cols[inside]] = True
        total = np.count_nonzero(target)
        return float(np.count_nonzero(hit & target)) / total if total else 0.0


def rasterise(world: World, x0: float, y0: float, resolution: float, shape: tuple[int, int]) -> np.ndarray:
    """Occupied cells (bool): wall and box-face lines, box interiors, pillar discs."""
    occupied = np.zeros(shape, dtype=np.uint8)
    scale = 1 << _SHIFT

    def pixels(points: np.ndarray) -> np.ndarray:
        p = (np.asarray(points, dtype=np.float64) - (x0, y0)) / resolution - 0.5
        return np.round(p * scale).astype(np.int32)

    for wall in world.walls:
        outline = pixels(np.asarray(wall.points))
        if not wall.two_sided:  # a box: a closed one-sided outline around solid furniture
            cv2.fillPoly(occupied, [outline], 1, cv2.LINE_8, _SHIFT)
        cv2.polylines(occupied, [outline], False, 1, 1, cv2.LINE_8, _SHIFT)
    for pillar in world.pillars:
        centre = pixels(np.array([pillar.x, pillar.y]))
        radius = int(round(pillar.radius / resolution * scale))
        cv2.circle(occupied, (int(centre[0]), int(centre[1])), radius, 1, -1, cv2.LINE_8, _SHIFT)
    return occupied.astype(bool)


def reached_from(occupied: np.ndarray, resolution: float, radius: float, cell: tuple[int, int]) -> np.ndarray:
    """The cells where the centre of a disc of ``radius`` goes from ``cell`` (row, col), keeping the
    disc off ``occupied`` (bool grid of ``resolution`` m); all False when the disc does not fit at ``cell``."""
    clearance = ndimage.distance_transform_edt(~occupied, sampling=resolution) if occupied.any() else None
    centre_ok = ~occupied if clearance is None else clearance > radius
    labels, _ = ndimage.label(centre_ok)
    start = labels[cell]
    return labels == start if start else np.zeros_like(centre_ok)


def reachable_floor(world: World, resolution: float = 0.05, radius: float | None = None,
                    window: tuple[float, float, float, float] | None = None) -> FloorGrid:
    """The reachable free floor of ``world`` (see the module docstring); ``radius``: the world's robot.

    ``window`` ``(xmin, ymin, xmax, ymax)``: rasterise only that part of the world (it must hold
    the start), e.g. the surroundings of the start in a large or open world; connectivity is then
    judged within the window. Default: the world's bounds plus a margin.
    Raises ``ValueError`` when the start pose is not free for the robot's disc.
    """
    radius = world.robot_radius if radius is None else radius
    margin = radius + 4 * resolution
    xmin, ymin, xmax, ymax = world.bounds() if window is None else window
    if window is not None:
        margin = 0.0
        if not (xmin < world.start.x < xmax and ymin < world.start.y < ymax):
            raise ValueError(f"the window {window} does not hold the start ({world.start.x:g}, {world.start.y:g})")
    x0, y0 = xmin - margin, ymin - margin
    shape = (int(math.ceil((ymax + margin - y0) / resolution)), int(math.ceil((xmax + margin - x0) / resolution)))
    occupied = rasterise(world, x0, y0, resolution, shape)
    row = int(math.floor((world.start.y - y0) / resolution))
    col = int(math.floor((world.start.x - x0) / resolution))
    reachable = reached_from(occupied, resolution, radius, (row, col))
    if not reachable.any():
        where = f"({world.start.x:g}, {world.start.y:g})"
        raise ValueError(f"the start pose {where} is not free for a robot of radius {radius:g} m")
    bounded = not (reachable[0].any() or reachable[-1].any() or reachable[:, 0].any() or reachable[:, -1].any())
    swept = ndimage.distance_transform_edt(~reachable, sampling=resolution) <= radius
    return FloorGrid(x0, y0, resolution, ~occupied, reachable, swept & ~occupied, bounded)
