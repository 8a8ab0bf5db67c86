"""Loading a simulated world: shipped worlds by name, world files checked into :class:`World` values.

The file format is declared in :mod:`drivers.sim.world_file` and documented in ``docs/worlds.md``;
the values it becomes are :mod:`drivers.sim.world_values` (re-exported here: ``World`` and
``load_world`` come from one place). Files are read through :mod:`maps.store` only, and every
problem of a file is reported at once as an :class:`~maps.store.InputError` with
``file:line:col`` diagnostics, like missions. What needs the whole world is checked after the
entries (duplicate ids and names, cameras under the ceiling, a start pose in free space: the last
one with the simulator's geometry, :func:`drivers.sim.scene.free_space_problem`).

Units: metres in the file and in the values; angles are degrees in the file (keys end in
``_deg``) and radians in the values.
"""

from __future__ import annotations

import math
from dataclasses import replace
from importlib import resources
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from drivers.sim import world_file as wf
from drivers.sim.scene import free_space_problem
from drivers.sim.world_values import (
    CameraSpec,
    Landmark,
    Lighting,
    MountPose,
    Person,
    Pillar,
    PtuSpec,
    RangeSpec,
    TextureSpec,
    Wall,
    World,
    default_cameras,
    empty_world,
)
from maps.located import describe_value, diagnose
from maps.store import Diagnostic, InputError, Mark, YamlList, YamlMap, load_yaml, mark_of
from perception.geometry import Pose2D

FORMAT_VERSION = wf.FORMAT_VERSION
CAMERA_KINDS = ("bearings", "panorama", "catadioptric", "pinhole", "stereo")
MOUNTS = ("base", "ptu")
PERSON_TEXTURE = {"feature_size": 0.1, "brightness": 90.0}  # people's default: darker, finer than walls


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
        ranges=RangeSpec(model.robot.sonar, model.robot.sonar_noise_m, model.robot.sonar_miss_probability,
                         model.robot.sonar_max_range, model.robot.bumpers),
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
    """Walls (boxes become one-sided closed walls), pillars and people, with textures seeded per surface."""
    counter = iter(range(1, 1_000_000))

    def texture(surface: wf.Textured, **default: Any) -> TextureSpec:
        return _texture(surface.texture, TextureSpec(seed=model.seed * 1000 + next(counter), **default))

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
    people = [Person(tuple((q[0], q[1]) for q in p.path), p.radius, p.height, texture(p, **PERSON_TEXTURE), p.speed,
                     p.wait_s, p.loop) for p in model.people]
    return {"walls": tuple(walls), "pillars": tuple(pillars), "landmarks": tuple(landmarks), "people": tuple(people)}


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


def _start_problems(world: World, data: YamlMap, file: str) -> list[Diagnostic]:
    problem = free_space_problem(world, world.start, people=False)
    if problem is None:
        return _people_on_start(world, data, file)
    mark = data.value_mark_of("start") if "start" in data else data.mark
    return [Diagnostic(file, mark.line, mark.col, f"the robot's start {problem}")]


def _people_on_start(world: World, data: YamlMap, file: str) -> list[Diagnostic]:
    """A person who starts (or stands) on the robot's start pose, as a start inside an obstacle is."""
    problems = []
    entries = data.get("people")
    start = world.start
    for index, person in enumerate(world.people):
        x, y = person.path[0]
        gap = math.hypot(x - start.x, y - start.y)
        if gap < person.radius + world.robot_radius:
            mark = entries[index].mark if isinstance(entries, YamlList) else data.mark
            problems.append(Diagnostic(file, mark.line, mark.col, (
                f"person {index} starts on the robot's start: ({x:g}, {y:g}) is {gap:.2f} m from ({start.x:g}, "
                f"{start.y:g}), less than its radius plus the robot's ({person.radius + world.robot_radius:g} m)")))
    return problems


def _camera_height(spec: CameraSpec, ptu: PtuSpec) -> float:
    return spec.pose.z + (ptu.z if spec.mount == "ptu" else 0.0)


def _box_outline(center: tuple[float, ...], size: tuple[float, ...], yaw: float) -> tuple[tuple[float, float], ...]:
    """The closed counter-clockwise outline of a box (so its faces' outward normals point right)."""
    cx, cy = center
    hx, hy = size[0] / 2.0, size[1] / 2.0
    c, s = math.cos(yaw), math.sin(yaw)
    corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy), (-hx, -hy)]
    return tuple((cx + c * x - s * y, cy + s * x + c * y) for x, y in corners)
