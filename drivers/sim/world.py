"""Simulated worlds: the values a world file describes, and the validating loader.

A world is a flat floor with vertical surfaces on it (wall polylines, boxes, round pillars), point
landmarks anywhere in 3D, a ceiling or an open sky, the robot's start and named poses, its pan-tilt
unit and cameras, and the lighting. The file format is documented in ``docs/worlds.md``. Files are
read through :mod:`maps.store` only, and every problem of a file is reported at once as an
:class:`~maps.store.InputError` with ``file:line:col`` diagnostics, like missions.

Units: metres in the file and in here; angles are degrees in the file (keys end in ``_deg``) and
radians in these values.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from maps.store import Diagnostic, InputError, Mark, YamlList, YamlMap, load_yaml, mark_of
from perception.camera import PanoramaCamera, PinholeCamera, StereoRig, camera_from_dict
from perception.geometry import Pose2D

FORMAT_VERSION = 1
CAMERA_KINDS = ("bearings", "panorama", "catadioptric", "pinhole", "stereo")
MOUNTS = ("base", "ptu")


@dataclass(frozen=True, slots=True)
class TextureSpec:
    """How a surface's procedural texture is generated: seed, resolution and feature size."""

    seed: int
    pixels_per_m: float = 60.0
    feature_size: float = 0.2  # m, typical size of a painted shape
    brightness: float = 128.0  # mean grey level
    contrast: float = 1.0


@dataclass(frozen=True, slots=True)
class Wall:
    """A vertical textured surface along a polyline from the floor up to ``height``.

    ``two_sided`` walls are visible from both sides (free-standing walls); the faces of boxes are
    one-sided (their insides are never seen).
    """

    points: tuple[tuple[float, float], ...]
    height: float
    texture: TextureSpec
    two_sided: bool = True


@dataclass(frozen=True, slots=True)
class Pillar:
    """A vertical cylinder standing on the floor."""

    x: float
    y: float
    radius: float
    height: float
    texture: TextureSpec


@dataclass(frozen=True, slots=True)
class Landmark:
    """A point landmark (for the ``bearings`` sensor; drawn as a small disc in images)."""

    id: int
    x: float
    y: float
    z: float
    size: float = 0.1  # m, diameter of the drawn disc


@dataclass(frozen=True, slots=True)
class MountPose:
    """Where a camera sits on its mount (base frame, or pan-tilt head frame), REP-103 axes."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    yaw: float = 0.0
    pitch: float = 0.0  # rad, positive looks up


@dataclass(frozen=True, slots=True)
class PtuSpec:
    """The pan-tilt unit: where it sits on the base, its limits and its top slew rate.

    Defaults are those of a Directed Perception PTU-D46-17 (+-159 deg pan, -47/+31 deg tilt,
    300 deg/s).
    """

    x: float = 0.1
    y: float = 0.0
    z: float = 1.0
    pan_limits: tuple[float, float] = (math.radians(-159.0), math.radians(159.0))
    tilt_limits: tuple[float, float] = (math.radians(-47.0), math.radians(31.0))
    max_speed: float = math.radians(300.0)


@dataclass(frozen=True, slots=True)
class CameraSpec:
    """One simulated camera: kind, mount, pose on the mount, model and imperfections.

    ``model`` is a :mod:`perception.camera` model for image cameras and None for ``bearings``.
    The ``bearings`` sensor uses ``noise`` (rad, per axis), ``azimuth_fov`` (rad, centred on the
    camera x axis), ``elevation_limits`` (rad) and ``max_range`` (m).
    """

    name: str
    kind: str
    mount: str = "base"
    pose: MountPose = MountPose(z=0.9)
    model: Any = None
    frame_drop: float = 0.0  # probability that grab() returns None
    exposure_noise: float = 0.0  # relative sigma of the per-frame gain, plus pixel noise
    noise: float = 0.0
    azimuth_fov: float = 2.0 * math.pi
    elevation_limits: tuple[float, float] = (math.radians(-60.0), math.radians(60.0))
    max_range: float = math.inf


@dataclass(frozen=True, slots=True)
class Lighting:
    """Global brightness: ``out = gain * in + bias``; ``run_variation`` draws a new gain per seed."""

    gain: float = 1.0
    bias: float = 0.0
    run_variation: float = 0.0


@dataclass(frozen=True, slots=True)
class World:
    """Everything a world file describes (see ``docs/worlds.md``)."""

    name: str
    seed: int = 0
    walls: tuple[Wall, ...] = ()
    pillars: tuple[Pillar, ...] = ()
    landmarks: tuple[Landmark, ...] = ()
    ceiling: float | None = None  # m; None: open sky
    floor: TextureSpec = TextureSpec(seed=0, pixels_per_m=25.0, feature_size=0.25, contrast=0.6)
    ground_margin: float = 10.0
    start: Pose2D = Pose2D()
    poses: dict[str, Pose2D] = field(default_factory=dict)
    robot_radius: float = 0.26
    ptu: PtuSpec = PtuSpec()
    cameras: tuple[CameraSpec, ...] = ()
    lighting: Lighting = Lighting()
    source: str = "<builtin>"

    def camera(self, name: str) -> CameraSpec:
        for spec in self.cameras:
            if spec.name == name:
                return spec
        raise KeyError(f"no camera {name!r} in world {self.name!r} (has: {', '.join(self.camera_names)})")

    @property
    def camera_names(self) -> tuple[str, ...]:
        return tuple(spec.name for spec in self.cameras)

    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of walls, pillars, start and poses (landmarks excluded)."""
        xs = [self.start.x, *(p.x for p in self.poses.values())]
        ys = [self.start.y, *(p.y for p in self.poses.values())]
        for wall in self.walls:
            xs += [p[0] for p in wall.points]
            ys += [p[1] for p in wall.points]
        for p in self.pillars:
            xs += [p.x - p.radius, p.x + p.radius]
            ys += [p.y - p.radius, p.y + p.radius]
        return min(xs), min(ys), max(xs), max(ys)


def default_cameras() -> tuple[CameraSpec, ...]:
    """The camera set of a world file without ``cameras``: one of each kind.

    ``panorama`` (720 x 172 at 0.5 deg/px) and ``omni`` (its raw catadioptric donut) on a mast on
    the base, ``landmarks`` (ideal bearings), and on the pan-tilt unit a ``front`` pinhole and a
    ``stereo`` pair (12 cm baseline).
    """
    mast = MountPose(z=0.9)
    head = MountPose(x=0.05, z=0.08)
    pinhole = PinholeCamera(640, 480, 525.0, 525.0, 319.5, 239.5, (-0.05, 0.01, 0.0, 0.0))
    rect = PinholeCamera(640, 480, 525.0, 525.0, 319.5, 239.5)
    return (
        CameraSpec("panorama", "panorama", "base", mast, PanoramaCamera()),
        CameraSpec("omni", "catadioptric", "base", mast, camera_from_dict({"kind": "catadioptric"})),
        CameraSpec("landmarks", "bearings", "base", mast, None, noise=math.radians(0.5), max_range=100.0),
        CameraSpec("front", "pinhole", "ptu", head, pinhole),
        CameraSpec("stereo", "stereo", "ptu", head, StereoRig(rect, rect, 0.12)),
    )


def empty_world() -> World:
    """An empty plane under an open sky, with the default cameras and no landmarks."""
    return World(name="empty", cameras=default_cameras())


# --------------------------------------------------------------------------------------------
# Shipped worlds and loading


def _worlds_dir() -> Path:
    return Path(str(resources.files("drivers") / "worlds"))


def shipped_worlds() -> dict[str, Path]:
    """Names and paths of the worlds shipped in ``drivers/worlds``."""
    folder = _worlds_dir()
    return {p.stem: p for p in sorted(folder.glob("*.yaml"))}


def load_world(world: str | Path | None) -> World:
    """A shipped world by name, a world file by path, or the empty plane (None/""/"empty")."""
    if world is None or str(world) in ("", "empty"):
        return empty_world()
    shipped = shipped_worlds()
    if isinstance(world, str) and world in shipped:
        return parse_world(load_yaml(shipped[world]), file=str(shipped[world]), default_name=world)
    path = Path(world)
    if not path.exists() and path.suffix == "":
        known = ", ".join(["empty", *shipped])
        raise InputError([Diagnostic(str(world), 0, 0, f"no such world file or shipped world (shipped: {known})")])
    return parse_world(load_yaml(path), file=str(path), default_name=path.stem)


# --------------------------------------------------------------------------------------------
# Validation


class _Checker:
    """Collects located diagnostics while converting located YAML data to values."""

    def __init__(self, file: str) -> None:
        self.file = file
        self.diagnostics: list[Diagnostic] = []

    def error(self, mark: Mark, message: str) -> None:
        self.diagnostics.append(Diagnostic(self.file, mark.line, mark.col, message))

    def mapping(self, value: Any, mark: Mark, what: str) -> YamlMap | None:
        if isinstance(value, YamlMap):
            return value
        self.error(mark_of(value, mark), f"{what} must be a mapping, got {_describe(value)}")
        return None

    def sequence(self, value: Any, mark: Mark, what: str) -> YamlList | None:
        if isinstance(value, YamlList):
            return value
        self.error(mark_of(value, mark), f"{what} must be a list, got {_describe(value)}")
        return None

    def keys(self, m: YamlMap, allowed: tuple[str, ...], what: str, required: tuple[str, ...] = ()) -> None:
        for key in m:
            if key not in allowed:
                hint = _closest(str(key), allowed)
                self.error(m.mark_of(key), f"unknown key {key!r} in {what}{hint} (allowed: {', '.join(allowed)})")
        for key in required:
            if key not in m:
                self.error(m.mark, f"{what} needs {key!r}")

    def number(
        self,
        m: YamlMap,
        key: str,
        default: float | None,
        *,
        lo: float | None = None,
        hi: float | None = None,
        strict_lo: bool = False,
        what: str = "",
    ) -> float | None:
        if key not in m:
            return default
        value, mark = m[key], m.value_mark_of(key)
        return self.check_number(value, mark, f"{what}{key}", lo=lo, hi=hi, strict_lo=strict_lo, default=default)

    def check_number(
        self,
        value: Any,
        mark: Mark,
        what: str,
        *,
        lo: float | None = None,
        hi: float | None = None,
        strict_lo: bool = False,
        default: float | None = None,
    ) -> float | None:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.error(mark, f"{what} must be a finite number, got {_describe(value)}")
            return default
        if lo is not None and (value < lo or (strict_lo and value <= lo)):
            self.error(mark, f"{what} must be {'>' if strict_lo else '>='} {lo:g}, got {value:g}")
            return default
        if hi is not None and value > hi:
            self.error(mark, f"{what} must be <= {hi:g}, got {value:g}")
            return default
        return float(value)

    def num(self, m: YamlMap, key: str, default: float, **limits: Any) -> float:
        """:meth:`number` with a default: the value, or ``default`` when absent or invalid."""
        value = self.number(m, key, default, **limits)
        return default if value is None else value

    def integer(self, m: YamlMap, key: str, default: int, what: str = "") -> int:
        if key not in m:
            return default
        value = m[key]
        if isinstance(value, bool) or not isinstance(value, int):
            self.error(m.value_mark_of(key), f"{what}{key} must be an integer, got {_describe(value)}")
            return default
        return int(value)

    def vector(self, m: YamlMap, key: str, n: int, what: str) -> tuple[float, ...] | None:
        """A list of ``n`` finite numbers at ``m[key]``."""
        if key not in m:
            return None
        value, mark = m[key], m.value_mark_of(key)
        if not isinstance(value, YamlList) or len(value) != n:
            self.error(mark, f"{what} must be a list of {n} numbers, got {_describe(value)}")
            return None
        out = [self.check_number(v, value.mark_of(i), f"{what}[{i}]") for i, v in enumerate(value)]
        return None if any(v is None for v in out) else tuple(out)  # type: ignore[arg-type]


def _describe(value: Any) -> str:
    if isinstance(value, YamlMap):
        return "a mapping"
    if isinstance(value, YamlList):
        return f"a list of {len(value)}"
    if value is None:
        return "nothing"
    return f"{type(value).__name__} {value!r}"


def _closest(word: str, options: tuple[str, ...]) -> str:
    match = difflib.get_close_matches(word, options, n=1)
    return f" (did you mean {match[0]!r}?)" if match else ""


_TOP_KEYS = (
    "format", "name", "description", "seed", "ceiling", "ground_margin", "floor", "walls", "boxes",
    "pillars", "landmarks", "start", "poses", "robot", "ptu", "cameras", "lighting",
)  # fmt: skip
_TEXTURE_KEYS = ("seed", "pixels_per_m", "feature_size", "brightness", "contrast")


def parse_world(data: Any, *, file: str, default_name: str = "world") -> World:
    """Validate located YAML data (from :func:`maps.store.load_yaml`) into a :class:`World`.

    Raises :class:`~maps.store.InputError` listing every problem found, each with file:line:col.
    """
    c = _Checker(file)
    root = c.mapping(data, Mark(1, 1), "a world file")
    if root is None:
        raise InputError(c.diagnostics)
    c.keys(root, _TOP_KEYS, "the world")
    if "format" in root and root["format"] != FORMAT_VERSION:
        c.error(root.value_mark_of("format"), f"unsupported world format {root['format']!r} (this is {FORMAT_VERSION})")
    name = root.get("name", default_name)
    if not isinstance(name, str) or not name:
        c.error(root.value_mark_of("name"), "name must be a non-empty string")
        name = default_name
    seed = c.integer(root, "seed", 0)
    ceiling = None
    if root.get("ceiling") is not None:
        ceiling = c.number(root, "ceiling", None, lo=0.0, strict_lo=True)
    margin = c.num(root, "ground_margin", 10.0, lo=1.0, hi=1000.0)
    surface_counter = iter(range(1, 1_000_000))

    def texture(parent: YamlMap, default: TextureSpec) -> TextureSpec:
        if "texture" not in parent:
            return default
        m = c.mapping(parent["texture"], parent.value_mark_of("texture"), "texture")
        if m is None:
            return default
        c.keys(m, _TEXTURE_KEYS, "texture")
        return TextureSpec(
            seed=c.integer(m, "seed", default.seed, "texture "),
            pixels_per_m=c.num(m, "pixels_per_m", default.pixels_per_m, lo=1.0, hi=1000.0, what="texture "),
            feature_size=c.num(m, "feature_size", default.feature_size, lo=0.0, strict_lo=True, what="texture "),
            brightness=c.num(m, "brightness", default.brightness, lo=0.0, hi=255.0, what="texture "),
            contrast=c.num(m, "contrast", default.contrast, lo=0.0, hi=4.0, what="texture "),
        )

    def auto_texture(ppm: float = 60.0) -> TextureSpec:
        return TextureSpec(seed=seed * 1000 + next(surface_counter), pixels_per_m=ppm)

    floor = TextureSpec(seed=seed * 1000, pixels_per_m=25.0, feature_size=0.25, contrast=0.6)
    if "floor" in root:
        fm = c.mapping(root["floor"], root.value_mark_of("floor"), "floor")
        if fm is not None:
            c.keys(fm, ("texture",), "floor")
            floor = texture(fm, floor)

    walls: list[Wall] = []
    for item, mark in _items(c, root, "walls"):
        m = c.mapping(item, mark, "a wall")
        if m is None:
            continue
        c.keys(m, ("points", "height", "closed", "texture"), "a wall", required=("points", "height"))
        height = c.number(m, "height", None, lo=0.0, strict_lo=True, what="wall ")
        points = _points(c, m, "points", 2)
        closed = m.get("closed", False)
        if not isinstance(closed, bool):
            c.error(m.value_mark_of("closed"), "closed must be true or false")
            closed = False
        tex = texture(m, auto_texture())
        if points is not None and height is not None:
            if closed:
                points = (*points, points[0])
            walls.append(Wall(tuple(points), height, tex, two_sided=True))

    for item, mark in _items(c, root, "boxes"):
        m = c.mapping(item, mark, "a box")
        if m is None:
            continue
        c.keys(m, ("center", "size", "height", "yaw_deg", "texture"), "a box", required=("center", "size", "height"))
        center = c.vector(m, "center", 2, "box center")
        size = c.vector(m, "size", 2, "box size")
        if size is not None and min(size) <= 0:
            c.error(m.value_mark_of("size"), f"box size must be positive, got {list(size)}")
            size = None
        height = c.number(m, "height", None, lo=0.0, strict_lo=True, what="box ")
        yaw = math.radians(c.num(m, "yaw_deg", 0.0))
        tex = texture(m, auto_texture())
        if center is not None and size is not None and height is not None:
            walls.append(Wall(_box_outline(center, size, yaw), height, tex, two_sided=False))

    pillars: list[Pillar] = []
    for item, mark in _items(c, root, "pillars"):
        m = c.mapping(item, mark, "a pillar")
        if m is None:
            continue
        c.keys(m, ("center", "radius", "height", "texture"), "a pillar", required=("center", "radius", "height"))
        center = c.vector(m, "center", 2, "pillar center")
        radius = c.number(m, "radius", None, lo=0.0, strict_lo=True, what="pillar ")
        height = c.number(m, "height", None, lo=0.0, strict_lo=True, what="pillar ")
        tex = texture(m, auto_texture())
        if center is not None and radius is not None and height is not None:
            pillars.append(Pillar(center[0], center[1], radius, height, tex))

    landmarks: list[Landmark] = []
    seen_ids: dict[int, Mark] = {}
    for index, (item, mark) in enumerate(_items(c, root, "landmarks")):
        m = c.mapping(item, mark, "a landmark")
        if m is None:
            continue
        c.keys(m, ("id", "position", "size"), "a landmark", required=("position",))
        lid = c.integer(m, "id", index)
        if lid in seen_ids:
            c.error(m.value_mark_of("id") if "id" in m else m.mark, f"duplicate landmark id {lid}")
        seen_ids[lid] = m.mark
        pos = c.vector(m, "position", 3, "landmark position")
        size = c.num(m, "size", 0.1, lo=0.0, strict_lo=True, what="landmark ")
        if pos is not None:
            landmarks.append(Landmark(lid, pos[0], pos[1], pos[2], size))

    start = Pose2D()
    if "start" in root:
        start = _pose(c, root["start"], root.value_mark_of("start"), "start") or start
    poses: dict[str, Pose2D] = {}
    if "poses" in root:
        pm = c.mapping(root["poses"], root.value_mark_of("poses"), "poses")
        for key, value in (pm or {}).items():
            pose = _pose(c, value, pm.value_mark_of(key), f"pose {key!r}")  # type: ignore[union-attr]
            if pose is not None:
                poses[str(key)] = pose

    robot_radius = 0.26
    if "robot" in root:
        rm = c.mapping(root["robot"], root.value_mark_of("robot"), "robot")
        if rm is not None:
            c.keys(rm, ("radius",), "robot")
            robot_radius = c.num(rm, "radius", 0.26, lo=0.0, strict_lo=True, what="robot ")

    ptu = PtuSpec()
    if "ptu" in root:
        ptu = _ptu(c, root["ptu"], root.value_mark_of("ptu")) or ptu

    cameras = default_cameras()
    if "cameras" in root:
        cameras = _cameras(c, root, ceiling)

    lighting = Lighting()
    if "lighting" in root:
        lm = c.mapping(root["lighting"], root.value_mark_of("lighting"), "lighting")
        if lm is not None:
            c.keys(lm, ("gain", "bias", "run_variation"), "lighting")
            lighting = Lighting(
                gain=c.num(lm, "gain", 1.0, lo=0.0, hi=10.0, what="lighting "),
                bias=c.num(lm, "bias", 0.0, lo=-255.0, hi=255.0, what="lighting "),
                run_variation=c.num(lm, "run_variation", 0.0, lo=0.0, hi=1.0, what="lighting "),
            )

    if ceiling is not None:
        for spec in cameras:
            z = _camera_height(spec, ptu)
            if not 0.0 < z < ceiling:
                c.error(root.value_mark_of("ceiling"), f"camera {spec.name!r} at {z:g} m is not below the ceiling")
    if c.diagnostics:
        raise InputError(c.diagnostics)
    return World(
        name=name,
        seed=seed,
        walls=tuple(walls),
        pillars=tuple(pillars),
        landmarks=tuple(landmarks),
        ceiling=ceiling,
        floor=floor,
        ground_margin=margin,
        start=start,
        poses=poses,
        robot_radius=robot_radius,
        ptu=ptu,
        cameras=cameras,
        lighting=lighting,
        source=file,
    )


def _camera_height(spec: CameraSpec, ptu: PtuSpec) -> float:
    return spec.pose.z + (ptu.z if spec.mount == "ptu" else 0.0)


def _items(c: _Checker, root: YamlMap, key: str) -> list[tuple[Any, Mark]]:
    if key not in root:
        return []
    seq = c.sequence(root[key], root.value_mark_of(key), key)
    if seq is None:
        return []
    return [(item, seq.mark_of(i)) for i, item in enumerate(seq)]


def _points(c: _Checker, m: YamlMap, key: str, minimum: int) -> list[tuple[float, float]] | None:
    seq = c.sequence(m[key], m.value_mark_of(key), key) if key in m else None
    if seq is None:
        return None
    if len(seq) < minimum:
        c.error(seq.mark, f"{key} needs at least {minimum} points, got {len(seq)}")
        return None
    out: list[tuple[float, float]] = []
    ok = True
    for i, p in enumerate(seq):
        if not isinstance(p, YamlList) or len(p) != 2:
            c.error(seq.mark_of(i), f"a point must be [x, y], got {_describe(p)}")
            ok = False
            continue
        xy = [c.check_number(v, p.mark_of(j), "a coordinate") for j, v in enumerate(p)]
        if None in xy:
            ok = False
            continue
        out.append((xy[0], xy[1]))  # type: ignore[arg-type]
    for i in range(1, len(out)):
        if out[i] == out[i - 1]:
            c.error(seq.mark_of(i), "two consecutive points are equal (zero-length wall)")
            ok = False
    return out if ok else None


def _pose(c: _Checker, value: Any, mark: Mark, what: str) -> Pose2D | None:
    m = c.mapping(value, mark, what)
    if m is None:
        return None
    c.keys(m, ("x", "y", "theta_deg"), what, required=("x", "y"))
    x, y = c.number(m, "x", None, what=f"{what} "), c.number(m, "y", None, what=f"{what} ")
    theta = c.number(m, "theta_deg", 0.0, what=f"{what} ")
    if x is None or y is None or theta is None:
        return None
    return Pose2D(x, y, math.radians(theta))


def _ptu(c: _Checker, value: Any, mark: Mark) -> PtuSpec | None:
    m = c.mapping(value, mark, "ptu")
    if m is None:
        return None
    c.keys(m, ("position", "pan_limits_deg", "tilt_limits_deg", "max_speed_deg"), "ptu")
    base = PtuSpec()
    pos = c.vector(m, "position", 3, "ptu position") or (base.x, base.y, base.z)
    limits = []
    for key, default in (("pan_limits_deg", base.pan_limits), ("tilt_limits_deg", base.tilt_limits)):
        lim = c.vector(m, key, 2, f"ptu {key}")
        if lim is not None and lim[0] >= lim[1]:
            c.error(m.value_mark_of(key), f"ptu {key}: the first limit must be below the second")
            lim = None
        limits.append((math.radians(lim[0]), math.radians(lim[1])) if lim else default)
    speed = c.number(m, "max_speed_deg", math.degrees(base.max_speed), lo=0.0, strict_lo=True, what="ptu ")
    return PtuSpec(pos[0], pos[1], pos[2], limits[0], limits[1], math.radians(speed or 300.0))


_CAMERA_KEYS = (
    "name", "kind", "mount", "pose", "model", "frame_drop", "exposure_noise", "noise_deg",
    "azimuth_fov_deg", "elevation_limits_deg", "max_range",
)  # fmt: skip


def _cameras(c: _Checker, root: YamlMap, ceiling: float | None) -> tuple[CameraSpec, ...]:
    out: list[CameraSpec] = []
    names: set[str] = set()
    for item, mark in _items(c, root, "cameras"):
        m = c.mapping(item, mark, "a camera")
        if m is None:
            continue
        c.keys(m, _CAMERA_KEYS, "a camera", required=("name", "kind"))
        name, kind = m.get("name"), m.get("kind")
        if "name" in m and (not isinstance(name, str) or not name):
            c.error(m.value_mark_of("name"), "camera name must be a non-empty string")
            name = None
        elif name in names:
            c.error(m.value_mark_of("name"), f"duplicate camera name {name!r}")
        names.add(str(name))
        if "kind" in m and kind not in CAMERA_KINDS:
            c.error(m.value_mark_of("kind"), f"unknown camera kind {kind!r} (known: {', '.join(CAMERA_KINDS)})")
            kind = None
        mount = m.get("mount", "base")
        if mount not in MOUNTS:
            c.error(m.value_mark_of("mount"), f"mount must be one of {', '.join(MOUNTS)}, got {mount!r}")
            mount = "base"
        pose = MountPose(z=0.9 if mount == "base" else 0.08)
        if "pose" in m:
            pm = c.mapping(m["pose"], m.value_mark_of("pose"), "camera pose")
            if pm is not None:
                c.keys(pm, ("x", "y", "z", "yaw_deg", "pitch_deg"), "a camera pose")
                pose = MountPose(
                    x=c.num(pm, "x", 0.0, what="camera pose "),
                    y=c.num(pm, "y", 0.0, what="camera pose "),
                    z=c.num(pm, "z", pose.z, what="camera pose "),
                    yaw=math.radians(c.num(pm, "yaw_deg", 0.0, what="camera pose ")),
                    pitch=math.radians(c.num(pm, "pitch_deg", 0.0, lo=-89.0, hi=89.0, what="camera pose ")),
                )
        model = None
        if kind not in (None, "bearings"):
            model = _camera_model(c, m, str(kind))
        elif "model" in m:
            c.error(m.mark_of("model"), "a bearings sensor has no image model")
        elev = c.vector(m, "elevation_limits_deg", 2, "elevation_limits_deg") or (-60.0, 60.0)
        if elev[0] >= elev[1]:
            c.error(m.value_mark_of("elevation_limits_deg"), "elevation_limits_deg: the first must be below the second")
        if kind != "bearings":
            for key in ("noise_deg", "azimuth_fov_deg", "elevation_limits_deg", "max_range"):
                if key in m:
                    c.error(m.mark_of(key), f"{key} only applies to a bearings sensor")
        spec = CameraSpec(
            name=str(name),
            kind=str(kind),
            mount=str(mount),
            pose=pose,
            model=model,
            frame_drop=c.num(m, "frame_drop", 0.0, lo=0.0, hi=1.0),
            exposure_noise=c.num(m, "exposure_noise", 0.0, lo=0.0, hi=1.0),
            noise=math.radians(c.num(m, "noise_deg", 0.0, lo=0.0, hi=90.0)),
            azimuth_fov=math.radians(c.num(m, "azimuth_fov_deg", 360.0, lo=0.0, strict_lo=True, hi=360.0)),
            elevation_limits=(math.radians(elev[0]), math.radians(elev[1])),
            max_range=c.num(m, "max_range", math.inf, lo=0.0, strict_lo=True),
        )
        out.append(spec)
    if not out and "cameras" in root:
        c.error(root.value_mark_of("cameras"), "cameras must list at least one camera (omit the key for the defaults)")
    return tuple(out)


def _camera_model(c: _Checker, m: YamlMap, kind: str) -> Any:
    """The perception model of an image camera; the defaults of its kind when ``model`` is absent."""
    data: dict[str, Any] = {}
    if "model" in m:
        mm = c.mapping(m["model"], m.value_mark_of("model"), "camera model")
        if mm is None:
            return None
        data = dict(mm)
    mark = m.value_mark_of("model") if "model" in m else m.mark
    try:
        if kind == "stereo":
            if "left" in data:
                return camera_from_dict({"kind": "stereo", **data})
            baseline = data.pop("baseline", 0.12)
            pin = camera_from_dict({"kind": "pinhole", **_PINHOLE_DEFAULTS, **data})
            return StereoRig(pin, pin, float(baseline))
        if kind == "pinhole":
            data = {**_PINHOLE_DEFAULTS, **data}
        model = camera_from_dict({"kind": kind, **data})
    except (ValueError, TypeError) as exc:
        c.error(mark, f"camera model: {exc}")
        return None
    if isinstance(model, PanoramaCamera) and model.width * model.deg_per_px > 360.0 + 1e-6:
        c.error(mark, "a panorama cannot cover more than 360 degrees (width * deg_per_px)")
    return model


_PINHOLE_DEFAULTS = {"width": 640, "height": 480, "fx": 525.0, "fy": 525.0, "cx": 319.5, "cy": 239.5}


def _box_outline(center: tuple[float, ...], size: tuple[float, ...], yaw: float) -> tuple[tuple[float, float], ...]:
    """The closed counter-clockwise outline of a box (so its faces' outward normals point right)."""
    cx, cy = center
    hx, hy = size[0] / 2.0, size[1] / 2.0
    c, s = math.cos(yaw), math.sin(yaw)
    corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy), (-hx, -hy)]
    return tuple((cx + c * x - s * y, cy + s * x + c * y) for x, y in corners)
