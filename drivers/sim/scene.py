"""The world as flat arrays for fast geometry: ray casting, occlusion, collision, texture layout.

Walls and box faces become line segments, pillars and people circles; each surface knows where its
texture sits in the atlas. Everything here is vectorised over rays and surfaces with numpy, so one
panorama's 720 column rays against a few dozen surfaces cost a handful of array operations.

A box pushed against a wall has a face in the wall's plane; seen from the wall's other side the two
lie at the same distance and the nearest of them changed from column to column with the rounding,
striping the wall with the box (found in a world written for a test). The box is always on the
far side (its face towards the viewer is in the wall), so a column takes the wall when a box face
is within :data:`FLUSH` of it.

People are the scene's only moving surfaces: circles after the pillars whose centres the
simulation moves each step (:meth:`Scene.move_people`), so every camera, the bearings sensor's
occlusion and the sonar see them where they are now. :meth:`Scene.clearance` (collisions, free
space) holds the fixed surfaces only; the simulation adds the people itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drivers.sim.people import position_at
from drivers.sim.textures import AtlasBuilder, Region, make_sky, make_texture
from drivers.sim.world_values import Person, Pillar, TextureSpec, World
from perception.geometry import Pose2D

EPS = 1e-9
FLUSH = 1e-4  # m: a box face this near a wall along a column ray counts as behind it (module docstring)
SKY_PX_PER_RAD = 60.0  # texels per radian of the sky / far-ground bands
SKY_TOP = math.radians(90.0)


@dataclass(frozen=True, slots=True)
class ColumnHits:
    """The nearest surface (or one layer of surfaces) hit by each column ray.

    ``distance`` is horizontal (inf: no hit); ``surface`` indexes the scene's surfaces (-1: none);
    ``u`` is the atlas column of the hit; per surface the scene knows height and texture rows.
    """

    distance: np.ndarray
    surface: np.ndarray
    u: np.ndarray


class Scene:
    """Segments, circles, landmarks and the texture atlas of one :class:`~drivers.sim.world_values.World`."""

    def __init__(self, world: World) -> None:
        self.world = world
        a, b, two_sided, offsets, heights, ppm = [], [], [], [], [], []
        for wall in world.walls:
            pts = np.asarray(wall.points, dtype=float)
            lengths = np.linalg.norm(np.diff(pts, axis=0), axis=1)
            a.append(pts[:-1])
            b.append(pts[1:])
            offsets.append(np.concatenate([[0.0], np.cumsum(lengths)[:-1]]))
            n = len(lengths)
            two_sided += [wall.two_sided] * n
            heights += [wall.height] * n
            ppm += [wall.texture.pixels_per_m] * n
        n_segments = len(heights)
        rounds: list[Pillar | Person] = [*world.pillars, *world.people]  # the vertical cylinders
        for round_surface in rounds:
            heights.append(round_surface.height)
            ppm.append(round_surface.texture.pixels_per_m)
        # surfaces: every wall/box segment, then every pillar, then every person
        self.n_surfaces = len(heights)
        self.n_segments = n_segments
        self.heights = np.asarray(heights, dtype=float)
        self.ppm = np.asarray(ppm, dtype=float)
        self.seg_a = np.concatenate(a) if a else np.zeros((0, 2))
        self.seg_b = np.concatenate(b) if b else np.zeros((0, 2))
        self.seg_two_sided = np.asarray(two_sided, dtype=bool)
        self.seg_height = self.heights[:n_segments]
        self._seg_offset = np.concatenate(offsets) if offsets else np.zeros(0)
        self._seg_e = self.seg_b - self.seg_a
        self.seg_len = np.hypot(self._seg_e[:, 0], self._seg_e[:, 1])
        self.n_pillars = len(world.pillars)
        centres = [*((p.x, p.y) for p in world.pillars), *(position_at(p, 0.0) for p in world.people)]
        self.circle_xy = np.asarray(centres, dtype=float).reshape(-1, 2)
        self.circle_r = np.asarray([p.radius for p in rounds], dtype=float)
        self._pillar_index = np.arange(n_segments, self.n_surfaces)
        self._box_face = np.concatenate([~self.seg_two_sided, np.zeros(self.n_surfaces - n_segments, dtype=bool)])
        ends = [p for wall in world.walls if wall.points[0] != wall.points[-1]
                for p in (wall.points[0], wall.points[-1])]
        self.wall_ends = np.asarray(ends, dtype=float).reshape(-1, 2)  # open ends of walls: door jambs, wall ends
        self.landmark_ids = np.asarray([lm.id for lm in world.landmarks], dtype=np.int64)
        self.landmark_xyz = np.asarray([(lm.x, lm.y, lm.z) for lm in world.landmarks], dtype=float).reshape(-1, 3)
        self.landmark_size = np.asarray([lm.size for lm in world.landmarks], dtype=float)
        self.landmark_cores = np.where(self.landmark_ids % 2 == 1, 235, 20)  # grey of a disc's centre
        self.atlas: np.ndarray | None = None  # built on first use by a renderer (ensure_textures)

    def ensure_textures(self) -> None:
        """Generate every texture and pack the atlas (once; bearings-only runs never need it)."""
        if self.atlas is not None:
            return
        world = self.world
        builder = AtlasBuilder()
        tex_index = []
        for wall in world.walls:
            length = float(np.sum(np.linalg.norm(np.diff(np.asarray(wall.points), axis=0), axis=1)))
            index = builder.add(_surface_texture(wall.texture, length, wall.height))
            tex_index += [index] * (len(wall.points) - 1)
        rounds: list[Pillar | Person] = [*world.pillars, *world.people]
        for round_surface in rounds:
            tex_index.append(builder.add(_surface_texture(
                round_surface.texture, 2 * math.pi * round_surface.radius, round_surface.height)))
        ground = self._add_ground(builder)
        sky_idx, sky_w, sky_h = self._add_sky(builder)
        atlas, origins = builder.build()
        self._lay_out_surfaces(origins, tex_index)
        floor_idx, ceiling_idx, floor_w, floor_h, floor_ppm = ground
        fu, fv = origins[floor_idx]
        self.floor_region = Region(fu, fv, floor_w, floor_h, floor_ppm)
        self.ceiling_region = None
        if ceiling_idx is not None:
            cu, cv = origins[ceiling_idx]
            self.ceiling_region = Region(cu, cv, floor_w, floor_h, floor_ppm)
        su, sv = origins[sky_idx]
        self.sky_region = Region(su, sv, 3 * sky_w, sky_h, SKY_PX_PER_RAD)
        self.sky_horizon_v = sv + sky_h // 2  # atlas row of elevation 0 in the sky band
        self.atlas = atlas

    def _add_ground(self, builder: AtlasBuilder) -> tuple[int, int | None, int, int, float]:
        """Floor (and ceiling) textures over the world's bounds plus the margin: (floor index, ceiling
        index or None, width, height, texels per metre)."""
        world = self.world
        floor_ppm = world.floor.pixels_per_m
        x0, y0, x1, y1 = world.bounds()
        m = world.ground_margin
        self.floor_origin = (x0 - m, y0 - m)
        floor_w = int(math.ceil((x1 - x0 + 2 * m) * floor_ppm)) + 2
        floor_h = int(math.ceil((y1 - y0 + 2 * m) * floor_ppm)) + 2
        scale = min(1.0, 8000.0 / max(floor_w, floor_h))  # keep huge grounds inside the atlas
        floor_ppm *= scale
        floor_w, floor_h = int(floor_w * scale) + 2, int(floor_h * scale) + 2
        floor_spec = TextureSpec(
            world.floor.seed, floor_ppm, world.floor.feature_size, world.floor.brightness, world.floor.contrast
        )
        floor_idx = builder.add(make_texture(floor_spec, floor_w, floor_h))
        ceiling_idx = None
        if world.ceiling is not None:
            ceil_spec = TextureSpec(world.seed * 1000 + 999, floor_ppm, 0.5, 200.0, 0.3)
            ceiling_idx = builder.add(make_texture(ceil_spec, floor_w, floor_h))
        return floor_idx, ceiling_idx, floor_w, floor_h, floor_ppm

    def _add_sky(self, builder: AtlasBuilder) -> tuple[int, int, int]:
        """The sky band (three periods side by side): (index, width of one period, height)."""
        world = self.world
        sky_w = int(math.ceil(2 * math.pi * SKY_PX_PER_RAD))
        sky_h = int(math.ceil(2 * SKY_TOP * SKY_PX_PER_RAD)) + 2
        sky = make_sky(world.seed * 1000 + 998, sky_w, sky_h, indoor=world.ceiling is not None)
        sky[sky_h // 2:] = int(world.floor.brightness)  # below the horizon: far ground, the floor's mean grey
        # three periods side by side: the renderer samples azimuths in [pi, 5 pi], no modulo
        return builder.add(np.hstack([sky, sky, sky])), sky_w, sky_h

    def _lay_out_surfaces(self, origins: list[tuple[int, int]], tex_index: list[int]) -> None:
        """Where each wall segment's and pillar's texels sit in the atlas, as per-surface tables."""
        n_segments = self.n_segments
        self.tex_u0 = np.asarray([origins[i][0] for i in tex_index], dtype=float).reshape(-1)
        # atlas row of z = 0 on each surface (texture row 0 is the top of the surface)
        self.tex_vz0 = np.asarray([origins[i][1] for i in tex_index], dtype=float).reshape(-1)
        self.tex_vz0 = self.tex_vz0 + self.heights * self.ppm
        self.seg_u0 = self.tex_u0[:n_segments] + self._seg_offset * self.ppm[:n_segments]
        # per surface: anchor (x, y), texture gradient (texels per metre along x, y), u0, is-pillar;
        # for pillars the third column holds radius * texels per metre (u grows with the arc)
        table = np.zeros((self.n_surfaces, 6))
        if n_segments:
            gain = self.ppm[:n_segments] / self.seg_len
            table[:n_segments] = np.column_stack(
                [self.seg_a, self._seg_e * gain[:, None], self.seg_u0, np.zeros(n_segments)]
            )
        if len(self.circle_r):
            table[n_segments:] = np.column_stack(
                [self.circle_xy, self.circle_r * self.ppm[n_segments:], np.zeros(len(self.circle_r)),
                 self.tex_u0[n_segments:], np.ones(len(self.circle_r))]
            )  # fmt: skip
        self._u_columns = tuple(np.ascontiguousarray(table[:, i]) for i in range(5))

    # ----------------------------------------------------------------------------------------
    # Rays

    def cast_columns(
        self, origin: np.ndarray, angles: np.ndarray, dirs: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Horizontal distances from ``origin`` along world ``angles`` to the surfaces facing it.

        Returns ``(distance, surface)``: a (W, L) array (inf where a ray misses) over the L
        surfaces that can be seen from ``origin``, and their indices into :attr:`heights`
        (segments first, then pillars). Box faces seen from behind (from inside) are culled.
        All ray/surface products come from one (W, 2) x (2, 2S + P) matrix product.
        """
        if dirs is None:
            dirs = np.column_stack([np.cos(angles), np.sin(angles)])
        ox, oy = float(origin[0]), float(origin[1])
        ex, ey = self._seg_e[:, 0], self._seg_e[:, 1]
        wx, wy = self.seg_a[:, 0] - ox, self.seg_a[:, 1] - oy
        side = ex * wy - ey * wx  # < 0: origin left of A->B (inside a counter-clockwise box)
        live = np.flatnonzero(self.seg_two_sided | (side > 0))
        ex, ey, wx, wy = ex[live], ey[live], wx[live], wy[live]
        cx, cy = self.circle_xy[:, 0] - ox, self.circle_xy[:, 1] - oy
        n = len(live)
        # columns: d x e (denominator), d x w (numerator of the segment parameter), d . c (pillars)
        products = dirs @ np.array([np.concatenate([ey, -wy, cx]), np.concatenate([-ex, wx, cy])])
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / products[:, :n]
            t = (wx * ey - wy * ex) * inv
            s = products[:, n : 2 * n] * inv
            # (a hair of overlap at segment ends: no ray slips between the two faces of a corner)
            seg = np.where((t > EPS) & (np.abs(s - 0.5) <= 0.5 + 1e-9), t, np.inf)
            if len(cx) == 0:
                return seg, live
            bproj = products[:, 2 * n :]
            t = bproj - np.sqrt(bproj * bproj - (cx * cx + cy * cy - self.circle_r**2))
            pillar = np.where(t > EPS, t, np.inf)  # NaN (a miss) compares False
        return np.hstack([seg, pillar]), np.concatenate([live, self._pillar_index])

    def layers(
        self, origin: np.ndarray, eye_z: float, angles: np.ndarray, n_layers: int, dirs: np.ndarray | None = None
    ) -> list[ColumnHits]:
        """The visible surfaces per column ray, nearest first.

        Layer 0 is the nearest hit; each further layer is the nearest surface whose top edge is
        seen above the previous layer's top edge (a wall behind a table). Painting the layers
        back to front gives correct occlusion for surfaces standing on the floor. ``dirs``: the
        unit vectors of ``angles`` when the caller has them.
        """
        out: list[ColumnHits] = []
        if self.n_surfaces == 0:
            return out
        if dirs is None:
            dirs = np.column_stack([np.cos(angles), np.sin(angles)])
        dist, index = self.cast_columns(origin, angles, dirs)
        if dist.shape[1] == 0:
            return out
        cols = np.arange(len(angles))
        top = (self.heights[index] - eye_z) / dist if n_layers > 1 else None  # tangent of each top edge
        behind = np.where(self._box_face[index], FLUSH, 0.0)  # a box face flush with a wall: the wall first
        for layer in range(n_layers):
            j = np.argmin(dist + behind, axis=1)
            d = dist[cols, j]
            found = d < np.inf
            if not found.any():
                break
            k = np.where(found, index[j], -1)
            out.append(ColumnHits(d, k, self._texture_u(origin, dirs, np.where(found, d, 0.0), index[j])))
            if top is not None and layer + 1 < n_layers:
                dist = np.where(top > top[cols, j][:, None] + 1e-12, dist, np.inf)
        return out

    def _texture_u(self, origin: np.ndarray, dirs: np.ndarray, d: np.ndarray, k: np.ndarray) -> np.ndarray:
        """Atlas column of the hit at distance ``d`` on surface ``k`` of each ray (unit ``dirs``)."""
        ax, ay, gx, gy, u0 = self._u_columns
        dx, dy = origin[0] + d * dirs[:, 0] - ax[k], origin[1] + d * dirs[:, 1] - ay[k]
        u = u0[k] + dx * gx[k] + dy * gy[k]
        if len(self.circle_r):
            pillar = np.flatnonzero(k >= self.n_segments)
            if pillar.size:  # around a pillar: u0 + arc length (gx holds radius * ppm)
                kp = k[pillar]
                u[pillar] = u0[kp] + (np.arctan2(dy[pillar], dx[pillar]) + math.pi) * gx[kp]
        return u

    # ----------------------------------------------------------------------------------------
    # Occlusion and collision

    def occluded(self, eye: np.ndarray, points: np.ndarray, margin: float = 0.02) -> np.ndarray:
        """Whether walls, box faces, pillars or people block the straight line from ``eye`` to each point.

        A surface hides a point when the line of sight crosses it (in plan) between the eye and
        the point, at a height between the floor and the surface's top. Surfaces closer than
        ``margin`` (m) to a point do not hide it (a landmark on a wall).
        """
        pts = np.asarray(points, dtype=float).reshape(-1, 3)
        if len(pts) == 0 or self.n_surfaces == 0:
            return np.zeros(len(pts), dtype=bool)
        v = pts - eye  # lines of sight (N, 3)
        length = np.maximum(np.hypot(v[:, 0], v[:, 1]), EPS)
        t_max = (1.0 - margin / length)[:, None]
        ex, ey = self._seg_e[:, 0], self._seg_e[:, 1]
        wx, wy = self.seg_a[:, 0] - eye[0], self.seg_a[:, 1] - eye[1]
        cx, cy = self.circle_xy[:, 0] - eye[0], self.circle_xy[:, 1] - eye[1]
        n = self.n_segments
        # v x e, v x w and v . c for every (point, surface) pair in one matrix product
        products = v[:, :2] @ np.array([np.concatenate([ey, -wy, cx]), np.concatenate([-ex, wx, cy])])
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / products[:, :n]
            t = (wx * ey - wy * ex) * inv  # fraction of the line of sight where it meets the segment
            s = products[:, n : 2 * n] * inv
            bproj = products[:, 2 * n :]
            a = (length * length)[:, None]
            tc = (bproj - np.sqrt(bproj * bproj - a * (cx * cx + cy * cy - self.circle_r**2))) / a
        t = np.hstack([np.where(np.abs(s - 0.5) <= 0.5, t, np.nan), tc])  # NaN: misses
        z = eye[2] + t * v[:, 2:3]  # height of the line of sight there
        with np.errstate(invalid="ignore"):
            hit = (t > 0) & (t < t_max) & (z >= 0) & (z <= self.heights)
        return hit.any(axis=1)

    def clearance(self, x: float, y: float) -> float:
        """Distance (m) from (x, y) to the nearest wall, box face or pillar surface (inf: none).

        People are not included (they move: the simulation adds them, :mod:`drivers.sim.people`).
        """
        best = math.inf
        if self.n_segments:
            ap = np.array([x, y]) - self.seg_a
            t = np.clip(np.sum(ap * self._seg_e, axis=1) / np.maximum(self.seg_len**2, EPS), 0.0, 1.0)
            closest = self.seg_a + t[:, None] * self._seg_e
            best = float(np.min(np.hypot(closest[:, 0] - x, closest[:, 1] - y)))
        if self.n_pillars:
            xy, r = self.circle_xy[: self.n_pillars], self.circle_r[: self.n_pillars]
            best = min(best, float(np.min(np.hypot(xy[:, 0] - x, xy[:, 1] - y) - r)))
        return best

    def nearest(self, x: float, y: float) -> tuple[float, float]:
        """Distance (m) and direction (rad, world) from (x, y) to the nearest point of any surface,
        people included ((inf, 0) in an empty world): where a robot there would touch first."""
        best, direction = math.inf, 0.0
        if self.n_segments:
            ap = np.array([x, y]) - self.seg_a
            t = np.clip(np.sum(ap * self._seg_e, axis=1) / np.maximum(self.seg_len**2, EPS), 0.0, 1.0)
            closest = self.seg_a + t[:, None] * self._seg_e
            d = np.hypot(closest[:, 0] - x, closest[:, 1] - y)
            i = int(np.argmin(d))
            best, direction = float(d[i]), math.atan2(closest[i, 1] - y, closest[i, 0] - x)
        if len(self.circle_r):
            d = np.hypot(self.circle_xy[:, 0] - x, self.circle_xy[:, 1] - y) - self.circle_r
            i = int(np.argmin(d))
            if d[i] < best:
                best, direction = float(d[i]), math.atan2(self.circle_xy[i, 1] - y, self.circle_xy[i, 0] - x)
        return best, direction

    def move_people(self, xy: np.ndarray) -> None:
        """Put the people's centres at ``xy`` (one row per person, in the world's order)."""
        if len(xy) == 0:
            return
        rows = slice(self.n_pillars, None)
        self.circle_xy[rows] = xy
        if self.atlas is not None:  # the texture anchors of round surfaces are their centres
            self._u_columns[0][self.n_segments + self.n_pillars :] = xy[:, 0]
            self._u_columns[1][self.n_segments + self.n_pillars :] = xy[:, 1]

    def cast_rays(self, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """Distance (m) along each ray (origins and unit directions, N x 2 each) to the first wall,
        box face, pillar or person it meets, from either side (inf: none)."""
        n = len(origins)
        best = np.full(n, np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.n_segments:
                ex, ey = self._seg_e[:, 0], self._seg_e[:, 1]
                wx = self.seg_a[:, 0] - origins[:, :1]  # (N, S)
                wy = self.seg_a[:, 1] - origins[:, 1:]
                dx, dy = dirs[:, :1], dirs[:, 1:]
                inv = 1.0 / (dx * ey - dy * ex)
                t = (wx * ey - wy * ex) * inv
                s = (wx * dy - wy * dx) * inv
                hit = np.where((t > EPS) & (np.abs(s - 0.5) <= 0.5 + 1e-9), t, np.inf)
                best = np.minimum(best, hit.min(axis=1))
            if len(self.circle_r):
                cx = self.circle_xy[:, 0] - origins[:, :1]
                cy = self.circle_xy[:, 1] - origins[:, 1:]
                b = cx * dirs[:, :1] + cy * dirs[:, 1:]
                t = b - np.sqrt(b * b - (cx * cx + cy * cy - self.circle_r**2))
                best = np.minimum(best, np.where(t > EPS, t, np.inf).min(axis=1))
        return best

    def collides(self, x: float, y: float, radius: float) -> bool:
        """Whether a robot disc of ``radius`` at (x, y) touches any wall, box face or pillar."""
        return self.clearance(x, y) < radius


def free_space_problem(world: World, pose: Pose2D, *, people: bool = True) -> str | None:
    """Why the robot cannot stand at ``pose`` (too close to a wall, box or pillar, or with
    ``people`` on a person where they are at time 0), or None.

    The world loader checks the start pose with it (people apart: it names the person), ``bearings
    run --start`` a pose given on the command line.
    """
    clearance = Scene(world).clearance(pose.x, pose.y)
    if clearance < world.robot_radius:
        return (f"({pose.x:g}, {pose.y:g}) is not in free space: {max(clearance, 0.0):.2f} m from a wall, box or "
                f"pillar, less than the robot radius {world.robot_radius:g} m")
    for index, person in enumerate(world.people if people else ()):
        x, y = position_at(person, 0.0)
        gap = math.hypot(x - pose.x, y - pose.y) - person.radius
        if gap < world.robot_radius:
            return (f"({pose.x:g}, {pose.y:g}) is on person {index} (at ({x:g}, {y:g}) at the start): "
                    f"{max(gap, 0.0):.2f} m from them, less than the robot radius {world.robot_radius:g} m")
    return None


def _surface_texture(spec: TextureSpec, length: float, height: float) -> np.ndarray:
    width = max(2, int(math.ceil(length * spec.pixels_per_m)) + 2)
    rows = max(2, int(math.ceil(height * spec.pixels_per_m)) + 2)
    return make_texture(spec, width, rows)
