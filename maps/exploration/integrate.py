"""One stereo observation into the exploration map (algorithm 3): explored floor, obstacles, points, edges.

The paper is vague in places; the choices made here:

- **What counts as explored** (the observation model of :func:`integrate_stereo`): the points
  on the floor or on obstacles (below ``obstacle_height``) make a virtual range scan: per
  ``scan_bin`` of azimuth across the camera's horizontal field, the plan range of the nearest
  obstacle point, else of the farthest floor point. The floor from where it enters the image (the
  footprint's near edge, ``eye_z / tan(depression)`` along the optical axis, over ``cos`` of the
  azimuth: the image's bottom row is a line on the floor across the axis for a camera without
  roll) out to that range, the footprint's far edge or ``explore_range``, whichever is first, was
  seen free: the image column of a point shows the floor in front of it, and an occluder in
  between would have given a nearer point. Bins without points stay unknown. Points higher than
  ``obstacle_height`` (the ceiling, tops of tall walls) say nothing about the floor below them.
  (Rays to single points instead leave one-cell combs, all border.) ``explore_range`` is
  deliberately shorter than ``max_range`` (stereo depth error grows as Z^2): the points beyond it
  are detected but their floor is not yet explored, which is what gives the attractive power
  (eq. 1) something to aim at.
- **Obstacles** are points between ``floor_tolerance`` and ``obstacle_height`` within
  ``explore_range``. Evidence is accumulated as log-odds
  (:class:`~maps.exploration.grid.EvidenceParams`): a hit adds, a free sighting subtracts, so the
  speckle of a stereo matcher and obstacles smeared by odometry drift clear again when the floor
  is seen there later (sticky obstacles closed the door behind the robot in a simulated run,
  leaving it "done" in one room).
- **Seen past**: what a view sees *past* (the floor ``see_past`` or more beyond a cell, in the same
  bin of the scan, with no point above the floor nearer) cannot be standing there now: a wall hides
  the floor behind it. Such cells take the large step ``EvidenceParams.past`` and become free at
  once, whatever they held; the cells near the end of the view's free floor take the small step
  ``miss`` (a wall smeared by odometry drift lies there, and must not be erased by one view). Without
  it, people walking in the office were mapped as obstacles and stayed (a person waiting in a door
  for 5 s is hit ~10 times: 9 views of the floor there to clear it, and none came), closing the
  corridor and two doors: exploration ended "done" at 39-51 % of the floor. A wall seen once and
  never seen past stays (the tests pin both).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from scipy import ndimage

from maps.exploration.grid import EvidenceParams, ExplorationMap, GridFrame, covering
from maps.exploration.head import CameraView, footprint
from maps.exploration.interest import (
    Interest,
    InterestParams,
    edge_geometry,
    image_edges,
    pair_keys,
    pairs_of_keys,
    reevaluate_interest,
)

_SHIFT = 4  # sub-cell precision (bits) of the scan's wedges drawn by cv2.fillConvexPoly


@dataclass(frozen=True, slots=True)
class IntegrationParams:
    """How a stereo observation becomes map (see the module docstring for the model)."""

    explore_range: float = 3.0  # m (plan): floor is explored, obstacles marked, up to here
    max_range: float = 8.0  # m (plan): farther points are dropped (depth error grows as Z^2)
    floor_tolerance: float = 0.08  # m: points lower are on the floor
    obstacle_height: float = 1.3  # m: points up to this height (and above the floor) are obstacles to the robot
    voxel: float = 0.1  # m: one stored point per voxel
    max_edge_px: float = 12.0  # image neighbours: pixels this close (~1.5 x the step of dense points; ~40 sparse)
    scan_bin: float = math.radians(1.0)  # azimuth bins of the virtual range scan
    see_past: float = 0.3  # m: cells this far or more before the end of a bin's free floor are seen past
    echo_top: float = 0.5  # m: the highest a range echo speaks for (a sonar passes under a table top)
    echo_near: float = 0.1  # m: ... an obstacle point this near a cell, up to echo_top, lets an echo clear it
    evidence: EvidenceParams = EvidenceParams()
    grow_chunk: float = 4.0  # m: the grid grows by multiples of this
    interest: InterestParams = InterestParams()


@dataclass(frozen=True, slots=True)
class StereoObservation:
    """One stereo observation in the odometry frame, ready to integrate: what :func:`observe` made of it.

    ``world``: the points kept (N x 3: finite, within ``max_range`` in plan), ``uv``: their left
    pixels (N x 2), ``plan``: their plan range from the eye (N,), and the observation as a virtual
    range scan (:func:`scan`: bin edges ``scan_edges`` and free ``ranges``), computed once for the
    map and for the record of what was seen (``MapStereo``'s ``scans``).
    """

    view: CameraView
    world: np.ndarray
    uv: np.ndarray
    plan: np.ndarray
    scan_edges: np.ndarray
    ranges: np.ndarray


def observe(
    points_camera: np.ndarray, uv: np.ndarray, view: CameraView, params: IntegrationParams = IntegrationParams()
) -> StereoObservation:
    """One stereo observation in the odometry frame, and its virtual range scan.

    ``points_camera``: (N, 3) points in the left camera's body frame
    (:func:`perception.stereo.dense_samples`); ``uv``: their left-image pixels, for the
    image-neighbour edges; ``view``: where the camera was (:meth:`StereoHead.view` of the odometry
    pose and pan/tilt).
    """
    world = np.asarray(points_camera, dtype=np.float64).reshape(-1, 3) @ view.rotation.T + view.eye
    pix = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    plan = np.hypot(world[:, 0] - view.eye[0], world[:, 1] - view.eye[1])
    ok = np.isfinite(world).all(axis=1) & (plan <= params.max_range)
    world, pix, plan = world[ok], pix[ok], plan[ok]
    edges, ranges = scan(view, world, plan, params)
    return StereoObservation(view, world, pix, plan, edges, ranges)


def integrate_stereo(
    m: ExplorationMap,
    points_camera: np.ndarray,
    uv: np.ndarray,
    view: CameraView,
    params: IntegrationParams = IntegrationParams(),
) -> ExplorationMap:
    """The map after one stereo observation (:func:`observe`, then :func:`integrate_observation`)."""
    return integrate_observation(m, observe(points_camera, uv, view, params), params)


def integrate_observation(
    m: ExplorationMap, seen_now: StereoObservation, params: IntegrationParams = IntegrationParams()
) -> ExplorationMap:
    """The map after one stereo observation (made by :func:`observe` with the same ``params``).

    Marks explored floor and obstacles, adds the points (one per voxel) and their image-neighbour
    edges, and re-evaluates every nearby edge's interest from this view (eq. 2).
    """
    view, world, plan = seen_now.view, seen_now.world, seen_now.plan
    reach = params.explore_range + 2 * m.frame.resolution
    frame, evidence, visited = covering(m, view.eye[:2] - reach, view.eye[:2] + reach, params.grow_chunk)
    seen = past = np.zeros(frame.shape, dtype=bool)
    if len(world):  # the floor between the footprint's near edge and each bin's range (past: well before it)
        seen = scan_cells(frame, view, seen_now.scan_edges, seen_now.ranges)
        past = scan_cells(frame, view, seen_now.scan_edges, seen_now.ranges - params.see_past)
    obstacle = (world[:, 2] > params.floor_tolerance) & (world[:, 2] <= params.obstacle_height)
    obstacle &= plan <= params.explore_range
    hit = np.zeros(frame.shape, dtype=bool)
    hit[frame.cell_of(world[obstacle, :2])] = True
    e = params.evidence
    free = seen & ~hit
    evidence[free] -= np.where(past[free], e.past, e.miss)
    evidence[hit] += e.hit
    np.clip(evidence, e.low, e.high, out=evidence)

    points, index = _merge_points(m.points, world, params.voxel)
    sightings = np.concatenate([m.sightings, np.zeros(len(points) - len(m.points), dtype=np.int32)])
    sightings[np.unique(index)] += 1  # once per observation, however many of its points fall in a voxel
    pairs = image_edges(seen_now.uv, params.max_edge_px)
    r, _, _ = edge_geometry(world[pairs[:, 0]], world[pairs[:, 1]], view.eye, view.heading)
    pairs = pairs[r < params.interest.r_never]  # no depth jump: nothing to look behind, not stored
    edges, interest = _merge_edges(m.edges, m.interest, index[pairs])
    out = ExplorationMap(frame, evidence, points, edges, interest, visited, sightings)
    return reevaluate_interest(out, view.eye, view.heading, params.interest, params.max_range)


def clear_rays(
    m: ExplorationMap, origins: np.ndarray, ends: np.ndarray, params: IntegrationParams = IntegrationParams()
) -> ExplorationMap:
    """The map after range echoes: the cells along each ray from ``origins`` to ``ends`` (N x 2,
    odometry frame), stopped ``see_past`` short of the end, were seen past: their obstacle evidence
    takes the step ``EvidenceParams.past`` (free at once). A range sensor's echo is the nearest
    thing in its cone, so nothing stands on its axis before it; the margin keeps the echo's own
    cells (and its noise) out. Only obstacle cells change: the sonar explores nothing (unknown
    floor stays unknown, for the cameras to see).

    Why: the cameras see nothing within ~0.66 m of the lens; a person who walked past the robot
    close by stayed in the map round it as obstacle cells no view could see past, and in one
    office run every path out of a room corner was blocked by them for 240 s.

    Not what hangs above the sensors: a cell whose stored obstacle points all lie higher than
    ``echo_top``, with none up to that height within ``echo_near`` of it (a table top, a shelf, a
    counter's overhang), stays: a sonar's beam passes under it, and clearing it would send the
    robot's mast into it."""
    f = m.frame
    starts = np.asarray(origins, dtype=np.float64).reshape(-1, 2)
    stops = np.asarray(ends, dtype=np.float64).reshape(-1, 2)
    length = np.hypot(*(stops - starts).T)
    keep = length > params.see_past
    if not keep.any():
        return m
    starts, stops, length = starts[keep], stops[keep], length[keep]
    unit = (stops - starts) / length[:, None]
    steps = [np.arange(0.0, n - params.see_past, f.resolution / 2.0) for n in length]
    xy = np.concatenate([a + np.outer(s, u) for a, s, u in zip(starts, steps, unit, strict=True)])
    rows, cols = f.cell_of(xy)
    inside = f.inside(rows, cols)
    cells = np.unique(rows[inside] * f.cols + cols[inside])
    if len(cells) == 0:
        return m
    r, c = np.divmod(cells, f.cols)
    held = m.evidence[r, c] > 0.0
    held[held] = ~_overhangs(m, r[held], c[held], params)
    if not held.any():
        return m
    evidence = m.evidence.copy()
    evidence[r[held], c[held]] -= params.evidence.past
    return m.replaced(evidence=evidence)


def _overhangs(m: ExplorationMap, rows: np.ndarray, cols: np.ndarray, params: IntegrationParams) -> np.ndarray:
    """Which of the cells (``rows``, ``cols``) hold stored obstacle points only above ``echo_top``,
    with no obstacle point up to that height within ``echo_near``: what a range echo cannot speak for."""
    out = np.zeros(len(rows), dtype=bool)
    if not len(m.points) or not len(rows):
        return out
    reach = int(math.ceil(params.echo_near / m.frame.resolution))
    top, left = rows.min() - reach, cols.min() - reach  # a window round the cells, wide enough for the reach
    shape = (int(rows.max() - top) + reach + 1, int(cols.max() - left) + reach + 1)
    pr, pc = m.frame.cell_of(m.points[:, :2])
    pr, pc, z = pr - top, pc - left, m.points[:, 2]
    near = (pr >= 0) & (pr < shape[0]) & (pc >= 0) & (pc < shape[1])
    near &= (z > params.floor_tolerance) & (z <= params.obstacle_height)  # obstacle points round the cells
    if not near.any():
        return out
    high, low = np.zeros(shape, dtype=bool), np.zeros(shape, dtype=bool)
    above = z > params.echo_top
    high[pr[near & above], pc[near & above]] = True
    low[pr[near & ~above], pc[near & ~above]] = True
    low = ndimage.binary_dilation(low, structure=np.ones((2 * reach + 1, 2 * reach + 1), dtype=bool))
    return high[rows - top, cols - left] & ~low[rows - top, cols - left]


def scan(
    view: CameraView, world: np.ndarray, plan: np.ndarray, params: IntegrationParams
) -> tuple[np.ndarray, np.ndarray]:
    """The observation as a virtual range scan: bin edges (B + 1, rad, left positive, relative to
    the camera axis in plan) and the free range of each bin (B, plan metres from the eye; 0: none).

    A bin's range is that of its nearest obstacle point, else of its farthest floor point; then
    cut at ``explore_range`` and at the far edge of the floor footprint.
    """
    direction, _, far = footprint(view)
    n = max(1, int(math.ceil(view.horizontal_fov / params.scan_bin)))
    edges = np.linspace(-view.horizontal_fov / 2.0, view.horizontal_fov / 2.0, n + 1)
    d = world[:, :2] - view.eye[:2]
    azimuth = np.arctan2(direction[0] * d[:, 1] - direction[1] * d[:, 0], d @ direction)
    bins = np.floor((azimuth - edges[0]) / (edges[1] - edges[0])).astype(np.int64)
    usable = (bins >= 0) & (bins < n) & (world[:, 2] <= params.obstacle_height)
    obstacle = usable & (world[:, 2] > params.floor_tolerance)
    floor = usable & ~obstacle
    nearest_obstacle = np.full(n, np.inf)
    np.minimum.at(nearest_obstacle, bins[obstacle], plan[obstacle])
    farthest_floor = np.zeros(n)
    np.maximum.at(farthest_floor, bins[floor], plan[floor])
    ranges = np.where(np.isfinite(nearest_obstacle), nearest_obstacle, farthest_floor)
    centre = (edges[:-1] + edges[1:]) / 2.0
    return edges, np.minimum(np.minimum(ranges, params.explore_range), far / np.cos(centre))


def scan_cells(frame: GridFrame, view: CameraView, edges: np.ndarray, ranges: np.ndarray) -> np.ndarray:
    """The cells (bool) a scan (:func:`scan`) saw as free floor from ``view``: between the footprint's
    near edge and each bin's range."""
    seen = np.zeros(frame.shape, dtype=np.uint8)
    direction, near, _ = footprint(view)
    if not math.isfinite(near):
        return seen.astype(bool)
    reach = near / np.cos(edges)  # the image's bottom row: a line on the floor across the axis
    c, s = np.cos(edges), np.sin(edges)
    units = np.column_stack((c * direction[0] - s * direction[1], s * direction[0] + c * direction[1]))
    for i in np.flatnonzero(ranges > np.maximum(reach[:-1], reach[1:])):
        corners = view.eye[:2] + np.array(
            [units[i] * reach[i], units[i] * ranges[i], units[i + 1] * ranges[i], units[i + 1] * reach[i + 1]]
        )
        quad = np.round(frame.pixel_of(corners) * (1 << _SHIFT)).astype(np.int32)
        cv2.fillConvexPoly(seen, quad, 1, cv2.LINE_8, _SHIFT)
    return seen > 0


def _voxel_keys(points: np.ndarray, voxel: float) -> np.ndarray:
    q = np.floor(points / voxel).astype(np.int64) + (1 << 20)  # +-1e5 km at 0.1 m voxels
    return (q[:, 0] << 42) | (q[:, 1] << 21) | q[:, 2]


def _merge_points(stored: np.ndarray, new: np.ndarray, voxel: float) -> tuple[np.ndarray, np.ndarray]:
    """Stored points plus the new ones in voxels not yet taken, and the stored index of every new point."""
    if len(new) == 0:
        return stored, np.zeros(0, dtype=np.int64)
    old_keys = _voxel_keys(stored, voxel)
    order = np.argsort(old_keys, kind="stable")
    sorted_keys = old_keys[order]
    keys, first, inverse = np.unique(_voxel_keys(new, voxel), return_index=True, return_inverse=True)
    pos = np.minimum(np.searchsorted(sorted_keys, keys), max(len(sorted_keys) - 1, 0))
    found = (sorted_keys[pos] == keys) if len(sorted_keys) else np.zeros(len(keys), dtype=bool)
    index = np.empty(len(keys), dtype=np.int64)
    index[found] = order[pos[found]]
    fresh = np.flatnonzero(~found)
    fresh = fresh[np.argsort(first[fresh], kind="stable")]  # new points keep their order of arrival
    index[fresh] = len(stored) + np.arange(len(fresh))
    return np.concatenate([stored, new[first[fresh]]]), index[inverse.ravel()]


def _merge_edges(edges: np.ndarray, interest: np.ndarray, new: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stored edges plus the new ones (two distinct points, not stored yet); new ones start WATCH_LATER
    (the caller re-evaluates them at once)."""
    new = np.sort(new.reshape(-1, 2), axis=1)
    keys = np.unique(pair_keys(new[new[:, 0] != new[:, 1]]))
    fresh = pairs_of_keys(keys[~np.isin(keys, pair_keys(edges))])
    states = np.full(len(fresh), Interest.WATCH_LATER, dtype=np.uint8)
    return np.concatenate([edges, fresh]).astype(np.int64), np.concatenate([interest, states])

