"""The exploration map of algorithm 3 (Rozman, Zbořil): explored floor, borders, stereo points, interest edges.

Everything is in the odometry frame (REP-103: x, y on the floor, z up). The map is a frozen value:
every update returns a new :class:`ExplorationMap`, so a reader on the blackboard never sees a
half-integrated observation. Its parts:

- ``evidence``/``cells``: an occupancy grid (log-odds that a cell is occupied) and the
  :class:`Cell` grid it gives (unknown / explored free / obstacle); it grows in chunks when the
  robot nears its edge.
- ``points``: the 3-D points the stereo pair detected (their floor projections are ``points[:,
  :2]``), one per voxel (``IntegrationParams.voxel``): a feature seen again from the same place is
  the same point, so memory grows with the explored volume, not with time.
- ``edges``/``interest``: pairs of points that were neighbours in an image (left pixels at most
  ``max_edge_px`` apart) with a depth jump when seen (r < 0.95), and their :class:`Interest`
  state (eq. 2). Neighbours on one surface (r >= 0.95 at once: nine edges in ten) are not
  stored: they would be *never* from birth, and the pair seen again from elsewhere is judged
  afresh.

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
  ``explore_range``. Evidence is accumulated as log-odds (:class:`EvidenceParams`): a hit adds,
  a free sighting subtracts, so the speckle of a stereo matcher and obstacles smeared by odometry
  drift clear again when the floor is seen there later (sticky obstacles closed the door behind
  the robot in a simulated run, leaving it "done" in one room).
- **The blind zone**: a camera 1.1 m up never sees the floor next to the robot (even tilted to
  the PTU-D46's -47 degrees, the footprint starts ~0.4 m in front of the lens). Where the robot
  stands the floor is free: :func:`mark_traversed` marks its disc, every tick; at the start, call
  it with a larger radius (the free floor assumed around the start pose, ~0.6 m) and look around
  (:func:`maps.exploration_gaze.survey`) so that the first footprints join the robot's disc.
- **Borders** are explored free cells with an unknown 4-neighbour, grouped 8-connected; groups
  smaller than ``min_cells`` are dropped (explore_lite's ``min_frontier_size``).
- **Travel cost G(v_S, P_b)** is the 8-connected grid shortest path (Dijkstra from
  ``scipy.sparse.csgraph``, step costs ``res`` and ``res * sqrt 2``) through *known* free space
  whose clearance to the nearest obstacle cell exceeds the robot radius (clearance from
  ``scipy.ndimage.distance_transform_edt``). Unknown cells are not traversed but do not inflate:
  a border next to the unknown must be reachable. The robot's trail (``visited``) is always
  traversable: it fitted there, and new obstacle evidence (a squeeze narrowed by stereo noise)
  must not lock it in a pocket of the map, which would read as "no border reachable", i.e.
  done. A robot standing on a cell that is not traversable starts from the nearest traversable
  cell within one radius, the snap added to every cost. Optionally, steps near obstacles cost more
  (``margin``, ``penalty``), so that paths keep off walls where there is room.
- **Interest edges (eq. 2)**: ``r = p_c / p_f`` with ``p_c``, ``p_f`` the 3-D distances from the
  camera to the edge's closer and farther point, and ``phi`` the angle between the robot's heading
  (its direction of travel) and the direction, in plan, from the camera to the closer point. An
  edge ahead (phi <= pi/6) with a large depth jump (r <= 0.5) is watched now: driving past it
  opens the view behind its closer point, and the gaze control follows it from there up to 90
  degrees (eq. 3). ``r >= 0.95`` (no depth jump left to look behind) makes an edge never
  interesting again, for good; everything else is watch later. The paper names no state for a
  large depth jump off to the side (r <= 0.5, phi > pi/6): it is *watch later*, since turning
  towards it makes it *watch now*. Edges are re-evaluated from the current pose
  (:func:`reevaluate_interest`) only within ``max_range``: r tends to 1 with distance, and an
  edge should not be retired just because the robot went elsewhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntEnum

import cv2
import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from perception.camera import PinholeCamera, StereoRig
from perception.geometry import Pose2D, rot_pitch, rot_z, wrap_angles

_SHIFT = 4  # sub-cell precision (bits) of the scan's wedges drawn by cv2.fillConvexPoly
_CROSS = ndimage.generate_binary_structure(2, 1)
_SQUARE = ndimage.generate_binary_structure(2, 2)


class Cell(IntEnum):
    """What a grid cell is known to be."""

    UNKNOWN = 0
    FREE = 1  # explored: seen (or driven over) and free
    OBSTACLE = 2


class Interest(IntEnum):
    """The interest state of an edge between two image neighbours (eq. 2)."""

    WATCH_NOW = 1
    WATCH_LATER = 2
    NEVER = 3  # never interesting again: sticky


# --------------------------------------------------------------------------------------------
# The grid


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


def _readonly(a: np.ndarray) -> np.ndarray:
    view = a.view()
    view.flags.writeable = False
    return view


@dataclass(frozen=True, slots=True)
class EvidenceParams:
    """Log-odds steps of the occupancy evidence (Thrun's occupancy grid): a cell is an obstacle
    while its evidence is positive, explored free while negative, unknown at 0 (never seen)."""

    hit: float = 0.85  # an obstacle point in the cell (once per observation)
    miss: float = 0.4  # the cell seen as free floor
    low: float = -2.0  # clamps: a wall seen 5 times outlives ~10 free sightings (drift), ...
    high: float = 3.5  # ...a single false hit is gone after 3


@dataclass(frozen=True, slots=True)
class ExplorationMap:
    """The exploration map (see the module docstring); arrays are read-only.

    ``evidence``: (rows, cols) float32 log-odds that a cell is occupied (0: never seen);
    ``cells``: the :class:`Cell` grid derived from it (uint8); ``points``: (N, 3) float,
    odometry frame; ``edges``: (M, 2) int64 indices into ``points`` (smaller first);
    ``interest``: (M,) uint8 :class:`Interest`; ``visited``: (rows, cols) bool, the cells the
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
            object.__setattr__(self, name, _readonly(getattr(self, name)))

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
        rows, cols = self.frame.cell_of(xy)
        inside = self.frame.inside(rows, cols)
        out = np.full(len(rows), Cell.UNKNOWN, dtype=np.uint8)
        out[inside] = self.cells[rows[inside], cols[inside]]
        return out

    @property
    def explored_area(self) -> float:
        """Explored free floor (m^2)."""
        return float(np.count_nonzero(self.cells == Cell.FREE)) * self.frame.resolution**2

    def _replace(self, **changes: np.ndarray | GridFrame) -> ExplorationMap:
        names = ("frame", "evidence", "points", "edges", "interest", "visited", "sightings")
        values = {name: getattr(self, name) for name in names}
        values.update(changes)
        return ExplorationMap(**values)


def _covering(
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
    frame, evidence, visited = _covering(m, centre - margin, centre + margin, chunk_m)
    disc = _disc(frame, centre, radius)
    evidence[disc] = np.minimum(evidence[disc], free)
    visited[_disc(frame, centre, frame.resolution)] = True
    return m._replace(frame=frame, evidence=evidence, visited=visited)


# --------------------------------------------------------------------------------------------
# Where the stereo pair looks from


@dataclass(frozen=True, slots=True)
class CameraView:
    """The left stereo camera at one instant, in the odometry frame.

    ``rotation`` maps camera body vectors (x forward, y left, z up) to the odometry frame;
    ``heading`` is the robot's (its direction of travel, for phi of eq. 2).
    """

    eye: np.ndarray
    rotation: np.ndarray
    vertical_fov: float
    horizontal_fov: float
    heading: float


def vertical_fov(camera: PinholeCamera) -> float:
    """Angle (rad) between the top and bottom edges of the image along its centre column."""
    edges = camera.pixel_to_bearing(np.array([[camera.cx, -0.5], [camera.cx, camera.height - 0.5]]))
    return float(np.arccos(np.clip(edges[0] @ edges[1], -1.0, 1.0)))


def horizontal_fov(camera: PinholeCamera) -> float:
    """Angle (rad) between the left and right edges of the image along its centre row."""
    edges = camera.pixel_to_bearing(np.array([[-0.5, camera.cy], [camera.width - 0.5, camera.cy]]))
    return float(np.arccos(np.clip(edges[0] @ edges[1], -1.0, 1.0)))


@dataclass(frozen=True, slots=True)
class StereoHead:
    """The stereo pair on the pan-tilt unit: the pan/tilt axes' intersection on the base, the left
    camera on the head (both REP-103, metres; the world file's ``ptu.position`` and the camera's
    ``pose``), and the fields of view. Defaults: the simulator's default ``stereo`` camera."""

    ptu: tuple[float, float, float] = (0.1, 0.0, 1.0)
    camera: tuple[float, float, float] = (0.05, 0.0, 0.08)
    vertical_fov: float = 2.0 * math.atan(240.0 / 525.0)
    horizontal_fov: float = 2.0 * math.atan(320.0 / 525.0)

    @classmethod
    def for_rig(cls, rig: StereoRig, ptu: tuple[float, float, float], camera: tuple[float, float, float]) -> StereoHead:
        return cls(ptu, camera, vertical_fov(rig.left), horizontal_fov(rig.left))

    @property
    def lens_height(self) -> float:
        """Height of the lens above the floor with the head level (m)."""
        return self.ptu[2] + self.camera[2]

    def axis_xy(self, robot: Pose2D) -> np.ndarray:
        """Where the pan axis stands on the floor (odometry frame)."""
        c, s = math.cos(robot.theta), math.sin(robot.theta)
        return np.array([robot.x + c * self.ptu[0] - s * self.ptu[1], robot.y + s * self.ptu[0] + c * self.ptu[1]])

    def view(self, robot: Pose2D, pan: float, tilt: float) -> CameraView:
        """The left camera when the base is at ``robot`` (odometry) and the head at (pan, tilt)."""
        rotation = rot_z(robot.theta + pan) @ rot_pitch(tilt)
        head = np.array([*self.axis_xy(robot), self.ptu[2]])
        eye = head + rotation @ np.asarray(self.camera, dtype=np.float64)
        return CameraView(eye, rotation, self.vertical_fov, self.horizontal_fov, robot.theta)


def footprint(view: CameraView) -> tuple[np.ndarray, float, float]:
    """The floor seen by the camera, along its axis: (unit plan direction, near, far distance).

    Near and far are plan distances from the eye to where the bottom and top image rows meet the
    floor (near = inf: the camera sees no floor; far = inf: the top row is above the horizon).
    """
    half = view.vertical_fov / 2.0
    bottom = view.rotation @ np.array([math.cos(half), 0.0, -math.sin(half)])
    top = view.rotation @ np.array([math.cos(half), 0.0, math.sin(half)])
    axis = view.rotation[:2, 0]
    norm = float(np.hypot(*axis))
    direction = axis / norm if norm > 1e-9 else bottom[:2] / max(float(np.hypot(*bottom[:2])), 1e-12)

    def reach(ray: np.ndarray) -> float:
        if ray[2] >= -1e-12:
            return math.inf
        return max(0.0, float(view.eye[2] * (ray[:2] @ direction) / -ray[2]))  # 0: the floor under the eye

    return direction, reach(bottom), reach(top)


# --------------------------------------------------------------------------------------------
# Interest edges (eq. 2)


@dataclass(frozen=True, slots=True)
class InterestParams:
    """Thresholds of eq. 2 (the paper's values)."""

    r_now: float = 0.5
    r_never: float = 0.95
    phi_now: float = math.pi / 6.0


def edge_geometry(
    a: np.ndarray, b: np.ndarray, eye: np.ndarray, heading: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``r``, ``phi`` of eq. 2 for edges a-b seen from ``eye``, and whether ``a`` is the closer point."""
    da = np.linalg.norm(np.asarray(a, dtype=np.float64).reshape(-1, 3) - eye, axis=1)
    db = np.linalg.norm(np.asarray(b, dtype=np.float64).reshape(-1, 3) - eye, axis=1)
    a_closer = da <= db
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.where(a_closer, da, db) / np.maximum(np.where(a_closer, db, da), 1e-12)  # eq. 2: r = p_c / p_f
    closer = np.where(a_closer[:, None], np.reshape(a, (-1, 3)), np.reshape(b, (-1, 3)))
    phi = np.abs(wrap_angles(np.arctan2(closer[:, 1] - eye[1], closer[:, 0] - eye[0]) - heading))  # eq. 2: phi
    return r, phi, a_closer


def classify_interest(r: np.ndarray, phi: np.ndarray, params: InterestParams = InterestParams()) -> np.ndarray:
    """Interest state from r and phi (eq. 2): r <= 0.5 and phi <= pi/6 now, r >= 0.95 never, else later."""
    r, phi = np.asarray(r, dtype=np.float64), np.asarray(phi, dtype=np.float64)
    state = np.full(r.shape, Interest.WATCH_LATER, dtype=np.uint8)
    state[(r <= params.r_now) & (phi <= params.phi_now)] = Interest.WATCH_NOW
    state[r >= params.r_never] = Interest.NEVER
    return state


def reevaluate_interest(
    m: ExplorationMap,
    eye: np.ndarray,
    heading: float,
    params: InterestParams = InterestParams(),
    max_range: float = 8.0,
) -> ExplorationMap:
    """The map with every edge within ``max_range`` of ``eye`` re-classified from there (NEVER stays)."""
    if len(m.edges) == 0:
        return m
    a, b = m.points[m.edges[:, 0]], m.points[m.edges[:, 1]]
    near = np.minimum(np.linalg.norm(a - eye, axis=1), np.linalg.norm(b - eye, axis=1)) <= max_range
    live = near & (m.interest != Interest.NEVER)
    if not live.any():
        return m
    r, phi, _ = edge_geometry(a[live], b[live], eye, heading)
    interest = m.interest.copy()
    interest[live] = classify_interest(r, phi, params)
    return m._replace(interest=interest)


def closer_points(m: ExplorationMap, eye: np.ndarray) -> np.ndarray:
    """The closer endpoint (M x 3) of every edge seen from ``eye``: the point to watch."""
    a, b = m.points[m.edges[:, 0]], m.points[m.edges[:, 1]]
    a_closer = np.linalg.norm(a - eye, axis=1) <= np.linalg.norm(b - eye, axis=1)
    return np.where(a_closer[:, None], a, b)


def image_edges(uv: np.ndarray, max_px: float) -> np.ndarray:
    """Pairs (K x 2, smaller index first, sorted) of image neighbours: pixels at most ``max_px`` apart."""
    pts = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    if len(pts) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    pairs = cKDTree(pts).query_pairs(max_px, output_type="ndarray").astype(np.int64)
    return _unpack(np.unique(_pack(np.sort(pairs, axis=1))))


# --------------------------------------------------------------------------------------------
# Integration of one stereo observation


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
    evidence: EvidenceParams = EvidenceParams()
    grow_chunk: float = 4.0  # m: the grid grows by multiples of this
    interest: InterestParams = InterestParams()


def integrate_stereo(
    m: ExplorationMap,
    points_camera: np.ndarray,
    uv: np.ndarray,
    view: CameraView,
    params: IntegrationParams = IntegrationParams(),
) -> ExplorationMap:
    """The map after one stereo observation.

    ``points_camera``: (N, 3) points in the left camera's body frame (``StereoPoints.points``);
    ``uv``: their left-image pixels (``StereoPoints.uv_left``), for the image-neighbour edges;
    ``view``: where the camera was (:meth:`StereoHead.view` of the odometry pose and pan/tilt).
    Marks explored floor and obstacles, adds the points (one per voxel) and their image-neighbour
    edges, and re-evaluates every nearby edge's interest from this view (eq. 2).
    """
    world = np.asarray(points_camera, dtype=np.float64).reshape(-1, 3) @ view.rotation.T + view.eye
    pix = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    plan = np.hypot(world[:, 0] - view.eye[0], world[:, 1] - view.eye[1])
    ok = np.isfinite(world).all(axis=1) & (plan <= params.max_range)
    world, pix, plan = world[ok], pix[ok], plan[ok]

    reach = params.explore_range + 2 * m.frame.resolution
    frame, evidence, visited = _covering(m, view.eye[:2] - reach, view.eye[:2] + reach, params.grow_chunk)
    seen = _scan_mask(frame, view, world, plan, params)
    obstacle = (world[:, 2] > params.floor_tolerance) & (world[:, 2] <= params.obstacle_height)
    obstacle &= plan <= params.explore_range
    hit = np.zeros(frame.shape, dtype=bool)
    hit[frame.cell_of(world[obstacle, :2])] = True
    e = params.evidence
    evidence[seen & ~hit] -= e.miss
    evidence[hit] += e.hit
    np.clip(evidence, e.low, e.high, out=evidence)

    points, index = _merge_points(m.points, world, params.voxel)
    sightings = np.concatenate([m.sightings, np.zeros(len(points) - len(m.points), dtype=np.int32)])
    sightings[np.unique(index)] += 1  # once per observation, however many of its points fall in a voxel
    pairs = image_edges(pix, params.max_edge_px)
    r, _, _ = edge_geometry(world[pairs[:, 0]], world[pairs[:, 1]], view.eye, view.heading)
    pairs = pairs[r < params.interest.r_never]  # no depth jump: nothing to look behind, not stored
    edges, interest = _merge_edges(m.edges, m.interest, index[pairs])
    out = ExplorationMap(frame, evidence, points, edges, interest, visited, sightings)
    return reevaluate_interest(out, view.eye, view.heading, params.interest, params.max_range)


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


def observation_scan(
    points_camera: np.ndarray, view: CameraView, params: IntegrationParams = IntegrationParams()
) -> tuple[np.ndarray, np.ndarray]:
    """The virtual range scan (:func:`scan`) of one stereo observation, as :func:`integrate_stereo`
    draws it: for a record of what was seen that can be drawn again elsewhere (:func:`scan_cells`)."""
    world = np.asarray(points_camera, dtype=np.float64).reshape(-1, 3) @ view.rotation.T + view.eye
    plan = np.hypot(world[:, 0] - view.eye[0], world[:, 1] - view.eye[1])
    ok = np.isfinite(world).all(axis=1) & (plan <= params.max_range)
    return scan(view, world[ok], plan[ok], params)


def _scan_mask(
    frame: GridFrame, view: CameraView, world: np.ndarray, plan: np.ndarray, params: IntegrationParams
) -> np.ndarray:
    """The cells (bool) seen as free floor: between the footprint's near edge and each bin's range."""
    if len(world) == 0:
        return np.zeros(frame.shape, dtype=bool)
    edges, ranges = scan(view, world, plan, params)
    return scan_cells(frame, view, edges, ranges)


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


def _pack(pairs: np.ndarray) -> np.ndarray:
    """One int64 key per index pair (indices below 2^31)."""
    return (pairs[:, 0].astype(np.int64) << 32) | pairs[:, 1].astype(np.int64)


def _unpack(keys: np.ndarray) -> np.ndarray:
    return np.column_stack((keys >> 32, keys & 0xFFFFFFFF)).astype(np.int64).reshape(-1, 2)


def _merge_edges(edges: np.ndarray, interest: np.ndarray, new: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stored edges plus the new ones (two distinct points, not stored yet); new ones start WATCH_LATER
    (the caller re-evaluates them at once)."""
    new = np.sort(new.reshape(-1, 2), axis=1)
    keys = np.unique(_pack(new[new[:, 0] != new[:, 1]]))
    fresh = _unpack(keys[~np.isin(keys, _pack(edges))])
    states = np.full(len(fresh), Interest.WATCH_LATER, dtype=np.uint8)
    return np.concatenate([edges, fresh]).astype(np.int64), np.concatenate([interest, states])


# --------------------------------------------------------------------------------------------
# Borders and travel cost


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


@dataclass(frozen=True, slots=True)
class TravelCost:
    """Shortest travel through known free space from one start (``G(v_S, .)`` of eq. 1).

    ``cost``: metres to every cell of the map's grid (inf: unreachable); ``previous``: the flat
    index of the previous cell on the shortest path (-1 at the start and where unreachable).
    """

    frame: GridFrame
    cost: np.ndarray
    previous: np.ndarray

    def at(self, xy: np.ndarray) -> np.ndarray:
        """G to each (x, y) (inf outside the grid)."""
        rows, cols = self.frame.cell_of(xy)
        inside = self.frame.inside(rows, cols)
        out = np.full(len(rows), np.inf)
        out[inside] = self.cost[rows[inside], cols[inside]]
        return out

    def path_to(self, xy: tuple[float, float]) -> np.ndarray:
        """Cell centres (K x 2) from the start to the cell of ``xy``; empty when unreachable."""
        rows, cols = self.frame.cell_of(np.array([xy]))
        if not self.frame.inside(rows, cols)[0] or not np.isfinite(self.cost[rows[0], cols[0]]):
            return np.zeros((0, 2))
        flat = int(rows[0] * self.frame.cols + cols[0])
        previous = self.previous.ravel()
        chain = [flat]
        while previous[chain[-1]] >= 0:
            chain.append(int(previous[chain[-1]]))
        chain.reverse()
        r, c = np.divmod(np.asarray(chain), self.frame.cols)
        return self.frame.centre_of(r, c)


def clearance(m: ExplorationMap) -> np.ndarray:
    """Distance (m) from every cell to the nearest obstacle cell (inf without obstacles)."""
    obstacle = m.cells == Cell.OBSTACLE
    if not obstacle.any():
        return np.full(m.frame.shape, np.inf)
    return ndimage.distance_transform_edt(~obstacle, sampling=m.frame.resolution)


def traversable(m: ExplorationMap, robot_radius: float) -> np.ndarray:
    """Known free cells whose clearance to the nearest obstacle cell exceeds ``robot_radius``, and
    the robot's trail (``visited``: it fitted there)."""
    return ((m.cells == Cell.FREE) & (clearance(m) > robot_radius)) | m.visited


def travel_cost(
    m: ExplorationMap, start: tuple[float, float], robot_radius: float, *, margin: float = 0.0, penalty: float = 0.0
) -> TravelCost:
    """G from ``start`` to every cell: 8-connected Dijkstra over :func:`traversable` cells.

    Steps cost their length; with ``margin`` > 0, a step between cells with less clearance than
    ``robot_radius + margin`` costs up to ``1 + penalty`` times its length (a linear ramp, like a
    costmap's inflation), so that paths keep off obstacles where there is room and G counts the
    care a squeeze takes. Without (the default), G is the path length in metres.
    """
    frame = m.frame
    cost = np.full(frame.shape, np.inf)
    previous = np.full(frame.shape, -1, dtype=np.int64)
    room = clearance(m)
    ok = ((m.cells == Cell.FREE) & (room > robot_radius)) | m.visited
    source = _snap(ok, frame, start, robot_radius)
    if source is None:
        return TravelCost(frame, _readonly(cost), _readonly(previous))
    (sr, sc), snap = source
    rows, cols = np.nonzero(ok)
    box = (slice(rows.min(), rows.max() + 1), slice(cols.min(), cols.max() + 1))  # Dijkstra on the bounding box
    r0, c0 = box[0].start, box[1].start
    sub = ok[box]
    weight = np.ones(sub.shape)
    if margin > 0.0:
        weight += penalty * np.clip((robot_radius + margin - room[box]) / margin, 0.0, 1.0)
    node = np.full(sub.shape, -1, dtype=np.int64)
    node[sub] = np.arange(np.count_nonzero(sub))
    graph = _grid_graph(sub, node, weight, frame.resolution)
    dist, pred = dijkstra(graph, directed=False, indices=int(node[sr - r0, sc - c0]), return_predecessors=True)
    sub_rows, sub_cols = np.nonzero(sub)
    cost[sub_rows + r0, sub_cols + c0] = dist + snap
    has_pred = pred >= 0
    pred_rows, pred_cols = sub_rows[np.maximum(pred, 0)] + r0, sub_cols[np.maximum(pred, 0)] + c0
    previous[sub_rows + r0, sub_cols + c0] = np.where(has_pred, pred_rows * frame.cols + pred_cols, -1)
    return TravelCost(frame, _readonly(cost), _readonly(previous))


def _snap(
    ok: np.ndarray, frame: GridFrame, start: tuple[float, float], radius: float
) -> tuple[tuple[int, int], float] | None:
    """The start cell if traversable, else the nearest traversable cell within ``radius`` (and how far)."""
    rows, cols = frame.cell_of(np.array([start]))
    r, c = int(rows[0]), int(cols[0])
    if frame.inside(rows, cols)[0] and ok[r, c]:
        return (r, c), 0.0
    k = int(math.ceil(radius / frame.resolution)) + 1
    r0, c0 = max(r - k, 0), max(c - k, 0)
    window = ok[r0 : max(r + k + 1, 0), c0 : max(c + k + 1, 0)]
    wr, wc = np.nonzero(window)
    if len(wr) == 0:
        return None
    d = np.hypot(*(frame.centre_of(wr + r0, wc + c0) - np.asarray(start)).T)
    best = int(np.argmin(d))
    if d[best] > radius + frame.resolution:
        return None
    return (int(wr[best] + r0), int(wc[best] + c0)), float(d[best])


def _grid_graph(ok: np.ndarray, node: np.ndarray, weight: np.ndarray, res: float) -> coo_matrix:
    """The 8-connected graph of the ``ok`` cells (undirected: each pair once): step length times the
    mean ``weight`` of its two cells."""
    heads, tails, weights = [], [], []
    rows, cols = ok.shape
    for dr, dc, length in ((0, 1, res), (1, 0, res), (1, 1, res * math.sqrt(2.0)), (1, -1, res * math.sqrt(2.0))):
        a = (slice(0, rows - dr), slice(max(0, -dc), cols - max(0, dc)))
        b = (slice(dr, rows), slice(max(0, dc), cols - max(0, -dc)))
        both = ok[a] & ok[b]
        heads.append(node[a][both])
        tails.append(node[b][both])
        weights.append(length * (weight[a][both] + weight[b][both]) / 2.0)
    n = int(ok.sum())
    return coo_matrix((np.concatenate(weights), (np.concatenate(heads), np.concatenate(tails))), shape=(n, n)).tocsr()
