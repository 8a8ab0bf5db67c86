"""Image rendering: a vectorised column ray-caster that fills each image with ONE ``cv2.remap``.

For a level cylindrical grid of view directions (one azimuth per column, one elevation per row),
every pixel sees either a wall, a pillar, the floor, the ceiling or the sky, and which one only
depends on the column's ray hits and the row's elevation:

- per column (W rays): the distance to the nearest surfaces and the atlas column of each hit
  (:meth:`~drivers.sim.scene.Scene.layers`);
- per row: the elevation, hence where a ray meets the floor or ceiling, or which sky texel;
- per pixel: an atlas coordinate, built from those with a few broadcast array operations.

The image is then ``cv2.remap(atlas, map)``; landmarks are drawn on top as small discs. Any other
central camera (pinhole, stereo, catadioptric, a tilted panorama) is rendered by a second remap
from such a level panorama, through lookup tables computed once from the camera model's
``pixel_to_bearing``.
"""

from __future__ import annotations

import functools
import math
from collections import OrderedDict
from dataclasses import dataclass

import cv2
import numpy as np

from drivers.sim.scene import SKY_PX_PER_RAD, ColumnHits, Scene
from perception.camera import PanoramaCamera

MAX_SOURCE_PIXELS = 3_000_000


@dataclass(frozen=True, slots=True)
class Grid:
    """A level cylindrical pixel grid: column ``u`` has azimuth ``az_first - u * step`` (left-positive),
    row ``v`` elevation ``el_first - v * step``."""

    width: int
    height: int
    az_first: float
    el_first: float
    step: float

    @classmethod
    def of_panorama(cls, model: PanoramaCamera) -> Grid:
        """The grid of a :class:`~perception.camera.PanoramaCamera` (exactly its pixel centres)."""
        r = model.rad_per_px
        return cls(model.width, model.height, model.width / 2.0 * r, model.horizon_row * r, r)

    def azimuths(self) -> np.ndarray:
        return self.az_first - self.step * np.arange(self.width)

    def elevations(self) -> np.ndarray:
        return self.el_first - self.step * np.arange(self.height)


class PanoramaRenderer:
    """Renders a level :class:`Grid` seen from a camera at height ``eye_z``.

    Everything that depends only on the grid and the eye height (floor/ceiling ray lengths, row
    bands, buffers) is computed once here; :meth:`render` then does the per-pose work.
    """

    def __init__(self, scene: Scene, grid: Grid, eye_z: float, *, layers: int = 2, landmarks: bool = True) -> None:
        self.scene, self.grid, self.eye_z = scene, grid, float(eye_z)
        self.n_layers = layers
        scene.ensure_textures()
        self.draw_landmarks = landmarks and len(scene.landmark_ids) > 0
        az, el = grid.azimuths(), grid.elevations()
        self.azimuths = az
        self._dirs = np.column_stack([np.cos(az), np.sin(az)])
        self.tan_el = np.tan(el)
        reach = scene.world.ground_margin
        ceiling = scene.world.ceiling
        with np.errstate(divide="ignore"):
            floor_r = np.where(el < 0, self.eye_z / -self.tan_el, np.inf)
            ceil_r = (
                np.where(el > 0, (ceiling - self.eye_z) / self.tan_el, np.inf) if ceiling else np.full_like(el, np.inf)
            )
        is_floor = floor_r <= reach
        is_ceiling = ceil_r <= reach
        # Every map coordinate is affine in one row quantity q (floor/ceiling: the horizontal
        # distance r to where the ray meets the plane; sky: the elevation) with per-column
        # coefficients, so each band of rows is ONE (rows x 2) @ (2 x W) matrix product.
        h, w = grid.height, grid.width
        sky_rows = ~(is_floor | is_ceiling)
        q = np.where(is_floor, floor_r, np.where(is_ceiling, ceil_r, el))
        self._q1 = np.column_stack([q, np.ones(h)]).astype(np.float32)  # rows: [q, 1]
        self._t1 = np.column_stack([self.tan_el, np.ones(h)]).astype(np.float32)  # rows: [tan el, 1]
        kinds = np.where(is_floor, 0, np.where(is_ceiling, 1, 2))
        kinds[sky_rows] = 2
        cuts = np.flatnonzero(np.diff(kinds)) + 1
        starts, ends = np.concatenate([[0], cuts]), np.concatenate([cuts, [h]])
        self._bands = [(int(s), int(e), int(kinds[s])) for s, e in zip(starts, ends, strict=True)]
        self._mx = np.empty((h, w), np.float32)
        self._my = np.empty((h, w), np.float32)
        self._rows = np.arange(h, dtype=np.uint8 if h < 256 else np.uint32)[:, None]
        self._offset = np.empty((h, w), self._rows.dtype)
        self._mask = np.empty((h, w), bool)
        self._coef = np.empty((2, w), np.float32)
        # per-surface constant of wall texture rows: v = vz0 - ppm * (eye_z + d * tan(el))
        self._v_base = scene.tex_vz0 - scene.ppm * self.eye_z

    def render(self, x: float, y: float, psi: float) -> np.ndarray:
        """The grey image seen from (x, y, eye_z) with the grid's azimuth 0 pointing at ``psi``."""
        mx, my = self.atlas_map(x, y, psi)
        assert self.scene.atlas is not None, "the renderer builds the scene's textures when it is made"
        image = cv2.remap(self.scene.atlas, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        if self.draw_landmarks:
            self.draw_landmarks_on(image, x, y, psi)
        return image

    def atlas_map(self, x: float, y: float, psi: float) -> tuple[np.ndarray, np.ndarray]:
        """The atlas column and row (H x W float32 each) that every pixel samples for this pose.

        The arrays are this renderer's buffers, overwritten by the next call.
        """
        scene, mx, my, coef = self.scene, self._mx, self._my, self._coef
        c, s = math.cos(psi), math.sin(psi)
        dirs = self._dirs @ np.array([[c, s], [-s, c]])  # the column directions turned by psi
        for r0, r1, kind in self._bands:
            rows = self._q1[r0:r1]
            if kind == 2:  # sky (or far ground): texel from world azimuth and elevation
                k = SKY_PX_PER_RAD
                coef[0] = 0.0
                coef[1] = self.azimuths * k + (scene.sky_region.u0 + (psi % (2.0 * math.pi) + 2.0 * math.pi) * k)
                np.matmul(rows, coef, out=mx[r0:r1])
                coef[0] = -k
                coef[1] = scene.sky_horizon_v
                np.matmul(rows, coef, out=my[r0:r1])
            else:  # floor or ceiling: texel of the world point at distance r along the column
                region = scene.floor_region if kind == 0 else scene.ceiling_region
                assert region is not None, "a ceiling band exists only under a ceiling"
                fx0, fy0 = scene.floor_origin
                p = region.pixels_per_m
                coef[0] = dirs[:, 0] * p
                coef[1] = region.u0 + p * (x - fx0)
                np.matmul(rows, coef, out=mx[r0:r1])
                coef[0] = dirs[:, 1] * p
                coef[1] = region.v0 + p * (y - fy0)
                np.matmul(rows, coef, out=my[r0:r1])
        self._layers = []
        if scene.n_surfaces:
            self._layers = scene.layers(np.array([x, y]), self.eye_z, self.azimuths + psi, self.n_layers, dirs)
            if self._layers:
                tops, bottoms = self._spans(self._layers)
                for i in reversed(range(len(self._layers))):  # back to front
                    # only the part seen above the nearer layers needs painting
                    bottom = np.minimum(bottoms[i], tops[:i].min(axis=0)) if i else bottoms[i]
                    self._paint(self._layers[i], tops[i], bottom)
        return mx, my

    def _spans(self, layers: list[ColumnHits]) -> tuple[np.ndarray, np.ndarray]:
        """First and past-the-last image row of each layer's wall in each column (K, W) (equal: none).

        Row ``i`` sees elevation ``el_first - i * step``: a wall whose edges are at elevations
        ``top`` and ``bottom`` covers rows ``ceil((el_first - top) / step)`` to
        ``floor((el_first - bottom) / step)``.
        """
        grid, ez = self.grid, self.eye_z
        surface = np.stack([hits.surface for hits in layers])
        found = surface >= 0
        d = np.where(found, np.stack([hits.distance for hits in layers]), 1.0)
        h = np.where(found, self.scene.heights[np.maximum(surface, 0)], -1.0)
        self._stacked = (d, h)  # for the landmarks' occlusion test
        scale = 1.0 / grid.step
        first = np.ceil((grid.el_first - np.arctan((h - ez) / d)) * scale - 1e-9)
        last = np.floor((grid.el_first + np.arctan(ez / d)) * scale + 1e-9) + 1.0
        top = np.clip(first, 0, grid.height).astype(np.int64)
        bottom = np.where(found, np.clip(last, 0, grid.height), top).astype(np.int64)
        return top, np.maximum(bottom, top)

    def _paint(self, hits: ColumnHits, top: np.ndarray, bottom: np.ndarray) -> None:
        """Overwrite the map with one layer of wall hits (each column: one contiguous row span)."""
        scene = self.scene
        r0, r1 = int(top.min()), int(bottom.max())
        if r1 <= r0:
            return
        k = np.maximum(hits.surface, 0)
        d = np.where(hits.surface >= 0, hits.distance, 1.0)
        # rows r with top <= r < bottom: (r - top) < (bottom - top), in wrapping unsigned arithmetic
        dtype = self._rows.dtype
        mask = self._mask[: r1 - r0]
        np.less(
            np.subtract(self._rows[r0:r1], top.astype(dtype), out=self._offset[: r1 - r0]),
            (bottom - top).astype(dtype),
            out=mask,
        )
        u = cv2.repeat(hits.u.astype(np.float32)[None, :], r1 - r0, 1)
        self._coef[0] = -scene.ppm[k] * d
        self._coef[1] = self._v_base[k]
        v = self._t1[r0:r1] @ self._coef  # v = vz0 - ppm * (eye_z + d * tan(el)), one matrix product
        cv2.copyTo(u, mask.view(np.uint8), self._mx[r0:r1])
        cv2.copyTo(v, mask.view(np.uint8), self._my[r0:r1])

    def draw_landmarks_on(self, image: np.ndarray, x: float, y: float, psi: float) -> None:
        """Draw the landmarks visible from this pose as discs (a ring and a bright or dark core).

        The disc's diameter is the landmark's ``size`` at its distance (at least 3 pixels);
        a landmark is hidden when a wall layer of its column stands in front of it.
        """
        scene, grid = self.scene, self.grid
        rel = scene.landmark_xyz - (x, y, self.eye_z)
        horiz = np.hypot(rel[:, 0], rel[:, 1])
        two_pi = 2.0 * math.pi
        u = np.mod(psi + grid.az_first - np.arctan2(rel[:, 1], rel[:, 0]), two_pi) / grid.step
        v = (grid.el_first - np.arctan2(rel[:, 2], horiz)) / grid.step
        radius = np.maximum(1.5, (0.5 / grid.step) * scene.landmark_size / np.hypot(horiz, rel[:, 2]))
        idx = np.flatnonzero((u < grid.width + radius) & (v > -radius) & (v < grid.height + radius))
        if idx.size == 0:
            return
        idx = idx[~self._hidden(idx, u, horiz, rel[:, 2])]
        idx = idx[np.argsort(-horiz[idx])]  # far first: near discs cover far ones
        uu, vv, rr = u[idx], v[idx], radius[idx]
        cores = scene.landmark_cores[idx]
        if abs(grid.width * grid.step - two_pi) < 1e-6:  # a disc across the seam: draw both sides
            wrap = (uu > grid.width - rr) | (uu < rr)
            if wrap.any():
                shifted = np.where(uu[wrap] < rr[wrap], uu[wrap] + grid.width, uu[wrap] - grid.width)
                uu, vv = np.concatenate([uu, shifted]), np.concatenate([vv, vv[wrap]])
                rr, cores = np.concatenate([rr, rr[wrap]]), np.concatenate([cores, cores[wrap]])
        fixed = np.rint(np.column_stack([uu * 16, vv * 16, rr * 16, rr * 8])).astype(int).tolist()
        for (cu, cv, outer, inner), core in zip(fixed, cores.tolist(), strict=True):
            cv2.circle(image, (cu, cv), outer, 255 - core, -1, cv2.LINE_AA, 4)
            if outer > 40:  # a core only where it shows (radius above 2.5 px)
                cv2.circle(image, (cu, cv), inner, core, -1, cv2.LINE_AA, 4)

    def _hidden(self, idx: np.ndarray, u: np.ndarray, horiz: np.ndarray, dz: np.ndarray) -> np.ndarray:
        """Whether a wall layer of the landmark's column stands in front of the landmark."""
        if not self._layers:
            return np.zeros(len(idx), dtype=bool)
        col = np.minimum(np.rint(u[idx]).astype(int), self.grid.width - 1)
        d, h = self._stacked[0][:, col], self._stacked[1][:, col]  # (layers, landmarks)
        z = self.eye_z + (dz[idx] / np.maximum(horiz[idx], 1e-9)) * d  # line of sight's height at the wall
        return np.any((d < horiz[idx] - 0.02) & (z <= h) & (z >= 0), axis=0)


@functools.lru_cache(maxsize=16)
def pixel_bearings(model) -> tuple[np.ndarray, np.ndarray, float]:  # noqa: ANN001 - any frozen camera model
    """Body-frame bearings (float32) of every pixel centre (H*W, 3; NaN where it sees nothing, e.g.
    outside a donut), the valid mask, and the finest angular spacing of horizontally adjacent
    pixels (rad). Cached per model: undistorting 300k points takes a while."""
    h, w = model.height, model.width
    us, vs = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    uv = np.column_stack([us.ravel(), vs.ravel()])
    b = model.pixel_to_bearing(uv)
    back, valid = model.bearing_to_pixel(b)
    valid &= np.all(np.abs(np.nan_to_num(back, nan=1e9) - uv) < 0.5, axis=1)
    b = np.where(valid[:, None], b, np.nan)
    grid_b = b.reshape(h, w, 3)
    cross = np.linalg.norm(np.cross(grid_b[:, 1:], grid_b[:, :-1]), axis=2)  # sin of the angle: exact when small
    spacing = np.arcsin(np.clip(cross[np.isfinite(cross)], 0.0, 1.0))
    bearings = b.astype(np.float32)  # float32: the per-tilt lookup tables are computed fast
    bearings.flags.writeable = False
    step = max(float(np.percentile(spacing, 10)) if spacing.size else 0.01, math.radians(0.04))
    return bearings, valid, step


class CameraRenderer:
    """Renders one camera model of any kind at a camera pose.

    The camera pose is ``eye`` (world, 3,), ``psi`` (world yaw of the level frame) and
    ``rest`` (3 x 3 rotation of the camera body in that level frame: pitch, and roll or yaw that
    a pan-tilt head adds). A level panorama is rendered directly; anything else through a level
    source panorama at the same eye and a precomputed remap (cached per ``rest`` and eye height).
    """

    def __init__(self, scene: Scene, model, *, layers: int = 2, cache: int = 8) -> None:  # noqa: ANN001
        self.scene, self.model, self.layers = scene, model, layers
        self._cache: OrderedDict[tuple, tuple[PanoramaRenderer, tuple[np.ndarray, np.ndarray] | None]] = OrderedDict()
        self._cache_size = cache

    def render(self, eye: np.ndarray, psi: float, rest: np.ndarray) -> np.ndarray:
        renderer, maps = self._prepare(rest, float(eye[2]))
        image = renderer.render(float(eye[0]), float(eye[1]), psi)
        if maps is None:
            return image
        return cv2.remap(image, maps[0], maps[1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)

    def _prepare(self, rest: np.ndarray, eye_z: float) -> tuple[PanoramaRenderer, tuple[np.ndarray, np.ndarray] | None]:
        key = (np.round(rest, 9).tobytes(), round(eye_z, 9))
        hit = self._cache.get(key)
        if hit is not None:
            self._cache.move_to_end(key)
            return hit
        level = np.allclose(rest, np.eye(3), atol=1e-12)
        entry: tuple[PanoramaRenderer, tuple[np.ndarray, np.ndarray] | None]
        if isinstance(self.model, PanoramaCamera) and level:
            entry = (PanoramaRenderer(self.scene, Grid.of_panorama(self.model), eye_z, layers=self.layers), None)
        else:
            grid, maps = self._source(rest)
            entry = (PanoramaRenderer(self.scene, grid, eye_z, layers=self.layers), maps)
        self._cache[key] = entry
        if len(self._cache) > self._cache_size:
            self._cache.popitem(last=False)
        return entry

    def _source(self, rest: np.ndarray) -> tuple[Grid, tuple[np.ndarray, np.ndarray]]:
        """The level source grid covering this camera at rotation ``rest``, and the remap tables."""
        b, valid, step = pixel_bearings(self.model)
        h, w = self.model.height, self.model.width
        level = b @ np.asarray(rest, dtype=np.float32).T
        az = np.arctan2(level[:, 1], level[:, 0])
        el = np.arcsin(np.clip(level[:, 2], -1.0, 1.0))
        az_v, el_v = az[valid], el[valid]
        span = float(np.ptp(az_v)) if az_v.size else 0.0
        if az_v.size == 0 or span > math.radians(300.0) or np.abs(az_v).max() > math.radians(170.0):
            az_hi, az_lo = math.pi + 2 * step, -math.pi - 2 * step
        else:
            az_hi, az_lo = float(az_v.max()) + 2 * step, float(az_v.min()) - 2 * step
        el_hi = min(float(el_v.max()) + 2 * step, math.radians(89.9)) if el_v.size else 0.1
        el_lo = max(float(el_v.min()) - 2 * step, math.radians(-89.9)) if el_v.size else -0.1
        while (az_hi - az_lo) * (el_hi - el_lo) / step**2 > MAX_SOURCE_PIXELS:
            step *= 1.25
        grid = Grid(
            width=int(math.ceil((az_hi - az_lo) / step)) + 1,
            height=int(math.ceil((el_hi - el_lo) / step)) + 1,
            az_first=az_hi,
            el_first=el_hi,
            step=step,
        )
        scale = np.float32(1.0 / step)
        map_u = np.where(valid, (np.float32(grid.az_first) - az) * scale, np.float32(-1.0)).reshape(h, w)
        map_v = np.where(valid, (np.float32(grid.el_first) - el) * scale, np.float32(-1.0)).reshape(h, w)
        return grid, (map_u, map_v)
