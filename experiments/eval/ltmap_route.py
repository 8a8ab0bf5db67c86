"""The route ``bearings eval ltmap`` teaches: a tour of a world's free floor, or given waypoints.

Any world file works, walled or open, large or small: only the floor around the start is looked
at. The default tour, from the world's true start pose S:

1. **Floor.** :func:`drivers.sim.floor.reachable_floor` in a window of :data:`WINDOW` m around S,
   at :data:`RESOLUTION`: the cells the robot's centre can reach. A reachable cell's *clearance*
   is its distance to the nearest unreachable cell (the window's edge counts as one), i.e. how far
   the robot's disc keeps from walls, boxes and pillars beyond its radius.
2. **Distances along the floor** from S (8-connected grid, Dijkstra), so a point behind a wall is
   as far as the way round it.
3. **End and bend**, with a clearance margin m, the first of :data:`MARGINS` that gives a route:

   - the end E: a cell of clearance >= m as far from S along the floor as it goes, up to
     :data:`REACH`; of those within 10 % of the farthest, the one most straight ahead of S's
     heading (the robot sets off forwards);
   - the bend M: a cell of clearance >= m whose floor distances to S and to E add up to at most
     :data:`DETOUR` times S-E, as far as possible from the straight line S-E (then as central,
     then on the left): the route is a tour through the free space that turns, not a straight
     line. A bend less than :data:`MIN_BEND` off the line is dropped (a straight route);
   - legs S-M-E planned by :func:`maps.planning.plan_path` (straight when the segment is free,
     else OMPL) for a disc of the robot's radius plus :data:`PLAN_SAFETY`, so no leg grazes a wall.

   In an open field that is a bent route of about 6 m; in a room, from the start across the
   room's free middle; in a corridor, along it with a slight bend.
4. The polyline, start excluded, in the **odometry frame of the start pose** (x ahead, y left,
   origin at S): the ``route`` input of ``teach_route`` (DriveWaypoints drives it on odometry).

**A route that revisits** (``--option route=back``): the default tour driven out to its end E and
back along itself (the same planned legs, reversed, so just as clear) to the point a third of the
tour's length from S. The way back passes every place of the last two thirds of the tour again,
the bend among them, facing the other way (bearings are compensated for the heading, so a place
is a place): the map sees its far landmarks again and, with gap filling, reports the loops. It
ends away from its start (a third of the tour along the floor), so a repeat that never moves
cannot look home; any world with a default tour has one.

Given waypoints (``--option route=x0,y0,...``, odometry frame as ``teach_route`` takes them) are
checked the same way: every waypoint and every straight leg on the reachable floor.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from drivers.sim.floor import FloorGrid, reachable_floor
from drivers.sim.world import World
from maps.planning import plan_path, segment_is_free
from maps.room import FreeGrid
from perception.geometry import Pose2D, frame_to_parent, parent_to_frame

RESOLUTION = 0.05  # m: the floor grid
REACH = 4.0  # m along the floor: the farthest end of the default tour
DETOUR = 1.5  # the bend's way S-M-E is at most this times S-E
MARGINS = (0.5, 0.35, 0.2, 0.1)  # m of clearance beyond the robot's radius the end and bend keep, tried in turn
MIN_END = 1.0  # m: a tour shorter than this from start to end is no tour
MIN_BEND = 0.3  # m off the line S-E: a smaller bend is dropped
PLAN_SAFETY = 0.1  # m: legs are planned for the robot's radius plus this
WINDOW = DETOUR * REACH + 1.5  # m: half the side of the floor window around the start
ROUTE_WINDOW_MARGIN = 1.5  # m around given waypoints
BACK_TO = 1.0 / 3.0  # the route back along the tour ends this fraction of the tour's length from the start


@dataclass(frozen=True)
class Route:
    """A route to teach: ``world_xy`` (N x 2, the start first, world frame) and ``odometry`` (the
    waypoints after the start, ``[x0, y0, x1, y1, ...]`` in the start's odometry frame)."""

    world_xy: np.ndarray
    odometry: list[float]
    source: str  # "tour" (the default), "back" (out and back along the tour) or "given"
    margin_m: float | None  # the tour's clearance margin; None for given waypoints

    @property
    def length_m(self) -> float:
        return float(np.sum(np.hypot(*np.diff(self.world_xy, axis=0).T)))


def parse_route(text: str) -> list[float]:
    """``x0,y0,x1,y1,...`` (m; brackets allowed) as floats; ``ValueError`` when it is not an even,
    non-empty list of finite numbers."""
    parts = [p.strip() for p in text.strip().strip("[]").split(",") if p.strip()]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise ValueError(f"route: numbers x0,y0,x1,y1,... expected, got {text!r}") from None
    if not values or len(values) % 2 or not all(math.isfinite(v) for v in values):
        raise ValueError(f"route: an even number of finite coordinates x0,y0,x1,y1,... expected, got {text!r}")
    return values


# ------------------------------------------------------------------------------------------------
# The floor around the start


@dataclass(frozen=True)
class Floor:
    """The reachable floor in a window, with clearance and floor distances from the start."""

    grid: FloorGrid
    clearance: np.ndarray  # m, per cell; 0 where not reachable
    start_cell: tuple[int, int]

    @classmethod
    def around(cls, world: World, window: tuple[float, float, float, float]) -> Floor:
        grid = reachable_floor(world, resolution=RESOLUTION, window=window)
        padded = np.pad(grid.reachable, 1, constant_values=False)  # the window's edge bounds the floor
        clearance = ndimage.distance_transform_edt(padded)[1:-1, 1:-1] * RESOLUTION
        rows, cols, _ = grid.cells_of(np.array([[world.start.x, world.start.y]]))
        return cls(grid, np.where(grid.reachable, clearance, 0.0), (int(rows[0]), int(cols[0])))

    def centres(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        g = self.grid
        return np.column_stack((g.x0 + (cols + 0.5) * g.resolution, g.y0 + (rows + 0.5) * g.resolution))

    def distances_from(self, cell: tuple[int, int]) -> np.ndarray:
        """Distance (m) along the reachable floor from ``cell`` to every cell (inf: not reachable)."""
        mask = self.grid.reachable
        index = np.full(mask.shape, -1, dtype=np.int64)
        index[mask] = np.arange(int(np.count_nonzero(mask)))
        padded = np.pad(index, 1, constant_values=-1)
        rows, cols = mask.shape
        heads, tails, weights = [], [], []
        for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):  # every neighbour pair once
            a, b = index, padded[1 + dr:1 + dr + rows, 1 + dc:1 + dc + cols]
            both = (a >= 0) & (b >= 0)
            heads.append(a[both])
            tails.append(b[both])
            weights.append(np.full(int(np.count_nonzero(both)), math.hypot(dr, dc) * RESOLUTION))
        n = int(np.count_nonzero(mask))
        graph = coo_matrix((np.concatenate(weights), (np.concatenate(heads), np.concatenate(tails))), shape=(n, n))
        flat = dijkstra(graph.tocsr(), directed=False, indices=int(index[cell]))
        out = np.full(mask.shape, np.inf)
        out[mask] = flat
        return out

    def free_grid(self) -> FreeGrid:
        """The planner's view of the window (``free[ix, iy]``, cell centres)."""
        g = self.grid
        return FreeGrid(g.free.T, g.resolution, (g.x0 + g.resolution / 2, g.y0 + g.resolution / 2))


def _window(centre: Pose2D, half: float) -> tuple[float, float, float, float]:
    return centre.x - half, centre.y - half, centre.x + half, centre.y + half


# ------------------------------------------------------------------------------------------------
# The default tour


def default_route(world: World) -> Route:
    """The default tour of ``world`` (module docstring); ``ValueError`` when its floor has no room."""
    start = world.start
    floor = Floor.around(world, _window(start, WINDOW))
    from_start = floor.distances_from(floor.start_cell)
    for margin in MARGINS:
        points = _tour(floor, from_start, start, margin, world.robot_radius)
        if points is not None:
            return Route(points, parent_to_frame(start, points[1:]).ravel().tolist(), "tour", margin)
    raise ValueError(f"no room for a route: the floor the robot reaches from the start ({start.x:g}, {start.y:g}) "
                     f"goes less than {MIN_END:g} m with {MARGINS[-1]:g} m of clearance; give waypoints with "
                     "--option route=x0,y0,...")


def back_route(world: World) -> Route:
    """Out along the default tour and back along it to a third of its length (module docstring)."""
    tour = default_route(world)
    way = tour.world_xy
    steps = np.hypot(*np.diff(way, axis=0).T)
    along = np.concatenate(([0.0], np.cumsum(steps)))
    stop = BACK_TO * along[-1]
    k = int(np.searchsorted(along, stop, side="right"))  # way[k - 1] .. way[k] holds the stop
    t = (stop - along[k - 1]) / max(float(steps[k - 1]), 1e-12)
    end = way[k - 1] + t * (way[k] - way[k - 1])
    points = np.vstack((way, way[-2:k - 1:-1] if k < len(way) - 1 else np.zeros((0, 2)), [end]))
    return Route(points, parent_to_frame(world.start, points[1:]).ravel().tolist(), "back", tour.margin_m)


def _tour(floor: Floor, from_start: np.ndarray, start: Pose2D, margin: float, radius: float) -> np.ndarray | None:
    """S, the planned legs through the bend, E (world points), or None when this margin leaves no tour."""
    roomy = (floor.clearance >= margin) & np.isfinite(from_start)
    ends = roomy & (from_start <= REACH)
    if not ends.any() or from_start[ends].max() < MIN_END:
        return None
    far = ends & (from_start >= 0.9 * from_start[ends].max())
    rows, cols = np.nonzero(far)
    xy = floor.centres(rows, cols)
    ahead = np.cos(np.arctan2(xy[:, 1] - start.y, xy[:, 0] - start.x) - start.theta)
    k = int(np.argmax(ahead))
    end_cell, end = (int(rows[k]), int(cols[k])), xy[k]
    s = np.array([start.x, start.y])
    leg_radius = radius + min(margin, PLAN_SAFETY)
    bend = _bend(floor, from_start, roomy, (s, end, end_cell), leg_radius)
    return _plan(floor, [s, *([] if bend is None else [bend]), end], start, leg_radius)


def _bend(floor: Floor, from_start: np.ndarray, roomy: np.ndarray,
          ends: tuple[np.ndarray, np.ndarray, tuple[int, int]], leg_radius: float) -> np.ndarray | None:
    """The bend M (module docstring): in the middle half of the way from S to E, both legs straight
    and clear for ``leg_radius``; None when no such point is MIN_BEND off the line S-E."""
    s, e, end_cell = ends
    from_end = floor.distances_from(end_cell)
    span = from_start[end_cell]
    with np.errstate(invalid="ignore"):  # inf - inf off the floor: not a candidate
        middle = np.abs(from_start - from_end) <= 0.5 * span
    rows, cols = np.nonzero(roomy & middle & (from_start + from_end <= DETOUR * span))
    xy = floor.centres(rows, cols)
    direction = (e - s) / max(float(np.hypot(*(e - s))), 1e-9)
    cross = direction[0] * (xy[:, 1] - s[1]) - direction[1] * (xy[:, 0] - s[0])  # > 0: left of S -> E
    imbalance = np.abs(from_start[rows, cols] - from_end[rows, cols]) / max(span, 1e-9)
    score = np.abs(cross) - 0.05 * imbalance + 1e-3 * (cross > 0)
    free = floor.free_grid()
    for k in np.argsort(-score, kind="stable"):
        if abs(cross[k]) < MIN_BEND:
            return None
        if segment_is_free(free, s, xy[k], leg_radius) and segment_is_free(free, xy[k], e, leg_radius):
            return xy[k]
    return None


def _plan(floor: Floor, points: Sequence[np.ndarray], start: Pose2D, radius: float) -> np.ndarray | None:
    """The planned polyline through ``points`` (world), or None when a leg has no path."""
    free = floor.free_grid()
    out = [np.asarray(points[0], dtype=np.float64)]
    heading = start.theta
    for a, b in zip(points[:-1], points[1:], strict=True):
        result = plan_path(free, Pose2D(float(a[0]), float(a[1]), heading), Pose2D(float(b[0]), float(b[1]), 0.0),
                           robot_radius=radius)
        if not result.ok:
            return None
        out += [np.array([w.x, w.y]) for w in result.waypoints[1:]]
        heading = result.waypoints[-2].theta if len(result.waypoints) > 2 else math.atan2(b[1] - a[1], b[0] - a[0])
    return np.array(out)


# ------------------------------------------------------------------------------------------------
# Given waypoints


def given_route(world: World, odometry: Sequence[float]) -> Route:
    """Waypoints in the start's odometry frame, checked on the floor; ``ValueError`` naming the
    first waypoint or leg off the reachable floor."""
    start = world.start
    points = np.vstack(([[start.x, start.y]], frame_to_parent(start, np.asarray(odometry, dtype=np.float64))))
    lo, hi = points.min(axis=0) - ROUTE_WINDOW_MARGIN, points.max(axis=0) + ROUTE_WINDOW_MARGIN
    floor = Floor.around(world, (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])))
    for k, (a, b) in enumerate(zip(points[:-1], points[1:], strict=True)):
        steps = max(1, math.ceil(float(np.hypot(*(b - a))) / (RESOLUTION / 2)))
        along = a + np.linspace(0.0, 1.0, steps + 1)[:, None] * (b - a)
        if not floor.grid.reachable_at(along[-1:])[0]:
            x, y = odometry[2 * k], odometry[2 * k + 1]
            raise ValueError(f"route: waypoint {k} ({x:g}, {y:g}) is not on the floor the robot reaches from the "
                             f"start (world ({b[0]:.2f}, {b[1]:.2f}))")
        if not floor.grid.reachable_at(along).all():
            raise ValueError(f"route: the leg to waypoint {k} passes closer than the robot's radius to a wall, box "
                             "or pillar")
    return Route(points, [float(v) for v in odometry], "given", None)
