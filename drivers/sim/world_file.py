"""The world file format, declared once: every key, its unit, its range and what it means.

These models are the format of ``docs/worlds.md``: :func:`drivers.sim.world.load_world`
validates a file against :class:`WorldFile` (located errors through :mod:`maps.located`) and
converts it to the simulator's :class:`~drivers.sim.world.World` values; ``bearings schema
--world`` prints their JSON Schema for editors. Angles are degrees here (keys end in ``_deg``)
and radians in ``World``.

Every quantity is bounded so that loading and rendering a world takes memory and time in
proportion to what it declares: coordinates within 10 km (landmarks within 100 km, for
horizons), heights and radii within 100 m, at most a few thousand surfaces, a texture budget for
the whole world (:data:`MAX_TEXTURE_TEXELS`) and a rendering budget for its cameras
(:data:`MAX_RENDER_BYTES`: pixels times the renderer's memory per pixel, which ``bearings bench
sim`` measures), so no camera can take the machine's memory.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BaseModel, Field, field_validator, model_validator

from maps.located import FILE_MODEL_CONFIG
from perception.camera import PanoramaCamera, PinholeCamera, StereoRig, camera_from_dict

FORMAT_VERSION = 1
MAX_COORD = 10_000.0  # m: the extent of any world
MAX_LANDMARK_COORD = 100_000.0  # m: far landmarks on a horizon
MAX_HEIGHT = 100.0  # m
MAX_SURFACES = 5_000
MAX_LANDMARKS = 100_000
MAX_TEXTURE_SIDE = 16_000  # texels: one surface's texture must fit the atlas (cv2.remap limit)
MAX_TEXTURE_TEXELS = 200_000_000  # all surfaces together: about 200 MB of 8-bit texture
MAX_PEOPLE = 200
MAX_PATH_POINTS = 1_000
RENDER_BYTES_PER_PIXEL = 720  # peak memory per pixel of a camera rendered through lookup tables (pinhole,
# stereo, catadioptric, a tilted panorama): every pixel's bearing, the remap tables, the source panorama;
# bearings bench sim measures it (render_bytes_per_pixel: ~690 for a pinhole)
LEVEL_PANORAMA_BYTES_PER_PIXEL = 32  # a level panorama on the base is ray-cast directly (measured: ~20)
MAX_RENDER_BYTES = 4_000_000_000  # all of a world's cameras together


def _m(description: str, **bounds: Any) -> Any:
    return Field(description=description, json_schema_extra={"unit": "m"}, **bounds)


def _deg(description: str, default: Any = ..., **bounds: Any) -> Any:
    return Field(default, description=description, json_schema_extra={"unit": "deg"}, **bounds)


Coordinate = Annotated[float, Field(ge=-MAX_COORD, le=MAX_COORD, json_schema_extra={"unit": "m"})]
Point = Annotated[list[Coordinate], Field(min_length=2, max_length=2, description="[x, y] in metres")]
Height = Annotated[float, Field(gt=0.0, le=MAX_HEIGHT, json_schema_extra={"unit": "m"})]
Seed = Annotated[int, Field(ge=0, le=2**32 - 1)]


class Texture(BaseModel):
    """A surface's procedural texture (generated from the seed: no image files)."""

    model_config = FILE_MODEL_CONFIG

    seed: Seed | None = Field(None, description="default: derived from the world seed and the surface's index")
    pixels_per_m: float = Field(60.0, ge=1.0, le=1000.0, description="texture resolution",
                                json_schema_extra={"unit": "px/m"})
    feature_size: float = _m("typical size of a painted shape", default=0.2, gt=0.0, le=10.0)
    brightness: float = Field(128.0, ge=0.0, le=255.0, description="mean grey level")
    contrast: float = Field(1.0, ge=0.0, le=4.0, description="contrast of the shapes")


class Textured(BaseModel):
    """A surface with an optional texture."""

    model_config = FILE_MODEL_CONFIG

    texture: Texture | None = None

    def texels(self, length: float, height: float) -> int:
        ppm = self.texture.pixels_per_m if self.texture else Texture().pixels_per_m
        return (math.ceil(length * ppm) + 2) * (math.ceil(height * ppm) + 2)

    def check_texture(self, length: float, height: float) -> None:
        ppm = self.texture.pixels_per_m if self.texture else Texture().pixels_per_m
        side = max(length, height) * ppm
        if side > MAX_TEXTURE_SIDE:
            raise ValueError(f"its texture would be {side:.0f} texels long (at most {MAX_TEXTURE_SIDE}): lower "
                             "texture.pixels_per_m or split the surface")


class Wall(Textured):
    """A vertical surface along a polyline, visible from both sides."""

    points: list[Point] = Field(min_length=2, max_length=10_000, description="the polyline, [[x, y], ...] in m")
    height: Height = Field(description="from the floor up")
    closed: bool = Field(False, description="add the segment back to the first point")

    @model_validator(mode="after")
    def _segments(self) -> Wall:
        for i in range(1, len(self.points)):
            if self.points[i] == self.points[i - 1]:
                raise ValueError(f"points {i - 1} and {i} are equal (a zero-length wall)")
        self.check_texture(self.length, self.height)
        return self

    @property
    def length(self) -> float:
        points = [*self.points, self.points[0]] if self.closed else self.points
        return sum(math.dist(a, b) for a, b in zip(points, points[1:], strict=False))


class Box(Textured):
    """Furniture, a building: a closed outline with one-sided faces."""

    center: Point
    size: Annotated[list[float], Field(min_length=2, max_length=2)] = Field(description="[length, width] in m")
    height: Height
    yaw_deg: float = _deg("rotation about the vertical", 0.0, ge=-360.0, le=360.0)

    @field_validator("size")
    @classmethod
    def _positive(cls, size: list[float]) -> list[float]:
        if min(size) <= 0 or max(size) > 2 * MAX_COORD:
            raise ValueError(f"box size must be positive and at most {2 * MAX_COORD:g} m, got {size}")
        return size

    @model_validator(mode="after")
    def _texture(self) -> Box:
        self.check_texture(2 * sum(self.size), self.height)
        return self


class Pillar(Textured):
    """A vertical cylinder: a pillar, a post, a tree trunk."""

    center: Point
    radius: float = _m("", gt=0.0, le=MAX_HEIGHT)
    height: Height

    @model_validator(mode="after")
    def _texture(self) -> Pillar:
        self.check_texture(2 * math.pi * self.radius, self.height)
        return self


class Person(Textured):
    """A person: a vertical cylinder standing on the floor, still or walking along a path.

    A person walks the path at ``speed`` and waits ``wait_s`` at each end: with ``loop``, round the
    path and back to its first point (waiting there); without, to its last point and back. A path
    of one point is a person standing still. People walk through walls (nothing stops them but the
    robot: they stop while their next step would touch it).
    """

    path: list[Point] = Field(min_length=1, max_length=MAX_PATH_POINTS,
                              description="where the person walks, [[x, y], ...] in m (one point: standing)")
    speed: float = Field(1.0, gt=0.0, le=3.0, description="walking speed", json_schema_extra={"unit": "m/s"})
    radius: float = _m("of the cylinder", default=0.25, gt=0.0, le=1.0)
    height: float = _m("of the cylinder", default=1.75, gt=0.0, le=3.0)
    wait_s: float = Field(0.0, ge=0.0, le=3600.0, description="how long the person waits at each end of the path",
                          json_schema_extra={"unit": "s"})
    loop: bool = Field(False, description="walk round the path back to its first point (false: back and forth)")

    @model_validator(mode="after")
    def _steps(self) -> Person:
        points = self.points_closed
        for i in range(1, len(points)):
            if points[i] == points[i - 1]:
                back = " (a loop walks back to its first point by itself)" if i == len(self.path) else ""
                raise ValueError(f"path points {i - 1} and {i % len(self.path)} are equal: a step of no length{back}")
        self.check_texture(2 * math.pi * self.radius, self.height)
        return self

    @property
    def points_closed(self) -> list[list[float]]:
        """The path, with the way back to its first point when it loops."""
        return [*self.path, self.path[0]] if self.loop and len(self.path) > 1 else self.path


class Landmark(BaseModel):
    """A point landmark (for the bearings sensor; drawn as a small disc in images)."""

    model_config = FILE_MODEL_CONFIG

    id: int | None = Field(None, ge=0, le=2**31 - 1, description="default: its index in the list")
    position: Annotated[list[float], Field(min_length=3, max_length=3)] = Field(
        description="[x, y, z] in m (within 100 km)")
    size: float = _m("diameter of the drawn disc", default=0.1, gt=0.0, le=MAX_HEIGHT)

    @field_validator("position")
    @classmethod
    def _within(cls, position: list[float]) -> list[float]:
        if max(abs(v) for v in position) > MAX_LANDMARK_COORD:
            raise ValueError(f"landmark position must be within {MAX_LANDMARK_COORD:g} m, got {position}")
        return position


class Pose(BaseModel):
    """A pose on the floor."""

    model_config = FILE_MODEL_CONFIG

    x: Coordinate
    y: Coordinate
    theta_deg: float = _deg("heading, counter-clockwise from +x", 0.0, ge=-360.0, le=360.0)


class Robot(BaseModel):
    """The simulated base."""

    model_config = FILE_MODEL_CONFIG

    radius: float = _m("collision disc (Pioneer 3-DX: 0.26)", default=0.26, gt=0.0, le=5.0)
    sonar: Literal["p3dx", "p3at", "none"] = Field(
        "p3dx", description="the sonar ring: a Pioneer 3-DX's or 3-AT's 16 transducers (docs/worlds.md), or none")
    sonar_noise_m: float = _m("sigma of the Gaussian noise on each sonar range", default=0.02, ge=0.0, le=1.0)
    sonar_miss_probability: float = Field(0.01, ge=0.0, le=1.0,
                                          description="probability that a transducer hears no echo when it fires")
    sonar_max_range: float = _m("farther echoes are not reported", default=5.0, gt=0.1, le=20.0)
    bumpers: bool = Field(True, description="front and rear bumper segments (5 each, as on a Pioneer 3)")


Limits = Annotated[list[float], Field(min_length=2, max_length=2, description="[lowest, highest] in degrees")]


class PanTiltUnit(BaseModel):
    """The pan-tilt unit (defaults: a PTU-D46-17)."""

    model_config = FILE_MODEL_CONFIG

    position: Annotated[list[float], Field(min_length=3, max_length=3)] = Field(
        [0.1, 0.0, 1.0], description="where the pan and tilt axes meet, on the base [x, y, z] in m")
    pan_limits_deg: Limits = _deg("", [-159.0, 159.0])
    tilt_limits_deg: Limits = _deg("positive looks up", [-47.0, 31.0])
    max_speed_deg: float = _deg("top slew rate, deg/s", 300.0, gt=0.0, le=3600.0)

    @field_validator("pan_limits_deg", "tilt_limits_deg")
    @classmethod
    def _ordered(cls, limits: list[float]) -> list[float]:
        if not -360.0 <= limits[0] < limits[1] <= 360.0:
            raise ValueError(f"the first limit must be below the second (within +-360 deg), got {limits}")
        return limits

    @field_validator("position")
    @classmethod
    def _near(cls, position: list[float]) -> list[float]:
        if max(abs(v) for v in position) > 10.0:
            raise ValueError(f"the pan-tilt unit must sit on the robot (within 10 m), got {position}")
        return position


class MountPose(BaseModel):
    """Where a camera sits on its mount (the base, or the pan-tilt head)."""

    model_config = FILE_MODEL_CONFIG

    x: float = _m("", default=0.0, ge=-10.0, le=10.0)
    y: float = _m("", default=0.0, ge=-10.0, le=10.0)
    z: float | None = _m("default: 0.9 on the base, 0.08 on the pan-tilt head", default=None, ge=-10.0, le=10.0)
    yaw_deg: float = _deg("", 0.0, ge=-360.0, le=360.0)
    pitch_deg: float = _deg("positive looks up", 0.0, ge=-89.0, le=89.0)


class Camera(BaseModel):
    """One simulated camera: an ideal bearings sensor or an image camera of a perception model."""

    model_config = FILE_MODEL_CONFIG

    name: str = Field(min_length=1, max_length=100)
    kind: Literal["bearings", "panorama", "catadioptric", "pinhole", "stereo"]
    mount: Literal["base", "ptu"] = "base"
    pose: MountPose | None = None
    model: dict[str, Any] | None = Field(None, description="the perception camera model's parameters (docs/worlds.md)")
    frame_drop: float = Field(0.0, ge=0.0, le=1.0, description="probability that grab() returns None")
    exposure_noise: float = Field(0.0, ge=0.0, le=1.0, description="sigma of a per-frame relative gain")
    noise_deg: float | None = _deg("bearings sensor: angular noise per axis", None, ge=0.0, le=90.0)
    azimuth_fov_deg: float | None = _deg("bearings sensor: field of view", None, gt=0.0, le=360.0)
    elevation_limits_deg: Limits | None = _deg("bearings sensor", None)
    max_range: float | None = _m("bearings sensor: farthest landmark seen", default=None, gt=0.0,
                                 le=MAX_LANDMARK_COORD * 3)

    @model_validator(mode="after")
    def _kind_fits(self) -> Camera:
        sensor_keys = [k for k in ("noise_deg", "azimuth_fov_deg", "elevation_limits_deg", "max_range")
                       if getattr(self, k) is not None]
        if self.kind != "bearings" and sensor_keys:
            raise ValueError(f"{', '.join(sensor_keys)} only applies to a bearings sensor")
        if self.kind == "bearings" and self.model is not None:
            raise ValueError("a bearings sensor has no image model")
        limits = self.elevation_limits_deg
        if limits is not None and not -90.0 <= limits[0] < limits[1] <= 90.0:
            raise ValueError("elevation_limits_deg: the first must be below the second (within +-90)")
        self.image_model()  # the perception model's own checks, reported with the file's other problems
        return self

    def render_bytes(self) -> int:
        """The renderer's peak memory for this camera (0 for the bearings sensor): its pixels (both
        images of a stereo pair) times the measured bytes per pixel of its way of rendering."""
        model = self.image_model()
        if model is None:
            return 0
        eyes = [model.left, model.right] if isinstance(model, StereoRig) else [model]
        pixels = sum(eye.width * eye.height for eye in eyes)
        level = self.kind == "panorama" and self.mount == "base" and (self.pose is None or self.pose.pitch_deg == 0)
        return pixels * (LEVEL_PANORAMA_BYTES_PER_PIXEL if level else RENDER_BYTES_PER_PIXEL)

    def image_model(self) -> Any:
        """The perception camera model of an image camera (None for the bearings sensor)."""
        if self.kind == "bearings":
            return None
        try:
            return camera_model(self.kind, self.model or {})
        except TypeError as exc:
            raise ValueError(f"model: {exc}") from None


def camera_model(kind: str, data: dict[str, Any]) -> Any:
    """The perception model of an image camera; the defaults of its kind for what ``model`` leaves out."""
    data = dict(data)
    if kind == "stereo":
        if "left" in data:
            return camera_from_dict({"kind": "stereo", **data})
        baseline = data.pop("baseline", 0.12)
        if isinstance(baseline, bool) or not isinstance(baseline, (int, float)) or not 0.0 < baseline <= 10.0:
            raise ValueError(f"baseline must be a number of metres in (0, 10], got {baseline!r}")
        pin = camera_from_dict({"kind": "pinhole", **_PINHOLE_DEFAULTS, **data})
        if not isinstance(pin, PinholeCamera):
            raise ValueError("a stereo pair is made of pinhole cameras")
        return StereoRig(pin, pin, float(baseline))
    if kind == "pinhole":
        data = {**_PINHOLE_DEFAULTS, **data}
    model = camera_from_dict({"kind": kind, **data})
    if isinstance(model, PanoramaCamera) and model.width * model.deg_per_px > 360.0 + 1e-6:
        raise ValueError("a panorama cannot cover more than 360 degrees (width * deg_per_px)")
    if max(getattr(model, "width", 0), getattr(model, "height", 0)) > 8192:
        raise ValueError("an image of more than 8192 pixels a side is not simulated")
    return model


_PINHOLE_DEFAULTS = {"width": 640, "height": 480, "fx": 525.0, "fy": 525.0, "cx": 319.5, "cy": 239.5}


class Lighting(BaseModel):
    """Global brightness: image = gain * rendered + bias."""

    model_config = FILE_MODEL_CONFIG

    gain: float = Field(1.0, ge=0.0, le=10.0)
    bias: float = Field(0.0, ge=-255.0, le=255.0)
    run_variation: float = Field(0.0, ge=0.0, le=1.0, description="each seed draws gain * (1 + run_variation * N(0,1))")


class Floor(BaseModel):
    """The floor's texture."""

    model_config = FILE_MODEL_CONFIG

    texture: Texture | None = None


class WorldFile(BaseModel):
    """A simulated world (docs/worlds.md)."""

    model_config = FILE_MODEL_CONFIG

    format: Literal[1] = Field(1, description="format version")
    name: str | None = Field(None, min_length=1, max_length=200, description="default: the file name")
    description: str = Field("", max_length=20_000)
    seed: Seed = Field(0, description="base seed of the generated textures")
    ceiling: Height | None = Field(None, description="height of a flat ceiling; omit for an open sky")
    ground_margin: float = _m("the floor texture covers the world's bounds plus this margin", default=10.0,
                              ge=1.0, le=1000.0)
    floor: Floor | None = None
    walls: list[Wall] = Field(default_factory=list, max_length=MAX_SURFACES)
    boxes: list[Box] = Field(default_factory=list, max_length=MAX_SURFACES)
    pillars: list[Pillar] = Field(default_factory=list, max_length=MAX_SURFACES)
    landmarks: list[Landmark] = Field(default_factory=list, max_length=MAX_LANDMARKS)
    people: list[Person] = Field(default_factory=list, max_length=MAX_PEOPLE,
                                 description="people standing or walking (drawn in every camera, they block the robot)")
    start: Pose = Field(default_factory=lambda: Pose(x=0.0, y=0.0), description="the robot's true start pose")
    poses: dict[str, Pose] = Field(default_factory=dict, max_length=10_000, description="named poses")
    robot: Robot = Field(default_factory=Robot)
    ptu: PanTiltUnit = Field(default_factory=PanTiltUnit)
    cameras: list[Camera] | None = Field(None, min_length=1, max_length=32, description="default: one of each kind")
    lighting: Lighting = Field(default_factory=Lighting)

    @field_validator("cameras")
    @classmethod
    def _render_budget(cls, cameras: list[Camera] | None) -> list[Camera] | None:
        total = sum(camera.render_bytes() for camera in cameras or ())
        if total > MAX_RENDER_BYTES:
            raise ValueError(f"rendering them would take about {total / 1e9:.1f} GB (at most "
                             f"{MAX_RENDER_BYTES / 1e9:.0f} GB: {RENDER_BYTES_PER_PIXEL} bytes per pixel, "
                             f"{LEVEL_PANORAMA_BYTES_PER_PIXEL} for a level panorama, as bearings bench sim "
                             "measures): fewer or smaller cameras")
        return cameras

    @model_validator(mode="after")
    def _texture_budget(self) -> WorldFile:
        texels = sum(w.texels(w.length, w.height) for w in self.walls)
        texels += sum(b.texels(2 * sum(b.size), b.height) for b in self.boxes)
        texels += sum(p.texels(2 * math.pi * p.radius, p.height) for p in self.pillars)
        texels += sum(p.texels(2 * math.pi * p.radius, p.height) for p in self.people)
        if texels > MAX_TEXTURE_TEXELS:
            raise ValueError(f"the world's textures would take {texels / 1e6:.0f} MB (at most "
                             f"{MAX_TEXTURE_TEXELS / 1e6:.0f} MB): lower pixels_per_m or the surfaces' size")
        return self
