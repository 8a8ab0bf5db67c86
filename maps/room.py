"""Room estimate from the dodecagon's 12 stereo pairs (docs/design.md, method 2, "Room estimation").

The robot drives a regular dodecagon (:func:`dodecagon`); at each corner it takes a stereo pair
of parallel images with the rig's known baseline, then turns 30 degrees. Depth along horizontal
epipolar lines (:mod:`perception.stereo`) gives 3-D points; this module turns the 12 point sets
into the free floor space and the distance to the scene in every direction.

Inputs per corner (:class:`StereoView`): the robot's odometry pose there, the camera heading
relative to the robot body (the PTU pan) and the stereo points in the rig's body frame
(``StereoPoints.points``). The rig's placement on the robot is a :class:`RigMount`.

Choices where the paper is vague (each tested in ``tests/maps/test_room.py``):

- **Reference pose**: the robot pose of the corner whose image had the most features
  (``StereoView.features``; by default the number of stereo points, i.e. features matched in
  both images); ties go to the earliest corner. Every output is expressed in the frame of that
  pose: x ahead of the robot there, y to its left.
- **Obstacles**: points between ``min_obstacle_height`` (below: floor texture, which is free
  floor) and ``max_obstacle_height`` above the floor (above: overhangs the robot passes under)
  and within ``max_range`` of the camera (stereo depth error grows with the square of depth).
- **Free floor polygon**: star-shaped around the dodecagon's centre, the only place all 12 views
  share. Directions from the centre are cut into ``direction_bins`` sectors; in each sector the
  ``support``-th nearest obstacle point (not the nearest: one mismatched stereo pair must not
  close a passage) becomes a vertex, at its own measured position, so polygon edges between
  neighbouring vertices on a straight wall lie on that wall. Sectors with fewer points are
  bridged by the chord between their neighbours. A gap wider than ``max_gap`` (the room was not
  seen all around) is an error, not a guess. Space hidden behind an obstacle is not free, except
  the sliver between two neighbouring vertices' chord and the shadow line (a sector wide).
- **Distance to the scene** in a direction (from the centre or any point): the distance along
  that ray to the polygon boundary (:meth:`RoomEstimate.distance_to_scene`).
- **Free grid** (:class:`FreeGrid`): a cell is free when its whole square lies inside the polygon
  (its centre is inside and at least half a cell diagonal from the boundary), so every non-free
  cell may be treated as a solid obstacle square.
- **Where a disc robot may stand** (:meth:`FreeGrid.can_stand`): the Euclidean distance transform
  (``scipy.ndimage.distance_transform_edt``) of the free cells gives, for each free cell centre,
  the distance to the nearest non-free cell centre; a point p in a cell with centre c is at
  least ``edt(c) - cell * sqrt(2)`` from any non-free square (``|p - c|`` and the obstacle's
  offset inside its own square are each at most half a diagonal). A robot of radius r may stand
  at p when ``edt(c) >= r + standing_margin``, ``standing_margin = cell * sqrt(2) + cell / 8``;
  the extra eighth of a cell lets a planner check straight motions every quarter cell and still
  guarantee the clearance between the checked points (see :mod:`maps.planning`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from scipy import ndimage

from perception.camera import StereoRig
from perception.geometry import Pose2D
from perception.stereo import sparse_stereo

CORNERS = 12  # the dodecagon
FREE_CELL = 0.05  # m, the free grid's cell for coverage validity and planning
_RAY_CHUNK = 8192  # rays per vectorised block of ray casting (memory: chunk x edges floats)


class RoomEstimateError(ValueError):
    """The stereo views do not support a room estimate (too few points, a side never seen)."""


@dataclass(frozen=True, slots=True)
class RigMount:
    """Where the stereo rig sits on the robot (REP-103 robot frame, metres).

    ``axis``: the pan axis in the robot frame; ``offset``: the rig's (left camera's) centre on the
    pan head, in the head frame (turns with the pan); ``height``: the rig's optical centre above
    the floor. The rig is level (no tilt) while the room is estimated.
    """

    height: float
    axis: tuple[float, float] = (0.0, 0.0)
    offset: tuple[float, float] = (0.0, 0.0)

    def camera_pose(self, pan: float) -> Pose2D:
        """The rig's planar pose in the robot frame for a pan angle (rad)."""
        c, s = math.cos(pan), math.sin(pan)
        ox, oy = self.offset
        return Pose2D(self.axis[0] + c * ox - s * oy, self.axis[1] + s * ox + c * oy, pan)


@dataclass(frozen=True, eq=False)
class StereoView:
    """One corner of the dodecagon: robot odometry pose, camera pan, stereo points (rig frame).

    ``points`` is N x 3 (``perception.stereo.StereoPoints.points``: x forward, y left, z up, from
    the left camera); non-finite rows are dropped. ``features`` ranks the views for the reference
    pose; -1 means "the number of stereo points".
    """

    pose: Pose2D
    pan: float
    points: np.ndarray
    features: int = -1

    @classmethod
    def from_pair(cls, pose: Pose2D, pan: float, left: np.ndarray, right: np.ndarray, rig: StereoRig,
                  **stereo: Any) -> StereoView:
        """The view of one rectified stereo pair (``perception.stereo.sparse_stereo``, its options)."""
        return cls(pose, pan, sparse_stereo(left, right, rig, **stereo).points)

    def __post_init__(self) -> None:
        pts = np.asarray(self.points, dtype=np.float64).reshape(-1, 3)
        pts = pts[np.isfinite(pts).all(axis=1)]
        object.__setattr__(self, "points", pts)
        if self.features < 0:
            object.__setattr__(self, "features", len(pts))


@dataclass(frozen=True, slots=True)
class RoomParams:
    """Tuning of :func:`estimate_room` (see the module docstring for what each one decides)."""

    direction_bins: int = 180
    support: int = 3
    min_obstacle_height: float = 0.05
    max_obstacle_height: float = math.inf
    max_range: float = 10.0
    max_gap: float = math.radians(45.0)

    def __post_init__(self) -> None:
        if self.direction_bins < 3 or self.support < 1:
            raise ValueError("direction_bins must be >= 3 and support >= 1")
        if not (self.max_range > 0.0 and self.min_obstacle_height < self.max_obstacle_height):
            raise ValueError("max_range must be positive and min_obstacle_height < max_obstacle_height")


@dataclass(frozen=True, eq=False)
class FreeGrid:
    """Free floor on a square grid: ``free[ix, iy]``; cell (0, 0) is centred at ``origin``.

    Coordinates are in the reference frame (metres). Cells outside the array are not free.
    """

    free: np.ndarray
    cell: float
    origin: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        free = np.asarray(self.free, dtype=bool)
        if free.ndim != 2 or 0 in free.shape:
            raise ValueError(f"free must be a non-empty 2-D array, got shape {free.shape}")
        if not self.cell > 0:
            raise ValueError(f"cell must be positive, got {self.cell}")
        object.__setattr__(self, "free", free)
        object.__setattr__(self, "origin", (float(self.origin[0]), float(self.origin[1])))

    @property
    def shape(self) -> tuple[int, int]:
        rows, cols = self.free.shape
        return rows, cols

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(x_min, y_min, x_max, y_max)`` of the grid's outer cell edges."""
        h = self.cell / 2
        nx, ny = self.shape
        return (self.origin[0] - h, self.origin[1] - h, self.origin[0] + (nx - 0.5) * self.cell,
                self.origin[1] + (ny - 0.5) * self.cell)

    def centres(self) -> np.ndarray:
        """Cell centres, ``(nx, ny, 2)``."""
        ix, iy = np.indices(self.shape)
        return np.stack((self.origin[0] + ix * self.cell, self.origin[1] + iy * self.cell), axis=-1)

    def cell_of(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cell indices ``(ix, iy)`` of points (N x 2) and whether each lies on the grid."""
        pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        ix = np.floor((pts[:, 0] - self.origin[0]) / self.cell + 0.5).astype(np.int64)
        iy = np.floor((pts[:, 1] - self.origin[1]) / self.cell + 0.5).astype(np.int64)
        inside = (ix >= 0) & (iy >= 0) & (ix < self.shape[0]) & (iy < self.shape[1])
        return np.where(inside, ix, 0), np.where(inside, iy, 0), inside

    @cached_property
    def clearance(self) -> np.ndarray:
        """Distance (m) from each cell centre to the nearest non-free cell centre (0 when not free)."""
        padded = np.pad(self.free, 1, constant_values=False)  # beyond the grid: unknown, not free
        return ndimage.distance_transform_edt(padded)[1:-1, 1:-1] * self.cell

    @property
    def standing_margin(self) -> float:
        """Clearance a cell centre needs beyond the robot radius (module docstring, "stand")."""
        return self.cell * math.sqrt(2.0) + self.cell / 8.0

    def standable(self, robot_radius: float) -> np.ndarray:
        """Cells ``(nx, ny)`` anywhere in which a disc robot of that radius may stand."""
        return self.clearance >= robot_radius + self.standing_margin

    def can_stand(self, xy: np.ndarray, robot_radius: float) -> np.ndarray:
        """Whether a disc robot of that radius may stand at each point (N x 2)."""
        ix, iy, inside = self.cell_of(xy)
        return inside & self.standable(robot_radius)[ix, iy]

    def regions(self, robot_radius: float) -> np.ndarray:
        """Labels ``(nx, ny)`` of the 8-connected groups of standable cells (0: cannot stand).

        Cells of different groups cannot be joined by any path checked every quarter cell
        (:mod:`maps.planning`), so a different label means "unreachable".
        """
        labels, _ = ndimage.label(self.standable(robot_radius), structure=np.ones((3, 3), dtype=bool))
        return labels

    def region_at(self, xy: np.ndarray, robot_radius: float) -> np.ndarray:
        """The region label (0: cannot stand there) of each point (N x 2)."""
        ix, iy, inside = self.cell_of(xy)
        return np.where(inside, self.regions(robot_radius)[ix, iy], 0)


@dataclass(frozen=True, eq=False)
class RoomEstimate:
    """The free floor polygon around ``centre`` and the reference pose, in the reference frame.

    ``polygon``: V x 2 vertices, counter-clockwise around ``centre``. ``reference_pose``: the
    odometry pose of the reference corner (to convert odometry poses, see :meth:`to_reference`).
    ``corners``: the robot's corner poses in the reference frame; ``obstacle_points``: M x 2
    obstacle points used (reference frame, for display).
    """

    polygon: np.ndarray
    centre: np.ndarray
    reference_pose: Pose2D = Pose2D()
    reference_index: int = 0
    corners: tuple[Pose2D, ...] = ()
    obstacle_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))

    def __post_init__(self) -> None:
        poly = np.asarray(self.polygon, dtype=np.float64).reshape(-1, 2)
        if len(poly) < 3:
            raise ValueError("a room polygon needs at least 3 vertices")
        object.__setattr__(self, "polygon", poly)
        object.__setattr__(self, "centre", np.asarray(self.centre, dtype=np.float64).reshape(2))

    @classmethod
    def from_polygon(cls, polygon: np.ndarray, centre: np.ndarray | None = None) -> RoomEstimate:
        """A room from a known polygon (tests, evaluation against ground truth)."""
        poly = np.asarray(polygon, dtype=np.float64).reshape(-1, 2)
        return cls(poly, poly.mean(axis=0) if centre is None else np.asarray(centre))

    @cached_property
    def free(self) -> FreeGrid:
        """The free grid at ``FREE_CELL`` (5 cm) that coverage and planning share (computed once)."""
        return self.free_grid(FREE_CELL)

    def to_reference(self, odometry: Pose2D) -> Pose2D:
        """An odometry pose expressed in the reference frame."""
        return odometry.relative_to(self.reference_pose)

    def to_odometry(self, pose: Pose2D) -> Pose2D:
        """A reference-frame pose expressed in the odometry frame."""
        return self.reference_pose.compose(pose)

    def contains(self, xy: np.ndarray) -> np.ndarray:
        """Whether points (N x 2) are inside the polygon (even-odd rule)."""
        return _inside_polygon(np.asarray(xy, dtype=np.float64).reshape(-1, 2), self.polygon)

    def boundary_distance(self, xy: np.ndarray) -> np.ndarray:
        """Distance (m) of points (N x 2) to the polygon's boundary."""
        return _distance_to_edges(np.asarray(xy, dtype=np.float64).reshape(-1, 2), self.polygon)

    def distance_to_scene(self, origins: np.ndarray, angles: np.ndarray) -> np.ndarray:
        """Distance (m) from each origin (N x 2) along each angle (N, rad) to the boundary.

        ``inf`` for a ray that meets no edge (an origin outside, looking away).
        """
        o = np.asarray(origins, dtype=np.float64).reshape(-1, 2)
        a = np.broadcast_to(np.asarray(angles, dtype=np.float64), (len(o),))
        return _ray_cast(o, a, self.polygon)

    def distances(self, angles: np.ndarray) -> np.ndarray:
        """Distance (m) from the centre to the scene in each direction (rad): the paper's map."""
        a = np.asarray(angles, dtype=np.float64).ravel()
        return self.distance_to_scene(np.broadcast_to(self.centre, (len(a), 2)), a)

    def free_grid(self, cell: float = FREE_CELL) -> FreeGrid:
        """Cells whose whole square lies inside the polygon (module docstring, "Free grid")."""
        lo = np.floor(self.polygon.min(axis=0) / cell) * cell
        hi = np.ceil(self.polygon.max(axis=0) / cell) * cell
        n = np.round((hi - lo) / cell).astype(int) + 1
        grid = FreeGrid(np.zeros(n, dtype=bool), cell, (float(lo[0]), float(lo[1])))
        centres = grid.centres().reshape(-1, 2)
        inside = self.contains(centres)
        clear = np.zeros(len(centres), dtype=bool)
        clear[inside] = self.boundary_distance(centres[inside]) >= cell * math.sqrt(0.5)
        return FreeGrid(clear.reshape(grid.shape), cell, grid.origin)


def corner_circle(side: float) -> float:
    """The radius of the circle the dodecagon's corners lie on: ``side / (2 sin 15 deg)``."""
    return side / (2.0 * math.sin(math.pi / CORNERS))


def dodecagon_centre(start: Pose2D, side: float) -> tuple[float, float]:
    """The centre of the room-estimation drive's corners from ``start``: the drive turns 30 degrees
    before its first side, so the centre lies :func:`corner_circle` away at 90 + 15 = 105 degrees
    to the start's heading (the angle between a side and the radius at its first corner is 75
    degrees). Until stop 49 this was taken square to the left, 0.125 m off for a 0.25 m side."""
    circle = corner_circle(side)
    bearing = start.theta + math.pi / 2.0 + math.pi / CORNERS
    return start.x + circle * math.cos(bearing), start.y + circle * math.sin(bearing)


def dodecagon(start: Pose2D, side: float) -> tuple[Pose2D, ...]:
    """The 12 corner poses of the room-estimation drive from ``start`` (same frame as start).

    At each corner the robot takes its stereo pair looking ahead, turns 30 degrees to the left,
    then drives ``side`` metres to the next corner, so the views point 30 degrees apart and the
    corners lie on a circle of radius ``side / (2 sin 15 deg)``.
    """
    step = Pose2D(0.0, 0.0, 2.0 * math.pi / CORNERS).compose(Pose2D(side, 0.0, 0.0))
    corners = [Pose2D(start.x, start.y, start.theta)]
    for _ in range(CORNERS - 1):
        corners.append(corners[-1].compose(step))
    return tuple(corners)


def reference_index(views: Sequence[StereoView]) -> int:
    """The corner whose image had the most features (the earliest one on a tie)."""
    if not views:
        raise RoomEstimateError("no stereo views")
    return int(np.argmax([v.features for v in views]))


def obstacle_points(views: Sequence[StereoView], mount: RigMount, reference: Pose2D,
                    params: RoomParams = RoomParams()) -> np.ndarray:
    """Obstacle points (M x 2) of all views in the frame of the ``reference`` odometry pose."""
    chunks = []
    for view in views:
        pts = view.points
        height = pts[:, 2] + mount.height
        keep = ((height >= params.min_obstacle_height) & (height <= params.max_obstacle_height)
                & (np.hypot(pts[:, 0], pts[:, 1]) <= params.max_range))
        camera = view.pose.relative_to(reference).compose(mount.camera_pose(view.pan))
        c, s = math.cos(camera.theta), math.sin(camera.theta)
        xy = pts[keep, :2]
        chunks.append(np.column_stack((camera.x + c * xy[:, 0] - s * xy[:, 1],
                                       camera.y + s * xy[:, 0] + c * xy[:, 1])))
    return np.concatenate(chunks) if chunks else np.zeros((0, 2))


def estimate_room(views: Sequence[StereoView], mount: RigMount, params: RoomParams = RoomParams()
                  ) -> RoomEstimate:
    """The room estimate from the dodecagon's stereo views (see the module docstring).

    Raises :class:`RoomEstimateError` when the points do not enclose the centre.
    """
    ref = reference_index(views)
    reference = views[ref].pose
    corners = tuple(v.pose.relative_to(reference) for v in views)
    centre = np.mean([[c.x, c.y] for c in corners], axis=0)
    points = obstacle_points(views, mount, reference, params)
    vertices = _sector_vertices(points, centre, params)
    return RoomEstimate(vertices, centre, reference, ref, corners, points)


def _sector_vertices(points: np.ndarray, centre: np.ndarray, params: RoomParams) -> np.ndarray:
    """The ``support``-th nearest point of each direction sector, ordered by angle."""
    rel = points - centre
    angle = np.mod(np.arctan2(rel[:, 1], rel[:, 0]), 2.0 * math.pi)
    rng = np.hypot(rel[:, 0], rel[:, 1])
    sector = np.minimum((angle / (2.0 * math.pi) * params.direction_bins).astype(np.int64),
                        params.direction_bins - 1)
    order = np.lexsort((rng, sector))
    counts = np.bincount(sector, minlength=params.direction_bins)
    starts = np.concatenate(([0], np.cumsum(counts)[:-1]))
    supported = counts >= params.support
    if supported.sum() < 3:
        raise RoomEstimateError(f"too few obstacle points: {int(supported.sum())} of {params.direction_bins} "
                                f"directions have {params.support} or more")
    chosen = order[starts[supported] + params.support - 1]
    chosen = chosen[np.argsort(angle[chosen], kind="stable")]
    a = angle[chosen]
    gaps = np.diff(np.concatenate((a, [a[0] + 2.0 * math.pi])))
    if gaps.max() > params.max_gap:
        at = math.degrees(a[int(np.argmax(gaps))])
        raise RoomEstimateError(f"no obstacle seen over {math.degrees(gaps.max()):.0f} deg of directions "
                                f"(from {at:.0f} deg): the views do not go all around")
    return points[chosen]


def _edges(polygon: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return polygon, np.roll(polygon, -1, axis=0) - polygon


def _inside_polygon(xy: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Even-odd test, vectorised over points and edges in blocks."""
    a, e = _edges(polygon)
    out = np.zeros(len(xy), dtype=bool)
    for lo in range(0, len(xy), _RAY_CHUNK):
        p = xy[lo:lo + _RAY_CHUNK, None, :]
        y0, y1 = a[None, :, 1], a[None, :, 1] + e[None, :, 1]
        straddles = (y0 > p[..., 1]) != (y1 > p[..., 1])
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # horizontal edges never straddle
            x_cross = a[None, :, 0] + (p[..., 1] - y0) / e[None, :, 1] * e[None, :, 0]
        out[lo:lo + _RAY_CHUNK] = (np.count_nonzero(straddles & (p[..., 0] < x_cross), axis=1) % 2) == 1
    return out


def _distance_to_edges(xy: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Distance of points to the nearest polygon edge (segments), vectorised in blocks."""
    a, e = _edges(polygon)
    length2 = np.maximum(np.einsum("ij,ij->i", e, e), 1e-300)
    out = np.empty(len(xy))
    for lo in range(0, len(xy), _RAY_CHUNK):
        d = xy[lo:lo + _RAY_CHUNK, None, :] - a[None]
        s = np.clip(np.einsum("nej,ej->ne", d, e) / length2, 0.0, 1.0)
        out[lo:lo + _RAY_CHUNK] = np.linalg.norm(d - s[..., None] * e[None], axis=2).min(axis=1)
    return out


def _ray_cast(origins: np.ndarray, angles: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Nearest positive hit of each ray with the polygon's edges (inf when none)."""
    a, e = _edges(polygon)
    out = np.empty(len(origins))
    for lo in range(0, len(origins), _RAY_CHUNK):
        o = origins[lo:lo + _RAY_CHUNK, None, :]
        ux, uy = np.cos(angles[lo:lo + _RAY_CHUNK])[:, None], np.sin(angles[lo:lo + _RAY_CHUNK])[:, None]
        w = a[None] - o  # origin -> edge start
        denom = ux * e[None, :, 1] - uy * e[None, :, 0]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # parallel edges: masked below
            t = (w[..., 0] * e[None, :, 1] - w[..., 1] * e[None, :, 0]) / denom
            s = (w[..., 0] * uy - w[..., 1] * ux) / denom
        hit = (np.abs(denom) > 1e-15) & (t > 1e-12) & (s >= 0.0) & (s <= 1.0)
        out[lo:lo + _RAY_CHUNK] = np.where(hit, t, np.inf).min(axis=1)
    return out
