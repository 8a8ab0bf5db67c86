"""The roadmap missions in the simulator: target images from named poses, worlds with another start,
random start poses, and the ground-truth comparison (evaluation only: behaviours never see any of it).

Used by ``bearings eval roadmap`` (:mod:`experiments.eval.roadmap`) and the mission tests.

Target images are made with ``bearings sim snapshot`` itself (the command a user runs), one PNG
per named pose of the world, named after the pose::

    write_target_images("lab", ["door", "window"], tmp_path / "targets")

``world_with(world, out, start=..., poses=...)`` writes a copy of a world file with another start
pose and extra named poses (targets anywhere). :func:`place_targets` places targets in a world's
free space (for a world without enough named poses): free as :func:`random_starts` (both draw
through :class:`FreeFloor`), apart, and facing surfaces in range (:func:`best_heading`, with the
simulator's own ray casting).

Placed targets must be ones ``learn_targets``' search can find. A target image is matched from
a scan taken near its heading (the 30-degree sector of ``maps/coverage.py``) and somewhere on its
line of sight: nearer or farther, the same scene at another scale. A target in a nook looking
into a corner is seen from a few cells of floor, and the search (which covers the floor evenly,
not nooks first) may give up before it stands there: a measured lab run never matched such a
target. So, without knowing the world:

- **room around a target**: ``TARGET_CLEARANCE`` (0.7 m) from every wall, box and pillar rather
  than the starts' 0.45 m; a target falls back to ``START_CLEARANCE`` when ``TARGET_DRAWS``
  draws find no such place (the world has none, :func:`has_room`, or the targets before it
  took it);
- **a view seen from much floor**: of the qualifying headings (every ray 1-5 m, at least two
  surfaces, as before), those whose optical axis meets its surface 2-4 m away
  (``PREFERRED_CENTRE``: far enough for a long line of sight, near enough for detail) when any
  does, then the one with the most reachable floor inside the camera's field of view between the
  camera and the surfaces it sees (:func:`floor_in_view`, on the reachable floor grid: where the
  robot can stand to see that view), then the most surfaces, then the axis nearest 3 m;
- **an open position**: of ``TARGET_CANDIDATES`` (3) positions drawn one after the other, the
  one whose chosen heading ranks first (so still anywhere in the room, but rarely in a nook).
  Open places taken first pack worse: a world too crowded for N targets so (12 in the lab) is
  placed again first come, first served.

Everything is drawn from the seed alone.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import yaml
from scipy import ndimage

from behaviours.roadmap.room import RoomEstimationDodecagon
from drivers.sim.cameras import camera_pose
from drivers.sim.floor import FloorGrid, rasterise, reachable_floor
from drivers.sim.scene import Scene
from drivers.sim.world import World, load_world, shipped_worlds
from maps.room import corner_circle, dodecagon_centre
from missions.cli import main
from perception.geometry import Pose2D, wrap_angle, wrap_angles

START_CLEARANCE = 0.45  # m: a random start is at least this far from any wall, box or pillar
TARGET_CLEARANCE = 0.7  # m: a placed target too, when the world has room (else START_CLEARANCE): open floor around it
MAX_DRAWS = 100_000  # random positions tried per start (per placed target) before giving up (a world with no room)
TARGET_SPACING = 1.5  # m: placed targets at least this far apart (distinct places, not one view twice)
VIEW_RANGE = (1.0, 5.0)  # m: a placed target's camera sees surfaces this far away on every ray
VIEW_RAYS = 7  # rays across the camera's centre row that must all see a surface in range
HEADINGS = 24  # candidate headings of a placed target (every 15 deg)
MIN_SURFACES = 2  # distinct surfaces a placed target's view must meet (one flat wall: the planar ambiguity)
TARGET_DRAWS = 10_000  # draws for a placed target at TARGET_CLEARANCE before START_CLEARANCE is tried
TARGET_CANDIDATES = 3  # positions drawn per placed target; the one with the best view is kept
PREFERRED_CENTRE = (2.0, 4.0)  # m: a placed target's optical axis preferably meets its surface this far away
DODECAGON_MARGIN = 0.35  # m spare round the dodecagon at a moved start: the monitor's slow-down margin
SIGHT_HEIGHT = 2.0  # m: a line of sight this high passes over desks, cabinets and people; walls and pillars stop it
SIGHT_SPREAD = 0.3  # m: ... drawn to the target and this far to each side of it: a pillar does not hide all three
LEARN_HEADINGS = 12  # headings tried at each place for a learning start (every 30 deg)
EXIT_MARGIN = 0.45  # m: a placed target is farther than this from floor outside its room (the far side of a wall: 0.52)
ROOM_NECK = 0.4  # m: floor in sight narrower than twice this (a door up to 1.3 m for the Pioneer) parts two rooms

T = TypeVar("T")


def world_path(world: str | Path) -> Path:
    """The file of a shipped world (by name) or a world file."""
    shipped = shipped_worlds()
    return Path(shipped[str(world)]) if str(world) in shipped else Path(world)


def world_with(world: str | Path, out: Path, *, start: Pose2D | None = None,
               poses: Mapping[str, Pose2D] | None = None) -> Path:
    """A copy of ``world`` at ``out`` with another start pose and/or more named poses."""
    data = yaml.safe_load(world_path(world).read_text())
    if start is not None:
        data["start"] = {"x": start.x, "y": start.y, "theta_deg": math.degrees(start.theta)}
    for name, pose in (poses or {}).items():
        data.setdefault("poses", {})[name] = {"x": pose.x, "y": pose.y, "theta_deg": math.degrees(pose.theta)}
    out.write_text(yaml.safe_dump(data, sort_keys=False))
    return out


def named_poses(world: str | Path | World) -> dict[str, Pose2D]:
    """The named poses of a world (world frame)."""
    loaded = world if isinstance(world, World) else load_world(str(world))
    return dict(loaded.poses)


def write_target_images(world: str | Path, names: Iterable[str], folder: Path, *, camera: str = "front",
                        seed: int = 0) -> Path:
    """One target image per named pose, rendered by ``bearings sim snapshot`` (lighting of ``seed``)
    into ``folder/NAME.png``; ``RuntimeError`` naming the pose when the command fails."""
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()) as err:
            code = main(["sim", "snapshot", "--world", str(world), "--pose", name, "--camera", camera,
                         "--seed", str(seed), "-o", str(folder / f"{name}.png")])
        if code != 0:
            said = err.getvalue().strip().splitlines()
            raise RuntimeError(f"bearings sim snapshot failed for pose {name!r} of {world}"
                               + (f": {said[-1]}" if said else ""))
    return folder


def pose_error(estimate: Pose2D, truth: Pose2D) -> tuple[float, float]:
    """(position error m, heading error deg) of an estimate."""
    return estimate.distance_to(truth), abs(math.degrees(wrap_angle(estimate.theta - truth.theta)))


def target_errors(report: Mapping[str, Any], truth: Mapping[str, Pose2D], reference_truth: Pose2D
                  ) -> dict[str, tuple[float, float]]:
    """Errors of the targets of a learn_targets report: their estimated poses (reference frame)
    against the true poses expressed in the true reference frame. Targets without a true pose in
    ``truth`` are left out."""
    targets = report.get("roadmap", {}).get("targets", {})
    errors = {}
    for name, t in targets.items():
        if name in truth:
            estimate = Pose2D(t["x"], t["y"], math.radians(t["theta_deg"]))
            errors[name] = pose_error(estimate, truth[name].relative_to(reference_truth))
    return errors


def reachable_grid(world: World) -> FloorGrid:
    """Where the robot's centre can go from the world's start (``ValueError`` if the start is not free)."""
    return reachable_floor(world, resolution=0.05)


def usable_poses(world: World, grid: FloorGrid | None = None) -> dict[str, Pose2D]:
    """The named poses where the robot can stand and that it can reach from the start."""
    grid = grid or reachable_grid(world)
    names = sorted(world.poses)
    if not names:
        return {}
    on_floor = grid.reachable_at(np.array([[world.poses[n].x, world.poses[n].y] for n in names]))
    return {n: world.poses[n] for n, ok in zip(names, on_floor, strict=True) if ok}


@dataclass(frozen=True)
class FreeFloor:
    """Where the robot can be put down: reachable from the world's start (the floor grid) and at
    least ``clearance`` from any wall, box or pillar (the scene's exact distance). Shared by the
    random starts and the placed targets, so both mean the same thing by "free"."""

    world: World
    grid: FloorGrid
    scene: Scene
    clearance: float

    @classmethod
    def of(cls, world: World, clearance: float, grid: FloorGrid | None = None) -> FreeFloor:
        return cls(world, grid or reachable_grid(world), Scene(world), clearance)

    @cached_property
    def cells(self) -> np.ndarray:
        """Centres of the reachable cells (:func:`floor_cells`), for the placed targets' floor in view."""
        return floor_cells(self.grid)

    def is_free(self, x: float, y: float) -> bool:
        """Whether (x, y) is reachable and clear enough."""
        return bool(self.grid.reachable_at(np.array([x, y]))[0]) and self.scene.clearance(x, y) >= self.clearance

    def draw(self, rng: np.random.Generator, judge: Callable[[float, float], T | None],
             draws: int = MAX_DRAWS) -> T | None:
        """The first of up to ``draws`` positions uniform in the world's bounds that is free and
        that ``judge`` accepts (its answer); None when none is."""
        xmin, ymin, xmax, ymax = self.world.bounds()
        for _ in range(draws):
            x, y = float(rng.uniform(xmin, xmax)), float(rng.uniform(ymin, ymax))
            if self.is_free(x, y):
                judged = judge(x, y)
                if judged is not None:
                    return judged
        return None


def random_starts(world: World, count: int, seed: int, *, clearance: float = START_CLEARANCE,
                  grid: FloorGrid | None = None) -> list[Pose2D]:
    """``count`` start poses drawn from ``seed`` alone: positions uniform in the world's bounds, at
    least ``clearance`` from any wall, box or pillar (the scene's exact distance) and reachable from
    the world's start (the floor grid), any heading. ``ValueError`` when no such place turns up."""
    free = FreeFloor.of(world, clearance, grid)
    rng = np.random.default_rng([seed, 0x60A1])
    starts: list[Pose2D] = []
    for _ in range(count):
        place = free.draw(rng, lambda x, y: (x, y))
        if place is None:
            raise ValueError(f"world {world.name!r} has no reachable place {clearance:g} m clear of every surface "
                             "to start from")
        starts.append(Pose2D(*place, float(rng.uniform(-math.pi, math.pi))))
    return starts


# ------------------------------------------------------------------------------------------------
# Targets placed in the free space (a world without enough named poses)


@dataclass(frozen=True)
class View:
    """What a camera's centre row looks at from one pose: along each of its rays (left to right),
    the horizontal distance to the nearest wall, box or pillar that stands above the camera (inf:
    none; a lower box is looked over), and which surfaces those are (indices of the scene's)."""

    distances: tuple[float, ...]
    surfaces: tuple[int, ...]

    @property
    def centre(self) -> float:
        """Distance along the optical axis (the middle ray)."""
        return self.distances[len(self.distances) // 2]

    def within(self, near: float, far: float) -> bool:
        """Whether every ray meets a surface between ``near`` and ``far`` m: the image is filled with
        texture close enough for the stereo camera and far enough to be seen whole."""
        return all(near <= d <= far for d in self.distances)


def camera_rays(world: World, camera: str = "front", rays: int = VIEW_RAYS) -> np.ndarray:
    """Azimuths (rad, relative to the robot's heading, pan and tilt 0) of ``rays`` pixels spread
    evenly across the centre row of ``camera``'s image, from its own model and mount."""
    spec = world.camera(camera)
    model = spec.model
    u = np.linspace(0.0, model.width - 1.0, rays)
    body = model.pixel_to_bearing(np.column_stack([u, np.full(rays, (model.height - 1) / 2.0)]))
    level = body @ camera_pose(spec, world.ptu, Pose2D()).rest.T
    return np.arctan2(level[:, 1], level[:, 0])


def camera_view(scene: Scene, world: World, pose: Pose2D, azimuths: np.ndarray, camera: str = "front") -> View:
    """What ``camera`` sees along ``azimuths`` (:func:`camera_rays`) with the robot at ``pose``,
    cast with the simulator's own scene geometry (``Scene.cast_columns``) from the camera's eye."""
    where = camera_pose(world.camera(camera), world.ptu, pose)
    distance, index = scene.cast_columns(where.eye, where.psi + azimuths)
    tall = scene.heights[index] > where.eye[2]
    distance = np.where(tall[None, :], distance, np.inf)
    nearest = np.argmin(distance, axis=1) if distance.shape[1] else np.zeros(len(azimuths), dtype=int)
    rows = np.arange(len(azimuths))
    hit = distance[rows, nearest] if distance.shape[1] else np.full(len(azimuths), np.inf)
    return View(tuple(float(d) for d in hit),
                tuple(int(index[k]) if math.isfinite(d) else -1 for k, d in zip(nearest, hit, strict=True)))


def floor_cells(grid: FloorGrid) -> np.ndarray:
    """World (x, y) of the centres of the grid's reachable cells (N x 2): where the robot can stand."""
    return cell_centres(grid, grid.reachable)


def cell_centres(grid: FloorGrid, mask: np.ndarray) -> np.ndarray:
    """World (x, y) of the centres of the cells of ``mask`` (the grid's shape), N x 2, row by row."""
    rows, cols = np.nonzero(mask)
    return np.column_stack([grid.x0 + (cols + 0.5) * grid.resolution, grid.y0 + (rows + 0.5) * grid.resolution])


def floor_in_view(cells: np.ndarray, cell_area: float, eye: np.ndarray, psi: float, azimuths: np.ndarray,
                  view: View) -> float:
    """m^2 of reachable floor (``cells``, :func:`floor_cells`) inside the camera's field of view
    between its eye (x, y) and the surfaces ``view`` meets: between the outermost rays, no farther
    than the distance to the surface at that bearing (interpolated between the rays). A robot
    standing there on the line of sight, facing the same way, sees the same scene nearer or
    farther: the larger this floor, the more places a scan can match the target image from."""
    order = np.argsort(azimuths)
    rays, reach = azimuths[order], np.asarray(view.distances)[order]
    rel = cells - np.asarray(eye[:2])[None, :]
    bearing = wrap_angles(np.arctan2(rel[:, 1], rel[:, 0]) - psi)
    ahead = (bearing >= rays[0]) & (bearing <= rays[-1])
    seen = ahead & (np.hypot(rel[:, 0], rel[:, 1]) <= np.interp(bearing, rays, reach))
    return float(np.count_nonzero(seen)) * cell_area


@dataclass(frozen=True)
class HeadingChoice:
    """A qualifying heading of a placed target (:func:`heading_choices`): what its camera sees and
    how much floor the robot can stand on inside that view (:func:`floor_in_view`)."""

    theta: float
    view: View
    floor: float  # m^2

    @property
    def surfaces(self) -> int:
        """Distinct surfaces the view meets."""
        return len(set(self.view.surfaces))

    def preferred(self, band: tuple[float, float] = PREFERRED_CENTRE) -> bool:
        """Whether the optical axis meets its surface within ``band`` (m)."""
        return band[0] <= self.view.centre <= band[1]

    def key(self, band: tuple[float, float] = PREFERRED_CENTRE) -> tuple[bool, float, int, float]:
        """The order of preference (largest best): centre distance in the band, then floor in view,
        then surfaces met, then the optical axis nearest the band's middle."""
        return (self.preferred(band), self.floor, self.surfaces, -abs(self.view.centre - sum(band) / 2.0))


def heading_choices(free: FreeFloor, x: float, y: float, azimuths: np.ndarray, *,
                    view_range: tuple[float, float] = VIEW_RANGE, camera: str = "front") -> list[HeadingChoice]:
    """Of ``HEADINGS`` headings evenly round from (x, y), those whose view is within ``view_range`` on
    every ray and meets at least ``MIN_SURFACES`` distinct surfaces (a single flat wall is the planar
    essential matrix's ambiguous case: homing to it may fail), each with its floor in view."""
    near, far = view_range
    spec, cells, area = free.world.camera(camera), free.cells, free.grid.resolution**2
    choices = []
    for k in range(HEADINGS):
        pose = Pose2D(x, y, wrap_angle(2.0 * math.pi * k / HEADINGS))
        view = camera_view(free.scene, free.world, pose, azimuths, camera)
        if not view.within(near, far) or len(set(view.surfaces)) < MIN_SURFACES:
            continue
        where = camera_pose(spec, free.world.ptu, pose)
        choices.append(HeadingChoice(pose.theta, view, floor_in_view(cells, area, where.eye, where.psi, azimuths,
                                                                     view)))
    return choices


def best_heading(free: FreeFloor, x: float, y: float, azimuths: np.ndarray, *,
                 view_range: tuple[float, float] = VIEW_RANGE, camera: str = "front") -> HeadingChoice | None:
    """The qualifying heading (:func:`heading_choices`) the search can find most easily: optical axis
    ``PREFERRED_CENTRE`` away if any is, then the most floor in view, then the most surfaces, then the
    axis nearest the band's middle (:meth:`HeadingChoice.key`); None if none qualifies."""
    choices = heading_choices(free, x, y, azimuths, view_range=view_range, camera=camera)
    return max(choices, key=HeadingChoice.key) if choices else None


def learn_start(world: World, grid: FloorGrid, side: float = RoomEstimationDodecagon.SIDE.default) -> Pose2D:
    """Where ``learn_targets`` starts: the world's start when the room estimation's dodecagon fits
    there (the robot's disc clears every surface all round the corners' circle, whose centre lies
    side / (2 sin 15 deg) away, 105 deg round from the start's heading: ``maps.room.dodecagon_centre``),
    else the reachable pose nearest to it where it does with :data:`DODECAGON_MARGIN` to spare (the lab's
    start has 0.02 m and is kept; a start moved is moved to where the collision monitor neither stops
    nor slows the drives: with 0.10 m, its
    stop margin, `flat`'s learning was stopped at the tenth corner). The method expects the
    robot in a room (the paper's); a world may start it in a hallway (``flat``: 1.4 m wide, where
    the learning was stopped at its fourth corner), and a user would carry it into a room. ValueError
    when no reachable place has the room."""
    circle = corner_circle(side)
    scene = Scene(world)
    start = world.start
    if scene.clearance(*dodecagon_centre(start, side)) >= circle + world.robot_radius:
        return Pose2D(start.x, start.y, start.theta)
    need = circle + world.robot_radius + DODECAGON_MARGIN
    room = ndimage.distance_transform_edt(grid.free) * grid.resolution  # generous by a cell: exact check below
    cells = floor_cells(grid)
    for i in np.argsort(np.hypot(cells[:, 0] - start.x, cells[:, 1] - start.y)):
        x, y = (float(c) for c in cells[i])
        for k in range(LEARN_HEADINGS):
            theta = wrap_angle(start.theta + 2.0 * math.pi * k / LEARN_HEADINGS)
            cx, cy = dodecagon_centre(Pose2D(x, y, theta), side)
            col, row = int((cx - grid.x0) / grid.resolution), int((cy - grid.y0) / grid.resolution)
            inside = 0 <= row < room.shape[0] and 0 <= col < room.shape[1]
            if inside and room[row, col] + grid.resolution >= need and scene.clearance(cx, cy) >= need:
                return Pose2D(x, y, theta)
    raise ValueError(f"world {world.name!r} has no reachable place where the room estimation's dodecagon (side "
                     f"{side:g} m) fits: a free disc {2.0 * need:.2f} m across")


def out_of_sight(world: World, start: Pose2D, targets: Mapping[str, Pose2D]) -> tuple[str, ...]:
    """The targets a wall hides from where the learning starts: the lines of sight at
    :data:`SIGHT_HEIGHT` to the target and :data:`SIGHT_SPREAD` to each side of it all meet a wall or
    a pillar (the scene's own occlusion test). The roadmap learns the targets of the room it starts
    in (the paper's method); one in another room is not found, and the evaluation says so."""
    names = sorted(targets)
    if not names:
        return ()
    seen = in_sight(Scene(world), start, np.array([[targets[n].x, targets[n].y] for n in names]))
    return tuple(n for n, ok in zip(names, seen, strict=True) if not ok)


def in_sight(scene: Scene, eye: Pose2D, xy: np.ndarray, chunk: int = 4096) -> np.ndarray:
    """Whether each floor point (N x 2) is in sight from ``eye``: of the lines of sight at
    :data:`SIGHT_HEIGHT` to it and :data:`SIGHT_SPREAD` to each side of it, one meets no wall or
    pillar (:func:`out_of_sight`'s test; ``chunk`` points at a time bound the memory)."""
    points = np.asarray(xy, dtype=float).reshape(-1, 2)
    origin = np.array([eye.x, eye.y, SIGHT_HEIGHT])
    away = points - origin[:2]
    across = np.column_stack([-away[:, 1], away[:, 0]]) / np.maximum(np.hypot(away[:, 0], away[:, 1]), 1e-9)[:, None]
    seen = np.zeros(len(points), dtype=bool)
    for k in (0.0, -1.0, 1.0):
        ends = np.column_stack([points + k * SIGHT_SPREAD * across, np.full(len(points), SIGHT_HEIGHT)])
        for i in range(0, len(points), chunk):
            seen[i:i + chunk] |= ~scene.occluded(origin, ends[i:i + chunk])
    return seen


def learning_room(world: World, grid: FloorGrid, start: Pose2D,
                  side: float = RoomEstimationDodecagon.SIDE.default) -> FloorGrid:
    """The reachable floor of the room the learning starts in: ``grid`` with :attr:`~FloorGrid.reachable`
    kept where it is :func:`in_sight` from ``start`` and joined to the dodecagon's centre by floor in
    sight at least ``2 * ROOM_NECK`` wide between the surfaces that stop a line of sight (a
    morphological opening: a door parts two rooms, a desk does not). The paper's method learns the
    targets of that room and navigates in it (its room estimate is the floor the dodecagon's
    stereo pairs see), so the evaluation draws its default targets and its navigations' starts
    there; a world of one room keeps its floor (the lab: 99.6 %)."""
    tall = dataclasses.replace(world, walls=tuple(w for w in world.walls if w.height >= SIGHT_HEIGHT),
                               pillars=tuple(p for p in world.pillars if p.height >= SIGHT_HEIGHT))
    occupied = rasterise(tall, grid.x0, grid.y0, grid.resolution, grid.free.shape)
    standable = ndimage.distance_transform_edt(~occupied) * grid.resolution > world.robot_radius
    seen = np.zeros(grid.reachable.shape, dtype=bool)
    seen[standable] = in_sight(Scene(world), start, cell_centres(grid, standable))
    wide = ndimage.distance_transform_edt(seen) * grid.resolution >= ROOM_NECK
    (row,), (col,), (inside,) = grid.cells_of(np.array([dodecagon_centre(start, side)]))
    parts, _ = ndimage.label(wide)
    if inside and parts[row, col]:
        room = (ndimage.distance_transform_edt(parts != parts[row, col]) * grid.resolution <= ROOM_NECK) & seen
    else:  # no room for the dodecagon's circle there: the floor in sight joined to the start, not opened
        parts, _ = ndimage.label(seen)
        (row,), (col,), (inside,) = grid.cells_of(np.array([[start.x, start.y]]))
        if not inside or not parts[row, col]:
            raise ValueError(f"the learning start ({start.x:g}, {start.y:g}) is not on the reachable floor of "
                             f"world {world.name!r}")
        room = parts == parts[row, col]
    return dataclasses.replace(grid, reachable=room & grid.reachable)


def away_from_exits(room: FloorGrid, grid: FloorGrid) -> FloorGrid:
    """``room`` (:func:`learning_room` of ``grid``) without its floor within :data:`EXIT_MARGIN` of
    reachable floor outside it: never in a doorway. Where the placed targets go: a target homed to
    in a doorway left the robot wedged against its jamb, the corridor's walker behind it, in
    `office`."""
    exits = grid.reachable & ~room.reachable
    if not exits.any():
        return room
    return dataclasses.replace(room, reachable=room.reachable
                               & (ndimage.distance_transform_edt(~exits) * grid.resolution > EXIT_MARGIN))


def has_room(grid: FloorGrid, clearance: float) -> bool:
    """Whether some reachable cell may be ``clearance`` from every wall, box and pillar (the grid's
    distance transform, generous by a cell: a quick test before drawing positions for it)."""
    distance = ndimage.distance_transform_edt(grid.free) * grid.resolution
    return bool(np.any(grid.reachable) and distance[grid.reachable].max() + grid.resolution >= clearance)


def place_targets(world: World, count: int, seed: int, *, clearance: float = TARGET_CLEARANCE,
                  fallback: float = START_CLEARANCE, spacing: float = TARGET_SPACING,
                  view_range: tuple[float, float] = VIEW_RANGE, camera: str = "front",
                  grid: FloorGrid | None = None) -> dict[str, Pose2D]:
    """``count`` target poses ``t1``..``tN`` drawn from ``seed`` alone: free positions (reachable,
    ``clearance`` from every surface: room around a target; ``fallback``, the random starts'
    clearance, for a target when ``TARGET_DRAWS`` draws find no such place or the world has none),
    at least ``spacing`` apart, each with the heading :func:`best_heading` chooses (a position where
    none qualifies is drawn again); of ``TARGET_CANDIDATES`` such positions, the one whose heading
    ranks first. The first ones do not depend on ``count``. A world too crowded for that (open
    places taken first pack worse) is placed again with one position per target, first come
    first served. ``ValueError`` when the world has no room for them all."""
    grid = grid or reachable_grid(world)
    try:
        return _place(world, count, seed, TARGET_CANDIDATES, clearance=clearance, fallback=fallback,
                      spacing=spacing, view_range=view_range, camera=camera, grid=grid)
    except ValueError:
        if TARGET_CANDIDATES == 1:
            raise
    return _place(world, count, seed, 1, clearance=clearance, fallback=fallback, spacing=spacing,
                  view_range=view_range, camera=camera, grid=grid)


def _place(world: World, count: int, seed: int, candidates: int, *, clearance: float, fallback: float,
           spacing: float, view_range: tuple[float, float], camera: str, grid: FloorGrid) -> dict[str, Pose2D]:
    """:func:`place_targets` keeping the best of ``candidates`` positions per target."""
    levels = [clearance, fallback] if fallback < clearance else [clearance]
    if len(levels) > 1 and not has_room(grid, clearance):
        levels = levels[1:]
    floors = [FreeFloor.of(world, c, grid) for c in levels]
    azimuths = camera_rays(world, camera)
    rng = np.random.default_rng([seed, 0x60A3])
    placed: dict[str, Pose2D] = {}

    def judge(x: float, y: float) -> tuple[Pose2D, HeadingChoice] | None:
        if any(math.hypot(x - p.x, y - p.y) < spacing for p in placed.values()):
            return None
        best = best_heading(floors[0], x, y, azimuths, view_range=view_range, camera=camera)
        return None if best is None else (Pose2D(x, y, best.theta), best)

    for k in range(1, count + 1):
        chosen = _best_of(floors, rng, judge, candidates)
        if chosen is None:
            raise ValueError(f"world {world.name!r} has room for {len(placed)} target(s), not {count}: reachable, "
                             f"{levels[-1]:g} m clear, {spacing:g} m apart, the {camera} camera facing surfaces "
                             f"{view_range[0]:g}-{view_range[1]:g} m away")
        placed[f"t{k}"] = chosen
    return placed


def _best_of(floors: list[FreeFloor], rng: np.random.Generator,
             judge: Callable[[float, float], tuple[Pose2D, HeadingChoice] | None], tries: int) -> Pose2D | None:
    """Of up to ``tries`` positions drawn one after the other, the pose whose heading ranks first
    (:meth:`HeadingChoice.key`; the earlier one on a tie). Positions are drawn from the strictest of
    ``floors`` first (``TARGET_DRAWS`` draws), the next one when that finds none (the last one:
    ``MAX_DRAWS``); once a position is found, a failed draw ends the search. None: no position."""
    drawn: list[tuple[Pose2D, HeadingChoice]] = []
    level = 0
    while len(drawn) < tries and level < len(floors):
        found = floors[level].draw(rng, judge, TARGET_DRAWS if level < len(floors) - 1 else MAX_DRAWS)
        if found is not None:
            drawn.append(found)
        elif drawn:
            break
        else:
            level += 1
    return max(drawn, key=lambda d: d[1].key())[0] if drawn else None
