"""What a simulated world is: the values a world file describes, in SI units and radians.

A world is a flat floor with vertical surfaces on it (wall polylines, boxes, round pillars), point
landmarks anywhere in 3D, people standing or walking, a ceiling or an open sky, the robot's start
and named poses, its range sensors, pan-tilt unit and cameras, and the lighting. These values are
what the simulator's geometry (:mod:`drivers.sim.scene`), textures and cameras are built from;
reading and checking a world file into them is :mod:`drivers.sim.world`'s job. They import nothing
of the simulator, so every module of it can use them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from perception.camera import PanoramaCamera, PinholeCamera, StereoRig, camera_from_dict
from perception.geometry import Pose2D


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
class Person:
    """A person: a vertical cylinder that stands still or walks along ``path``.

    With ``loop`` the person walks round the path back to its first point and waits ``wait``
    there; without, to the last point, waits, walks back and waits at the first. Where a person
    is at any moment is :func:`drivers.sim.people.position_at`.
    """

    path: tuple[tuple[float, float], ...]
    radius: float
    height: float
    texture: TextureSpec
    speed: float = 1.0  # m/s
    wait: float = 0.0  # s at each end
    loop: bool = False


@dataclass(frozen=True, slots=True)
class RangeSpec:
    """The robot's range sensors: which sonar ring (``p3dx``, ``p3at``, ``none``), its noise and
    missed echoes, its reach, and whether it has bumpers (:mod:`drivers.sim.ranges`)."""

    sonar: str = "p3dx"
    noise: float = 0.02  # m, sigma of each range
    miss_probability: float = 0.01  # a firing hears no echo
    max_range: float = 5.0  # m
    bumpers: bool = True


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
    people: tuple[Person, ...] = ()
    ceiling: float | None = None  # m; None: open sky
    floor: TextureSpec = TextureSpec(seed=0, pixels_per_m=25.0, feature_size=0.25, contrast=0.6)
    ground_margin: float = 10.0
    start: Pose2D = Pose2D()
    poses: dict[str, Pose2D] = field(default_factory=dict)
    robot_radius: float = 0.26
    ranges: RangeSpec = RangeSpec()
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
        """(xmin, ymin, xmax, ymax) of walls, pillars, people's paths, start and poses (landmarks excluded)."""
        xs = [self.start.x, *(p.x for p in self.poses.values())]
        ys = [self.start.y, *(p.y for p in self.poses.values())]
        for wall in self.walls:
            xs += [p[0] for p in wall.points]
            ys += [p[1] for p in wall.points]
        for p in self.pillars:
            xs += [p.x - p.radius, p.x + p.radius]
            ys += [p.y - p.radius, p.y + p.radius]
        for person in self.people:
            xs += [q[0] + s * person.radius for q in person.path for s in (-1, 1)]
            ys += [q[1] + s * person.radius for q in person.path for s in (-1, 1)]
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
