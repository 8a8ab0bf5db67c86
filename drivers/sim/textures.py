"""Procedural textures and the texture atlas every rendered image samples from.

Textures are generated from a seed at load time, so the repository holds no image files and the
same seed always gives the same pixels. A wall texture is a smooth grey background covered with
random filled shapes (rectangles, polygons, ellipses, lines) of a few sizes: many corners at
every scale for feature detectors (ORB, SIFT), and no repeating pattern that would make matches
ambiguous. All textures of a world are packed into one 8-bit atlas so that a whole image is filled
with a single ``cv2.remap``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from drivers.sim.world_values import TextureSpec

PAD = 2  # texels of clamped border around each texture: bilinear sampling never bleeds
MAX_ATLAS_WIDTH = 16384  # cv2.remap needs coordinates below 32767


def smooth_noise(rng: np.random.Generator, height: int, width: int, cell: float) -> np.ndarray:
    """Band-limited noise in [-1, 1] with blobs about ``cell`` texels wide (float32)."""
    gh, gw = max(2, int(height / cell) + 2), max(2, int(width / cell) + 2)
    grid = rng.uniform(-1.0, 1.0, size=(gh, gw)).astype(np.float32)
    return cv2.resize(grid, (width, height), interpolation=cv2.INTER_CUBIC).clip(-1.0, 1.0)


def make_texture(spec: TextureSpec, width: int, height: int) -> np.ndarray:
    """A ``height x width`` grey texture (uint8) of random painted shapes, seeded by ``spec``."""
    rng = np.random.default_rng(spec.seed)
    feature = max(2.0, spec.feature_size * spec.pixels_per_m)
    base = spec.brightness + 25.0 * spec.contrast * smooth_noise(rng, height, width, 4.0 * feature)
    img = base.clip(0, 255).astype(np.uint8)
    n_shapes = int(0.6 * width * height / (feature * feature)) + 4
    kinds = rng.integers(0, 4, n_shapes)
    centres = rng.uniform((0, 0), (width, height), size=(n_shapes, 2))
    sizes = feature * np.exp(rng.uniform(np.log(0.3), np.log(2.5), n_shapes))
    greys = (spec.brightness + spec.contrast * rng.uniform(-110, 110, n_shapes)).clip(0, 255)
    angles = rng.uniform(0, np.pi, n_shapes)
    aspects = rng.uniform(0.3, 1.0, n_shapes)
    for kind, (x, y), size, grey, angle, aspect in zip(kinds, centres, sizes, greys, angles, aspects, strict=True):
        colour = int(grey)
        half = (size / 2.0, size * aspect / 2.0)
        if kind == 0:  # rotated rectangle
            box = cv2.boxPoints(((float(x), float(y)), (2 * half[0], 2 * half[1]), float(np.degrees(angle))))
            cv2.fillConvexPoly(img, np.round(box).astype(np.int32), colour, lineType=cv2.LINE_AA)
        elif kind == 1:  # random triangle / quad
            k = int(rng.integers(3, 5))
            pts = np.array([x, y]) + rng.uniform(-size / 2, size / 2, size=(k, 2))
            cv2.fillPoly(img, [np.round(pts).astype(np.int32)], colour, lineType=cv2.LINE_AA)
        elif kind == 2:  # ellipse
            axes = (max(1, int(half[0])), max(1, int(half[1])))
            cv2.ellipse(img, (int(x), int(y)), axes, float(np.degrees(angle)), 0, 360, colour, -1, cv2.LINE_AA)
        else:  # thick line
            d = np.array([np.cos(angle), np.sin(angle)]) * size
            p0, p1 = np.array([x, y]) - d, np.array([x, y]) + d
            thickness = max(1, int(size * aspect / 4))
            cv2.line(
                img, tuple(np.round(p0).astype(int)), tuple(np.round(p1).astype(int)), colour, thickness, cv2.LINE_AA
            )
    return img


def make_sky(seed: int, width: int, height: int, *, indoor: bool) -> np.ndarray:
    """Sky (bright, soft clouds) or a dim far band for indoor worlds; periodic in azimuth columns."""
    rng = np.random.default_rng(seed)
    period = smooth_noise(rng, height, width, width / 24.0)
    grey = (60.0 if indoor else 200.0) + (10.0 if indoor else 30.0) * period
    return grey.clip(0, 255).astype(np.uint8)


@dataclass(frozen=True, slots=True)
class Region:
    """Where one texture sits in the atlas: top-left texel (u0, v0), size, texels per metre."""

    u0: int
    v0: int
    width: int
    height: int
    pixels_per_m: float


class AtlasBuilder:
    """Packs textures into one atlas image with shelf packing (rows of strips, tallest first)."""

    def __init__(self) -> None:
        self._items: list[np.ndarray] = []

    def add(self, texture: np.ndarray) -> int:
        """Queue a texture; returns its index for :meth:`build`."""
        self._items.append(texture)
        return len(self._items) - 1

    def build(self) -> tuple[np.ndarray, list[tuple[int, int]]]:
        """The atlas and the (u0, v0) of each texture's first texel, in the order added."""
        widest = max((t.shape[1] for t in self._items), default=1) + 2 * PAD
        width = int(min(MAX_ATLAS_WIDTH, max(4096, widest)))
        order = sorted(range(len(self._items)), key=lambda i: -self._items[i].shape[0])
        origins: list[tuple[int, int]] = [(0, 0)] * len(self._items)
        x = y = shelf = 0
        for i in order:
            h, w = self._items[i].shape[0] + 2 * PAD, self._items[i].shape[1] + 2 * PAD
            if w > width:
                raise ValueError(f"a texture {w} texels wide does not fit the atlas: lower its pixels_per_m")
            if x + w > width:
                x, y, shelf = 0, y + shelf, 0
            origins[i] = (x + PAD, y + PAD)
            x, shelf = x + w, max(shelf, h)
        atlas = np.zeros((y + shelf, width), np.uint8)
        for i, tex in enumerate(self._items):
            u0, v0 = origins[i]
            padded = cv2.copyMakeBorder(tex, PAD, PAD, PAD, PAD, cv2.BORDER_REPLICATE)
            atlas[v0 - PAD : v0 - PAD + padded.shape[0], u0 - PAD : u0 - PAD + padded.shape[1]] = padded
        if atlas.shape[0] >= 32767:
            raise ValueError("the world's textures do not fit one atlas: lower pixels_per_m")
        return atlas, origins
