"""Simulated worlds: the values a world file describes, and the validating loader.

A world is a flat floor with vertical surfaces on it (wall polylines, boxes, round pillars), point
landmarks anywhere in 3D, a ceiling or an open sky, the robot's start and named poses, its pan-tilt
unit and cameras, and the lighting. The file format is declared in :mod:`drivers.sim.world_file`
and documented in ``docs/worlds.md``. Files are read through :mod:`maps.store` only, and every
problem of a file is reported at once as an :class:`~maps.store.InputError` with
``file:line:col`` diagnostics, like missions.

Units: metres in the file and in here; angles are degrees in the file (keys end in ``_deg``) and
radians in these values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from drivers.sim import world_file as wf
from maps.located import describe_value, diagnose
from maps.store import Diagnostic, InputError, Mark, YamlList, YamlMap, load_yaml, mark_of
from perception.camera import PanoramaCamera, PinholeCamera, StereoRig, camera_from_dict
from perception.geometry import Pose2D

FORMAT_VERSION = wf.FORMAT_VERSION
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
# From the declared file format (drivers/sim/world_file.py) to World values


def parse_world(data: Any, *, file: str, default_name: str = "world") -> World:
    """Validate located YAML data (from :func:`maps.store.load_yaml`) into a :class:`World`.

    Raises :class:`~maps.store.InputError` listing every problem found, each with file:line:col:
    first what the declared format says (:class:`~drivers.sim.world_file.WorldFile`), then what
    needs the whole world (duplicate ids and names, cameras under the ceiling, a start pose in
    free space).
    """
    if not isinstance(data, YamlMap):
        raise InputError([Diagnostic(file, *_at(mark_of(data, Mark(1, 1))), "a world file must be a mapping, got "
                                     f"{describe_value(data)}")])
    duplicates = _duplicates(data, file)
    try:
        model = wf.WorldFile.model_validate(data)
    except ValidationError as exc:
        raise InputError(diagnose(exc, data, file=file, model=wf.WorldFile) + duplicates) from None
    world = World(
        name=model.name or default_name,
        seed=model.seed,
        ceiling=model.ceiling,
        floor=_texture(model.floor.texture if model.floor else None, _floor_default(model.seed)),
        ground_margin=model.ground_margin,
        start=_pose(model.start),
        poses={name: _pose(pose) for name, pose in model.poses.items()},
        robot_radius=model.robot.radius,
        ptu=_ptu(model.ptu),
        cameras=tuple(_camera(c) for c in model.cameras) if model.cameras is not None else default_cameras(),
        lighting=Lighting(model.lighting.gain, model.lighting.bias, model.lighting.run_variation),
        source=file,
        **_surfaces(model),
    )
    problems = duplicates + _whole_world_problems(world, data, file)
    if problems:
        raise InputError(problems)
    return world


def _at(mark: Mark) -> tuple[int, int]:
    return mark.line, mark.col


def _floor_default(seed: int) -> TextureSpec:
    return TextureSpec(seed=seed * 1000, pixels_per_m=25.0, feature_size=0.25, contrast=0.6)


def _texture(spec: wf.Texture | None, default: TextureSpec) -> TextureSpec:
    """The texture a surface declares, with what it leaves out taken from ``default``."""
    if spec is None:
        return default
    given = {name: getattr(spec, name) for name in spec.model_fields_set if getattr(spec, name) is not None}
    return replace(default, **given)


def _surfaces(model: wf.WorldFile) -> dict[str, Any]:
    """Walls (boxes become one-sided closed walls) and pillars, with textures seeded per surface."""
    counter = iter(range(1, 1_000_000))

    def texture(surface: wf.Textured) -> TextureSpec:
        return _texture(surface.texture, TextureSpec(seed=model.seed * 1000 + next(counter)))

    walls = []
    for wall in model.walls:
        points = [tuple(p) for p in wall.points]
        if wall.closed:
            points.append(points[0])
        walls.append(Wall(tuple(points), wall.height, texture(wall), two_sided=True))  # type: ignore[arg-type]
    for box in model.boxes:
        outline = _box_outline(tuple(box.center), tuple(box.size), math.radians(box.yaw_deg))
        walls.append(Wall(outline, box.height, texture(box), two_sided=False))
    pillars = [Pillar(p.center[0], p.center[1], p.radius, p.height, texture(p)) for p in model.pillars]
    landmarks = [Landmark(lm.id if lm.id is not None else i, lm.position[0], lm.position[1], lm.position[2], lm.size)
                 for i, lm in enumerate(model.landmarks)]
    return {"walls": tuple(walls), "pillars": tuple(pillars), "landmarks": tuple(landmarks)}


def _pose(pose: wf.Pose) -> Pose2D:
    return Pose2D(pose.x, pose.y, math.radians(pose.theta_deg))


def _ptu(ptu: wf.PanTiltUnit) -> PtuSpec:
    x, y, z = ptu.position
    pan, tilt = (tuple(math.radians(v) for v in lim) for lim in (ptu.pan_limits_deg, ptu.tilt_limits_deg))
    return PtuSpec(x, y, z, pan, tilt, math.radians(ptu.max_speed_deg))  # type: ignore[arg-type]


def _camera(camera: wf.Camera) -> CameraSpec:
    pose = camera.pose or wf.MountPose()
    z = pose.z if pose.z is not None else (0.9 if camera.mount == "base" else 0.08)
    elevation = camera.elevation_limits_deg or [-60.0, 60.0]
    return CameraSpec(
        name=camera.name, kind=camera.kind, mount=camera.mount,
        pose=MountPose(pose.x, pose.y, z, math.radians(pose.yaw_deg), math.radians(pose.pitch_deg)),
        model=camera.image_model(), frame_drop=camera.frame_drop, exposure_noise=camera.exposure_noise,
        noise=math.radians(camera.noise_deg or 0.0), azimuth_fov=math.radians(camera.azimuth_fov_deg or 360.0),
        elevation_limits=(math.radians(elevation[0]), math.radians(elevation[1])),
        max_range=camera.max_range if camera.max_range is not None else math.inf,
    )  # fmt: skip


def _duplicates(data: YamlMap, file: str) -> list[Diagnostic]:
    """Landmark ids and camera names used twice (checked on the raw entries, with the rest)."""
    problems = []
    for key, field_name, default_index in (("landmarks", "id", True), ("cameras", "name", False)):
        entries = data.get(key)
        seen: set[Any] = set()
        for index, entry in enumerate(entries if isinstance(entries, YamlList) else ()):
            if not isinstance(entry, YamlMap):
                continue
            value = entry.get(field_name, index if default_index else None)
            if isinstance(value, (int, str)) and not isinstance(value, bool):
                if value in seen:
                    mark = entry.value_mark_of(field_name) if field_name in entry else entry.mark
                    what = "landmark id" if key == "landmarks" else "camera name"
                    problems.append(Diagnostic(file, mark.line, mark.col, f"duplicate {what} {value!r}"))
                seen.add(value)
    return problems


def _whole_world_problems(world: World, data: YamlMap, file: str) -> list[Diagnostic]:
    """What no single entry can tell: cameras under the ceiling, a start pose in free space."""
    problems = []
    if world.ceiling is not None:
        for spec in world.cameras:
            z = _camera_height(spec, world.ptu)
            if not 0.0 < z < world.ceiling:
                mark = data.value_mark_of("ceiling")
                problems.append(Diagnostic(file, mark.line, mark.col,
                                           f"camera {spec.name!r} at {z:g} m is not below the ceiling"))
    return problems or _start_problems(world, data, file)


def free_space_problem(world: World, pose: Pose2D) -> str | None:
    """Why the robot cannot stand at ``pose`` (too close to a wall, box or pillar), or None."""
    from drivers.sim.scene import Scene  # the scene is built from a World: imported here, not at the top

    clearance = Scene(world).clearance(pose.x, pose.y)
    if clearance >= world.robot_radius:
        return None
    return (f"({pose.x:g}, {pose.y:g}) is not in free space: {max(clearance, 0.0):.2f} m from a wall, box or "
            f"pillar, less than the robot radius {world.robot_radius:g} m")


def _start_problems(world: World, data: YamlMap, file: str) -> list[Diagnostic]:
    problem = free_space_problem(world, world.start)
    if problem is None:
        return []
    mark = data.value_mark_of("start") if "start" in data else data.mark
    return [Diagnostic(file, mark.line, mark.col, f"the robot's start {problem}")]


def _camera_height(spec: CameraSpec, ptu: PtuSpec) -> float:
    return spec.pose.z + (ptu.z if spec.mount == "ptu" else 0.0)




def _box_outline(center: tuple[float, ...], size: tuple[float, ...], yaw: float) -> tuple[tuple[float, float], ...]:
    """The closed counter-clockwise outline of a box (so its faces' outward normals point right)."""
    cx, cy = center
    hx, hy = size[0] / 2.0, size[1] / 2.0
    c, s = math.cos(yaw), math.sin(yaw)
    corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy), (-hx, -hy)]
    return tuple((cx + c * x - s * y, cy + s * x + c * y) for x, y in corners)
