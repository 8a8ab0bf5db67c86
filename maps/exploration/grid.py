"""The exploration map's grid (algorithm 3, Rozman, Zbořil): explored floor, obstacles, the robot's trail, borders.

Everything is in the odometry frame (REP-103: x, y on the floor, z up). The map is a frozen value:
every update returns a new :class:`ExplorationMap`, so a reader on the blackboard never sees a
half-integrated observation. Its parts:

- ``evidence``/``cells``: an occupancy grid (log-odds that a cell is occupied) and the
  :class:`Cell` grid it gives (unknown / explored free / obstacle); it grows in chunks when the
  robot nears its edge.
- ``points``: the 3-D points the stereo pair detected (their floor projections are ``points[:,
  :2]``), one per voxel (``IntegrationParams.voxel`` of :mod:`maps.exploration.integrate`): a
  feature seen again from the same place is the same point, so memory grows with the explored
  volume, not with time.
- ``edges``/``interest``: pairs of points that were neighbours in an image (left pixels at most
  ``max_edge_px`` apart) with a depth jump when seen (r < 0.95), and their
  :class:`~maps.exploration.interest.Interest` state (eq. 2). Neighbours on one surface (r >= 0.95
  at once: nine edges in ten) are not stored: they would be *never* from birth, and the pair seen
  again from elsewhere is judged afresh.
- ``clearance``: the distance from every cell to the nearest obstacle cell, computed once per map
  (goal selection and path following ask for it many times on the same map).

The paper is vague in places; the choices made here (the others are in the docstrings of
:mod:`maps.exploration.integrate`, :mod:`maps.exploration.interest` and
:mod:`maps.exploration.travel`):

- **The blind zone**: a camera 1.1 m up never sees the floor next to the robot (even tilted to
  the PTU-D46's -47 degrees, the footprint starts ~0.4 m in front of the lens). Where the robot
  stands the floor is free: :func:`mark_traversed` marks its disc, every tick; at the start, call
  it with a larger radius (the free floor assumed around the start pose, ~0.6 m) and look around
  (:func:`maps.exploration.gaze.survey`) so that the first footprints join the robot's disc.
- **Borders** are explored free cells with an unknown 4-neighbour, grouped 8-connected; groups
  smaller than ``min_cells`` are dropped (explore_lite's ``min_frontier_size``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any

import numpy as np
from scipy import ndimage

from perception.geometry import Pose2D

_CROSS = ndimage.generate_binary_structure(2, 1)
_SQUARE = ndimage.generate_binary_structure(2, 2)


class Cell(IntEnum):
    """What a grid cell is known to be."""

    UNKNOWN = 0
    FREE = 1  # explored: seen (or driven over) and free
    OBSTACLE = 2


@dataclass(frozen=True, slots=True)
class GridFrame:
    """Where the grid lies in the odometry frame: cell ``(row, col)`` covers
    ``[x0 + col * res, x0 + (col + 1) * res) x [y0 + row * res, y0 + (row + 1) * res)``."""

    x0: float
    y0: float
    resolution: float
    rows: int
    cols: int

    @property
    def shape(self) -> tuple[int, int]:
        return (self.rows, self.cols)

    def cell_of(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Row and column (int64, possibly outside the grid) of each (x, y)."""
        pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        cols = np.floor((pts[:, 0] - self.x0) / self.resolution).astype(np.int64)
        rows = np.floor((pts[:, 1] - self.y0) / self.resolution).astype(np.int64)
        return rows, cols

    def inside(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        return (rows >= 0) & (rows < self.rows) & (cols >= 0) & (cols < self.cols)

    def sample(self, grid: np.ndarray, xy: np.ndarray, outside: Any, dtype: Any = None) -> np.ndarray:
        """The value of ``grid`` (of this frame's shape) at the cell of each (x, y); ``outside`` for a
        point off the grid (``dtype``: the result's, by default ``outside``'s)."""
        rows, cols = self.cell_of(xy)
        inside = self.inside(rows, cols)
        out = np.full(len(rows), outside, dtype=dtype)
        out[inside] = grid[rows[inside], cols[inside]]
        return out

    def centre_of(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """(x, y) of cell centres (N x 2)."""
        r, c = np.asarray(rows, dtype=np.float64), np.asarray(cols, dtype=np.float64)
        return np.column_stack((self.x0 + (c + 0.5) * self.resolution, self.y0 + (r + 0.5) * self.resolution))

    def pixel_of(self, xy: np.ndarray) -> np.ndarray:
        """OpenCV drawing coordinates (x = column, y = row; integers at cell centres)."""
        pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        return np.column_stack(
            ((pts[:, 0] - self.x0) / self.resolution - 0.5, (pts[:, 1] - self.y0) / self.resolution - 0.5)
        )

    def grown(self, lo: tuple[float, float], hi: tuple[float, float], chunk: int) -> tuple[GridFrame, int, int]:
        """A frame covering this one and the box ``lo``..``hi``, grown by multiples of ``chunk`` cells.

        Returns the frame and how many rows and columns were added below and to the left.
        """
        r_lo, c_lo = (int(v[0]) for v in self.cell_of(np.array([lo])))
        r_hi, c_hi = (int(v[0]) for v in self.cell_of(np.array([hi])))

        def pad(before: int, after: int, size: int) -> tuple[int, int]:
            need_lo, need_hi = max(0, -before), max(0, after - (size - 1))
            return -(-need_lo // chunk) * chunk, -(-need_hi // chunk) * chunk

        down, up = pad(r_lo, r_hi, self.rows)
        left, right = pad(c_lo, c_hi, self.cols)
        frame = GridFrame(
            self.x0 - left * self.resolution, self.y0 - down * self.resolution, self.resolution,
            self.rows + down + up, self.cols + left + right,
        )  # fmt: skip
        return frame, down, left


def read_only(a: np.ndarray) -> np.ndarray:
    """A view of ``a`` that cannot be written (the arrays of a frozen map)."""
    view = a.view()
    view.flags.writeable = False
    return view


@dataclass(frozen=True, slots=True)
class EvidenceParams:
    """Log-odds steps of the occupancy evidence (Thrun's occupancy grid): a cell is an obstacle
    while its evidence is positive, explored free while negative, unknown at 0 (never seen).

    Two steps for a cell seen free (the inverse sensor model of
    :func:`maps.exploration.integrate.integrate_observation`): ``miss`` where the view's free floor
    ends near the cell (within ``IntegrationParams.see_past`` of where it ends: a wall smeared by
    drift lies there, so evidence there clears slowly), ``past`` where the view saw the floor well
    beyond the cell with nothing in between: nothing that stands on the floor can be there now (a
    wall would have hidden that floor), so whatever was seen there before walked away. ``past``
    exceeds ``high``: a person who stood in a doorway for a whole look-around is gone from the map at
    the first view past their place; a wall is never seen past, and stays.
    """

    hit: float = 0.85  # an obstacle point in the cell (once per observation)
    miss: float = 0.4  # the cell seen as free floor, near where the view's free floor ends
    past: float = 4.0  # the cell seen as free floor, the floor well beyond it seen too (> high: free at once)
    low: float = -2.0  # clamps: a wall seen 5 times outlives ~10 free sightings (drift), ...
    high: float = 3.5  # ...a single false hit is gone after 3


@dataclass(frozen=True, slots=True)
class ExplorationMap:
    """The exploration map (see the module docstring); arrays are read-only.

    ``evidence``: (rows, cols) float32 log-odds that a cell is occupied (0: never seen);
    ``cells``: the :class:`Cell` grid derived from it (uint8); ``points``: (N, 3) float,
    odometry frame; ``edges``: (M, 2) int64 indices into ``points`` (smaller first);
    ``interest``: (M,) uint8 :class:`~maps.exploration.interest.Interest`; ``visited``: (rows, cols) bool, the cells the
    robot's centre has been on (:func:`mark_traversed`); ``sightings``: (N,) int32, in how many
    observations each point's voxel was seen (a stereo matcher's stray matches are seen once; a
    point given without a count counts once). Points and edges are only ever appended, so their
    indices are stable.
    """

    frame: GridFrame
    evidence: np.ndarray
    points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))
    interest: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.uint8))
    visited: np.ndarray | None = None
    sightings: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))
    cells: np.ndarray = field(init=False, repr=False)
    _clearance: np.ndarray | None = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.evidence.shape != self.frame.shape:
            raise ValueError(f"evidence {self.evidence.shape} does not match the frame {self.frame.shape}")
        if len(self.edges) != len(self.interest):
            raise ValueError("every edge needs an interest state")
        if self.visited is None:
            object.__setattr__(self, "visited", np.zeros(self.frame.shape, dtype=bool))
        if len(self.sightings) == 0 and len(self.points):  # points given without counts count once
            object.__setattr__(self, "sightings", np.ones(len(self.points), dtype=np.int32))
        if len(self.sightings) != len(self.points):
            raise ValueError("every point needs a count of sightings")
        cells = np.where(self.evidence > 0, Cell.OBSTACLE, np.where(self.evidence < 0, Cell.FREE, Cell.UNKNOWN))
        object.__setattr__(self, "cells", cells.astype(np.uint8))
        for name in ("evidence", "visited", "cells", "points", "edges", "interest", "sightings"):
            object.__setattr__(self, name, read_only(getattr(self, name)))

    @classmethod
    def empty(
        cls, resolution: float = 0.05, half_size: float = 5.0, centre: tuple[float, float] = (0.0, 0.0)
    ) -> ExplorationMap:
        """An all-unknown square map of side ``2 * half_size`` m around ``centre``."""
        n = int(math.ceil(2.0 * half_size / resolution))
        frame = GridFrame(centre[0] - half_size, centre[1] - half_size, resolution, n, n)
        return cls(frame, np.zeros(frame.shape, dtype=np.float32))

    @classmethod
    def from_cells(cls, frame: GridFrame, cells: np.ndarray, **arrays: np.ndarray) -> ExplorationMap:
        """A map with the given :class:`Cell` grid (evidence -1 free, +1 obstacle), e.g. for tests."""
        evidence = np.select([cells == Cell.FREE, cells == Cell.OBSTACLE], [-1.0, 1.0], 0.0).astype(np.float32)
        return cls(frame, evidence, **arrays)

    def cell_state(self, xy: np.ndarray) -> np.ndarray:
        """The :class:`Cell` at each (x, y) (UNKNOWN outside the grid)."""
        return self.frame.sample(self.cells, xy, Cell.UNKNOWN, np.uint8)

    @property
    def explored_area(self) -> float:
        """Explored free floor (m^2)."""
        return float(np.count_nonzero(self.cells == Cell.FREE)) * self.frame.resolution**2

    @property
    def clearance(self) -> np.ndarray:
        """Distance (m) from every cell to the nearest obstacle cell (inf without obstacles), read-only.

        Computed on first use and kept (the map is a frozen value, like :class:`maps.room.FreeGrid`'s):
        one goal selection asks for it several times on the same map."""
        room = self._clearance
        if room is None:
            obstacle = self.cells == Cell.OBSTACLE
            if not obstacle.any():
                room = np.full(self.frame.shape, np.inf)
            else:
                room = ndimage.distance_transform_edt(~obstacle, sampling=self.frame.resolution)
            room = read_only(room)
            object.__setattr__(self, "_clearance", room)
        return room

    def replaced(self, **changes: np.ndarray | GridFrame) -> ExplorationMap:
        """This map with some of its arrays (or its frame) replaced: a new map, the cells derived again."""
        names = ("frame", "evidence", "points", "edges", "interest", "visited", "sightings")
        values = {name: getattr(self, name) for name in names}
        values.update(changes)
        return ExplorationMap(**values)


def covering(
    m: ExplorationMap, lo: np.ndarray, hi: np.ndarray, chunk_m: float
) -> tuple[GridFrame, np.ndarray, np.ndarray]:
    """The frame and writable copies of the evidence and visited grids, grown to cover ``lo``..``hi``."""
    chunk = max(1, int(round(chunk_m / m.frame.resolution)))
    frame, down, left = m.frame.grown((float(lo[0]), float(lo[1])), (float(hi[0]), float(hi[1])), chunk)
    old = (slice(down, down + m.frame.rows), slice(left, left + m.frame.cols))
    evidence = np.zeros(frame.shape, dtype=np.float32)
    evidence[old] = m.evidence
    visited = np.zeros(frame.shape, dtype=bool)
    visited[old] = m.visited
    return frame, evidence, visited


def _disc(frame: GridFrame, centre: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of the cells whose centres lie within ``radius`` of ``centre``."""
    r0, c0 = (int(v[0]) for v in frame.cell_of(centre - radius))
    r1, c1 = (int(v[0]) for v in frame.cell_of(centre + radius))
    rows, cols = (a.ravel() for a in np.mgrid[r0 : r1 + 1, c0 : c1 + 1])
    xy = frame.centre_of(rows, cols)
    inside = np.hypot(xy[:, 0] - centre[0], xy[:, 1] - centre[1]) <= radius
    return rows[inside], cols[inside]


def mark_traversed(
    m: ExplorationMap, pose: Pose2D, radius: float, chunk_m: float = 4.0, free: float = EvidenceParams().low
) -> ExplorationMap:
    """The map with the robot at ``pose``: its disc explored free at evidence ``free`` (it stands
    there), and the cells within one cell of its centre ``visited`` (call it every tick: the trail
    stays traversable whatever is seen later, so the robot can always go back the way it came)."""
    centre = np.array([pose.x, pose.y])
    margin = radius + 2 * m.frame.resolution  # keeps the disc off the grid's edge (beyond it: unknown)
    frame, evidence, visited = covering(m, centre - margin, centre + margin, chunk_m)
    disc = _disc(frame, centre, radius)
    evidence[disc] = np.minimum(evidence[disc], free)
    visited[_disc(frame, centre, frame.resolution)] = True
    return m.replaced(frame=frame, evidence=evidence, visited=visited)


def borders(m: ExplorationMap, min_cells: int = 1) -> np.ndarray:
    """Border cells (bool grid): explored free cells with an unknown 4-neighbour, in 8-connected
    groups of at least ``min_cells`` (everything beyond the grid counts as unknown)."""
    near_unknown = ndimage.binary_dilation(m.cells == Cell.UNKNOWN, structure=_CROSS, border_value=1)
    border = (m.cells == Cell.FREE) & near_unknown
    labels, n = ndimage.label(border, structure=_SQUARE)
    if n == 0:
        return border
    keep = np.bincount(labels.ravel()) >= min_cells
    keep[0] = False
    return keep[labels]

