"""Coverage of the configuration space by images (docs/design.md, method 2, "Coverage").

The robot looks for the user's target images by visiting positions and taking 12 images at
each, one per 30 degrees. A configuration is a robot position and heading, on a grid of
``cell`` (10 cm) by 5-degree heading bins, inside the free space. A configuration is *covered*
once an image has been taken from which a target image taken AT that configuration would have
matched. The next position is the one whose 12 images cover the most uncovered configurations
without fragmenting what is left.

Choices where the paper is vague (each tested in ``tests/maps/test_coverage.py``):

- **Heading bins**: bin ``h`` spans ``[5h, 5h + 5)`` degrees of the reference frame (centre
  ``5h + 2.5``). An image taken with heading ``phi`` serves the bins whose centre is within
  15 degrees of ``phi`` (``|wrap(centre - phi)| < 15``): six bins, so the 12 images of a
  position, 30 degrees apart, serve every bin exactly once and a position's score is a sum.
- **Sensor range** of a target image taken at configuration ``(p_T, theta_T)`` (the
  configurations from which it can still be matched): heading within the same 30-degree sector
  (above) and position within ``reach`` of ``p_T``, a disc whose radius grows with ``D``, the
  distance to the scene along ``theta_T`` from the room estimate:
  ``reach = clip(reach_per_metre * D, min_reach, max_reach)``. Moving ``k D`` sideways turns the
  view of the scene by ``atan(k)`` and moving ``k D`` along the axis changes its scale by up to
  ``1 / (1 - k)``; with ``k = 0.35`` that is 19 degrees and 1.5x, inside what upright SIFT with
  the 0.65 ratio test matches. ``max_reach`` (1.5 m) bounds it because clutter and occlusion
  grow with distance in a room. Reaches are whole cells (``floor(reach / cell)``), the disc is
  ``dx^2 + dy^2 <= r^2`` in cells, and a robot position is snapped to its cell centre, so the
  vectorised scores and :meth:`CoverageGrid.cover` agree exactly.
- **New coverage of every candidate at once**: configurations are grouped by reach ``r``; for
  each group, the uncovered count per position (summed over headings) is convolved with a disc
  of radius ``r`` (``scipy.signal.fftconvolve``): one 2-D FFT convolution per distinct reach
  (at most ``max_reach / cell + 1``), whatever the number of candidates.
- **Fragmentation**: the uncovered configurations split into connected components
  (``scipy.ndimage.label``, face neighbours in (x, y, heading), the heading axis closed into a
  ring with ``scipy.sparse.csgraph.connected_components``). Covering from a candidate that
  raises the component count leaves pieces that each need another visit, so a candidate's score
  is ``new - fragment_cost * max(0, components_after - components_before)``. Labelling costs
  milliseconds per candidate, so it is done lazily: candidates in decreasing order of ``new``
  (an upper bound of the score) until no remaining ``new`` can beat the best score found, which
  gives the exact best; at most ``max_evaluations`` labellings bound the time (past it, the
  best found so far).
- **Fragment cost** (default 72 configurations, one position's full set of headings), measured
  on an 8 x 6 m room with the lab's furniture and pillars, robot radius 0.25 m, 40 positions:
  uncovered fragments left 77 without the penalty, 20 with it; positions to reach 90 % 34 and
  35; straight-line travel to 90 % 133 m and 138 m. The penalty keeps what is left in few
  pieces; it does not shorten the search by itself (the paper's score has no travel term).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, replace
from typing import Any, overload

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from maps.room import FreeGrid, RoomEstimate
from perception.geometry import wrap_angles

HEADING_BIN = math.radians(5.0)
HEADING_BINS = 72
IMAGES_PER_POSITION = 12
SECTOR_HALF_WIDTH = math.pi / IMAGES_PER_POSITION  # 15 degrees
FRAGMENT_COST = 72.0  # configurations: one new fragment weighs as much as a position's 72 headings


@dataclass(frozen=True, slots=True)
class SensorRange:
    """How far from where a target image was taken it can still be matched (module docstring)."""

    reach_per_metre: float = 0.35
    min_reach: float = 0.2
    max_reach: float = 1.5

    def __post_init__(self) -> None:
        if not (self.reach_per_metre >= 0 and 0 <= self.min_reach <= self.max_reach):
            raise ValueError("need reach_per_metre >= 0 and 0 <= min_reach <= max_reach")

    def reach(self, depth: np.ndarray) -> np.ndarray:
        """Reach (m) for distances to the scene (m); non-finite depths get ``max_reach``."""
        d = np.where(np.isfinite(depth), depth, np.inf)
        return np.clip(self.reach_per_metre * d, self.min_reach, self.max_reach)


@dataclass(frozen=True, eq=False)
class CoverageGrid:
    """Configurations ``(ix, iy, h)``: which the robot may occupy, their reach, which are covered.

    ``valid``: ``(nx, ny)`` positions where the robot may stand; ``reach``: ``(nx, ny, H)`` sensor
    reach in cells of the configuration's target image; ``covered``: ``(nx, ny, H)``, only ever
    True on valid positions. Cell ``(0, 0)`` is centred at ``origin`` (reference frame, m).
    Values: :meth:`cover` returns a new grid.
    """

    valid: np.ndarray
    reach: np.ndarray
    covered: np.ndarray
    cell: float = 0.1
    origin: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        valid = np.asarray(self.valid, dtype=bool)
        reach = np.asarray(self.reach, dtype=np.int16)
        covered = np.asarray(self.covered, dtype=bool) & valid[..., None]
        if valid.ndim != 2 or reach.shape != covered.shape or reach.shape[:2] != valid.shape:
            raise ValueError(f"shapes disagree: valid {valid.shape}, reach {reach.shape}, covered {covered.shape}")
        if reach.shape[2] != HEADING_BINS or (reach < 0).any():
            raise ValueError(f"reach must be non-negative, with {HEADING_BINS} heading bins")
        object.__setattr__(self, "valid", valid)
        object.__setattr__(self, "reach", reach)
        object.__setattr__(self, "covered", covered)

    @classmethod
    def empty(cls, valid: np.ndarray, reach_cells: np.ndarray | int, *, cell: float = 0.1,
              origin: tuple[float, float] = (0.0, 0.0)) -> CoverageGrid:
        """Nothing covered yet; ``reach_cells`` per configuration or one value for all."""
        valid = np.asarray(valid, dtype=bool)
        shape = (*valid.shape, HEADING_BINS)
        reach = np.broadcast_to(np.asarray(reach_cells, dtype=np.int16), shape).copy()
        return cls(valid, reach, np.zeros(shape, dtype=bool), cell, origin)

    @property
    def heading_bins(self) -> int:
        return self.reach.shape[2]

    @property
    def uncovered(self) -> np.ndarray:
        """Valid configurations not yet covered, ``(nx, ny, H)``."""
        return self.valid[..., None] & ~self.covered

    @property
    def fraction_covered(self) -> float:
        total = int(self.valid.sum()) * self.heading_bins
        return float(self.covered.sum()) / total if total else 1.0

    def heading_centres(self) -> np.ndarray:
        """Centre of each heading bin (rad, reference frame)."""
        return (np.arange(self.heading_bins) + 0.5) * HEADING_BIN

    @overload
    def position(self, ix: int, iy: int) -> tuple[float, float]: ...
    @overload
    def position(self, ix: np.ndarray, iy: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...

    def position(self, ix: int | np.ndarray, iy: int | np.ndarray) -> tuple[Any, Any]:
        """Reference-frame position (m) of a cell centre; of each cell of index arrays (``np.nonzero``)."""
        return self.origin[0] + ix * self.cell, self.origin[1] + iy * self.cell

    def index(self, x: float, y: float) -> tuple[int, int] | None:
        """The cell of a position, or None off the grid."""
        ix = math.floor((x - self.origin[0]) / self.cell + 0.5)
        iy = math.floor((y - self.origin[1]) / self.cell + 0.5)
        return (ix, iy) if 0 <= ix < self.valid.shape[0] and 0 <= iy < self.valid.shape[1] else None

    def sector_bins(self, heading: float) -> np.ndarray:
        """Bins served by an image taken with this heading (rad): centres within 15 degrees."""
        return np.abs(wrap_angles(self.heading_centres() - heading)) < SECTOR_HALF_WIDTH - 1e-12

    def within_reach(self, ix: int, iy: int) -> np.ndarray:
        """``(nx, ny, H)``: configurations whose target image an image from cell (ix, iy) could match."""
        nx, ny = self.valid.shape
        d2 = (np.arange(nx)[:, None] - ix) ** 2 + (np.arange(ny)[None, :] - iy) ** 2
        return d2[..., None] <= self.reach.astype(np.int64) ** 2

    def cover(self, x: float, y: float, headings: Iterable[float] | None = None) -> CoverageGrid:
        """The grid after images taken at (x, y) with these headings (default: the 12 of a position)."""
        at = self.index(x, y)
        if at is None:
            return self
        served = np.zeros(self.heading_bins, dtype=bool)
        for heading in image_headings() if headings is None else headings:
            served |= self.sector_bins(float(heading))
        newly = self.within_reach(*at) & served[None, None, :] & self.valid[..., None]
        return replace(self, covered=self.covered | newly)


@dataclass(frozen=True, slots=True)
class CoverageChoice:
    """The next position to visit: where, how many configurations it newly covers, its score."""

    x: float
    y: float
    index: tuple[int, int]
    new: int
    fragments_added: int
    score: float
    evaluated: int  # candidates whose fragmentation was computed


def image_headings(first: float = 0.0) -> np.ndarray:
    """The 12 headings (rad) of a position's images, 30 degrees apart from ``first``."""
    return first + np.arange(IMAGES_PER_POSITION) * (2.0 * math.pi / IMAGES_PER_POSITION)


def coverage_grid(room: RoomEstimate, free: FreeGrid, *, robot_radius: float, cell: float = 0.1,
                  sensor: SensorRange = SensorRange()) -> CoverageGrid:
    """Nothing covered yet, over the room's bounding box at ``cell`` and 5-degree headings.

    A position is valid where ``free`` lets the robot stand (:meth:`FreeGrid.can_stand`, the same
    test the planner uses); a configuration's reach comes from the room's distance to the scene
    along the bin's centre heading.
    """
    lo = np.floor(room.polygon.min(axis=0) / cell) * cell
    n = np.round((np.ceil(room.polygon.max(axis=0) / cell) * cell - lo) / cell).astype(int) + 1
    ix, iy = np.indices(n)
    centres = np.stack((lo[0] + ix * cell, lo[1] + iy * cell), axis=-1).reshape(-1, 2)
    valid = free.can_stand(centres, robot_radius)
    heading_bins = HEADING_BINS
    angles = (np.arange(heading_bins) + 0.5) * HEADING_BIN
    reach = np.zeros((len(centres), heading_bins), dtype=np.int16)
    where = np.flatnonzero(valid)
    depth = room.distance_to_scene(np.repeat(centres[where], heading_bins, axis=0), np.tile(angles, len(where)))
    reach[where] = np.floor(sensor.reach(depth) / cell + 1e-9).reshape(len(where), heading_bins)
    return CoverageGrid.empty(valid.reshape(n), reach.reshape(*n, heading_bins), cell=cell,
                              origin=(float(lo[0]), float(lo[1])))


def reachable_positions(grid: CoverageGrid, free: FreeGrid, robot_radius: float, x: float, y: float) -> np.ndarray:
    """``(nx, ny)``: valid positions in the same free region as (x, y) (``candidates`` of :func:`choose_next`)."""
    ix, iy = np.indices(grid.valid.shape)
    centres = np.column_stack((grid.origin[0] + ix.ravel() * grid.cell, grid.origin[1] + iy.ravel() * grid.cell))
    here = free.region_at(np.array([[x, y]]), robot_radius)[0]
    if here == 0:
        return np.zeros(grid.valid.shape, dtype=bool)
    return grid.valid & (free.region_at(centres, robot_radius) == here).reshape(grid.valid.shape)


def sensor_range(grid: CoverageGrid, x: float, y: float, theta: float) -> np.ndarray:
    """``(nx, ny, H)``: configurations from which a target image taken at (x, y, theta) matches.

    Positions within the target configuration's reach, headings in its 30-degree sector.
    """
    at = grid.index(x, y)
    if at is None:
        return np.zeros(grid.reach.shape, dtype=bool)
    h = int(np.mod(theta, 2 * math.pi) // HEADING_BIN) % grid.heading_bins
    nx, ny = grid.valid.shape
    d2 = (np.arange(nx)[:, None] - at[0]) ** 2 + (np.arange(ny)[None, :] - at[1]) ** 2
    near = (d2 <= int(grid.reach[at[0], at[1], h]) ** 2) & grid.valid
    return near[..., None] & grid.sector_bins(theta)[None, None, :]


def newly_covered(grid: CoverageGrid) -> np.ndarray:
    """``(nx, ny)``: configurations the 12 images of each position would newly cover (0 if invalid)."""
    from scipy import signal  # here: importing scipy.signal costs 0.8 s, and every mission load imports this module

    uncovered = grid.uncovered
    total = np.zeros(grid.valid.shape, dtype=np.float64)
    for r in np.unique(grid.reach[uncovered]):
        per_position = (uncovered & (grid.reach == r)).sum(axis=2).astype(np.float64)
        offsets = np.arange(-int(r), int(r) + 1)
        disc = (offsets[:, None] ** 2 + offsets[None, :] ** 2 <= int(r) ** 2).astype(np.float64)
        total += signal.fftconvolve(per_position, disc, mode="same")  # coverage from every position at once
    return np.where(grid.valid, np.rint(total), 0).astype(np.int64)


def count_fragments(uncovered: np.ndarray) -> int:
    """Connected components of a ``(nx, ny, H)`` mask; face neighbours, heading axis a ring."""
    labels, count = ndimage.label(uncovered)
    if count == 0:
        return 0
    first, last = labels[:, :, 0], labels[:, :, -1]
    joined = (first > 0) & (last > 0)  # the same positions at heading bins H-1 and 0 touch
    links = coo_matrix((np.ones(int(joined.sum())), (first[joined], last[joined])), shape=(count + 1, count + 1))
    components, _ = connected_components(links, directed=False)
    return int(components) - 1  # label 0 (covered or invalid) is a component of its own


def choose_next(grid: CoverageGrid, *, fragment_cost: float = FRAGMENT_COST, candidates: np.ndarray | None = None,
                min_new: int = 1, max_evaluations: int = 64) -> CoverageChoice | None:
    """The best next position (module docstring), or None when no candidate covers ``min_new``.

    ``candidates``: optional ``(nx, ny)`` mask of positions allowed (e.g. reachable ones);
    ``fragment_cost``: configurations one extra uncovered fragment is worth.
    """
    new = newly_covered(grid)
    if candidates is not None:
        new = np.where(candidates, new, 0)
    order = np.argsort(-new, axis=None, kind="stable")
    if new.flat[order[0]] < min_new:
        return None
    uncovered = grid.uncovered
    before = count_fragments(uncovered) if fragment_cost > 0 else 0
    best: CoverageChoice | None = None
    evaluated = 0
    for flat in order[:max_evaluations]:
        count = int(new.flat[flat])
        if count < min_new or (best is not None and count <= best.score):
            break  # no later candidate can beat the best: its score is at most its new count
        evaluated += 1
        ix, iy = np.unravel_index(flat, new.shape)
        added = 0
        if fragment_cost > 0:
            after = uncovered & ~(grid.within_reach(int(ix), int(iy)))
            added = max(0, count_fragments(after) - before)
        choice = CoverageChoice(*grid.position(int(ix), int(iy)), (int(ix), int(iy)), count, added,
                                count - fragment_cost * added, 0)
        if best is None or choice.score > best.score:
            best = choice
    return None if best is None else replace(best, evaluated=evaluated)
