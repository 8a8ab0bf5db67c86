"""Camera models: pixels to unit bearings in the camera BODY frame, and back.

Every model returns unit 3-vectors with the REP-103 body axes of :mod:`perception.geometry`:
x forward (optical axis / panorama centre column), y left, z up. Pinhole models convert from
OpenCV's optical frame (x right, y down, z forward) internally, so nothing above this module
ever sees the optical convention.

Pixel convention (all models, as in OpenCV): integer pixel coordinates ``(u, v)`` are pixel
CENTRES; ``u`` grows to the right, ``v`` grows down; the image covers ``[-0.5, width - 0.5)`` x
``[-0.5, height - 0.5)``.

Models are frozen dataclasses with ``width``, ``height``, ``kind``, ``pixel_to_bearing``,
``bearing_to_pixel`` and ``to_dict``; :func:`camera_from_dict` is the inverse of ``to_dict`` (plain
data for the camera YAML; reading and writing the file is the caller's job via ``maps.store``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import cv2
import numpy as np

# Body <- optical axes: body x = optical z, body y = -optical x, body z = -optical y.
_BODY_FROM_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
_EPS = 1e-12


@runtime_checkable
class CameraModel(Protocol):
    """What every camera model offers (structural type for annotations)."""

    width: int
    height: int

    @property
    def kind(self) -> str: ...

    def pixel_to_bearing(self, uv: np.ndarray) -> np.ndarray: ...

    def bearing_to_pixel(self, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...

    def to_dict(self) -> dict[str, Any]: ...


def _as_uv(uv: np.ndarray) -> np.ndarray:
    arr = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    return arr


def _as_bearings(b: np.ndarray) -> np.ndarray:
    arr = np.asarray(b, dtype=np.float64).reshape(-1, 3)
    norms = np.linalg.norm(arr, axis=1, keepdims=True)
    return arr / np.maximum(norms, _EPS)


def _normalise(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), _EPS)


def _inside(uv: np.ndarray, width: int, height: int) -> np.ndarray:
    u, v = uv[:, 0], uv[:, 1]
    return (u >= -0.5) & (u < width - 0.5) & (v >= -0.5) & (v < height - 0.5)


def _check_size(width: int, height: int) -> None:
    if int(width) <= 0 or int(height) <= 0:
        raise ValueError(f"image size must be positive, got {width}x{height}")


@dataclass(frozen=True, slots=True)
class PinholeCamera:
    """A pinhole camera with OpenCV's distortion model (``dist`` = k1, k2, p1, p2[, k3, ...]).

    Distortion is applied and removed by OpenCV (``cv2.projectPoints`` / ``cv2.undistortPoints``),
    so any coefficient vector OpenCV accepts (0, 4, 5, 8, 12 or 14 values) works here.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    dist: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        _check_size(self.width, self.height)
        if not (self.fx > 0 and self.fy > 0):
            raise ValueError(f"focal lengths must be positive, got fx={self.fx}, fy={self.fy}")
        if len(self.dist) not in (0, 4, 5, 8, 12, 14):
            raise ValueError(f"dist must have 0, 4, 5, 8, 12 or 14 coefficients, got {len(self.dist)}")
        object.__setattr__(self, "dist", tuple(float(d) for d in self.dist))

    @property
    def kind(self) -> str:
        return "pinhole"

    @property
    def K(self) -> np.ndarray:
        """The 3 x 3 camera matrix."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def dist_array(self) -> np.ndarray:
        return np.asarray(self.dist, dtype=np.float64) if self.dist else np.zeros(0)

    def normalised(self, uv: np.ndarray) -> np.ndarray:
        """Undistorted normalised image coordinates (N x 2, OpenCV optical convention)."""
        pts = _as_uv(uv)
        if len(pts) == 0:
            return np.zeros((0, 2))
        if not self.dist:
            return np.column_stack(((pts[:, 0] - self.cx) / self.fx, (pts[:, 1] - self.cy) / self.fy))
        criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-12)
        out = cv2.undistortPoints(pts.reshape(-1, 1, 2), self.K, self.dist_array, criteria=criteria)
        return out.reshape(-1, 2)

    def pixel_to_bearing(self, uv: np.ndarray) -> np.ndarray:
        """Unit bearings (N x 3, body frame) of pixel positions (N x 2)."""
        xy = self.normalised(uv)
        optical = np.column_stack((xy, np.ones(len(xy))))
        return _normalise(optical @ _BODY_FROM_OPTICAL.T)

    def bearing_to_pixel(self, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixels (N x 2) of body-frame bearings and whether each is in front and inside the image."""
        bearings = _as_bearings(b)
        optical = bearings @ _BODY_FROM_OPTICAL  # row-vector form of R^T b
        uv = np.full((len(bearings), 2), np.nan)
        front = optical[:, 2] > 1e-9
        if front.any():
            pts = optical[front] / optical[front, 2:3]
            projected, _ = cv2.projectPoints(
                pts.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), self.K, self.dist_array
            )
            uv[front] = projected.reshape(-1, 2)
        valid = front & _inside(np.nan_to_num(uv, nan=-1e9), self.width, self.height)
        if self.dist and valid.any():
            # a distortion polynomial folds rays far outside the view back into the image: only
            # rays within the undistorted image corners' radius (plus 5 %) can really be seen
            radius = np.hypot(optical[:, 0], optical[:, 1]) / np.maximum(optical[:, 2], 1e-12)
            valid &= radius <= 1.05 * self.max_normalised_radius()
        return uv, valid

    def max_normalised_radius(self) -> float:
        """Largest undistorted normalised radius of the image (reached at a corner or edge centre)."""
        w, h = self.width - 0.5, self.height - 0.5
        border = np.array([[-0.5, -0.5], [w, -0.5], [-0.5, h], [w, h], [self.cx, -0.5], [self.cx, h],
                           [-0.5, self.cy], [w, self.cy]])
        return float(np.hypot(*self.normalised(border).T).max())

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "width": int(self.width),
            "height": int(self.height),
            "fx": float(self.fx),
            "fy": float(self.fy),
            "cx": float(self.cx),
            "cy": float(self.cy),
            "dist": [float(d) for d in self.dist],
        }


@dataclass(frozen=True, slots=True)
class PanoramaCamera:
    """An equirectangular panorama (cylindrical strip) around the robot.

    Column ``u`` (pixel centre) has azimuth ``(width / 2 - u) * deg_per_px``: azimuth 0 (straight
    ahead, body x) is at ``u = width / 2``, azimuth grows to the LEFT (counter-clockwise seen from
    above), and the image wraps around at the seam (``u = -0.5`` and ``u = width - 0.5`` are both
    azimuth +-180 deg when the panorama covers 360 deg). Row ``v`` has elevation
    ``(horizon_row - v) * deg_per_px`` (positive up). Default: 720 x 172 at 0.5 deg/px with the
    horizon at row 60, so the view spans +30 deg (row -0.5 edge ~ +30.25) down to about -56 deg,
    enough to see the floor near the robot.
    """

    width: int = 720
    height: int = 172
    deg_per_px: float = 0.5
    horizon_row: float = 60.0

    def __post_init__(self) -> None:
        _check_size(self.width, self.height)
        if not self.deg_per_px > 0:
            raise ValueError(f"deg_per_px must be positive, got {self.deg_per_px}")

    @property
    def kind(self) -> str:
        return "panorama"

    @property
    def rad_per_px(self) -> float:
        return math.radians(self.deg_per_px)

    @property
    def wraps(self) -> bool:
        """True when the columns cover the full circle (features must wrap at the seam)."""
        return abs(self.width * self.deg_per_px - 360.0) < 1e-6

    def azimuth(self, u: np.ndarray) -> np.ndarray:
        """Azimuth (rad, left-positive) of columns ``u``."""
        return (self.width / 2.0 - np.asarray(u, dtype=np.float64)) * self.rad_per_px

    def elevation(self, v: np.ndarray) -> np.ndarray:
        """Elevation (rad, up-positive) of rows ``v``."""
        return (self.horizon_row - np.asarray(v, dtype=np.float64)) * self.rad_per_px

    def pixel_to_bearing(self, uv: np.ndarray) -> np.ndarray:
        pts = _as_uv(uv)
        az, el = self.azimuth(pts[:, 0]), self.elevation(pts[:, 1])
        ce = np.cos(el)
        return np.column_stack((ce * np.cos(az), ce * np.sin(az), np.sin(el)))

    def bearing_to_pixel(self, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        bearings = _as_bearings(b)
        az = np.arctan2(bearings[:, 1], bearings[:, 0])
        el = np.arctan2(bearings[:, 2], np.hypot(bearings[:, 0], bearings[:, 1]))
        u = self.width / 2.0 - az / self.rad_per_px
        if self.wraps:  # fold onto [-0.5, width - 0.5)
            u = np.mod(u + 0.5, self.width) - 0.5
        v = self.horizon_row - el / self.rad_per_px
        uv = np.column_stack((u, v))
        return uv, _inside(uv, self.width, self.height)

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "width": int(self.width),
            "height": int(self.height),
            "deg_per_px": float(self.deg_per_px),
            "horizon_row": float(self.horizon_row),
        }


@dataclass(frozen=True, slots=True)
class CatadioptricCamera:
    """The raw "donut" image of an upward-looking camera under a convex mirror.

    Model (a linearised single-viewpoint mirror, good enough for bearings): a pixel at offset
    ``(du, dv) = (u - cx, v - cy)`` from the mirror centre has radius ``r = hypot(du, dv)`` and

    - elevation linear in radius: ``elev = elev_inner + (r - r_inner) / (r_outer - r_inner) *
      (elev_outer - elev_inner)`` (radians; by default the inner ring looks down at the floor and
      the rim looks up, as with a convex mirror above the lens);
    - azimuth ``atan2(-du, -dv) + azimuth_offset``: straight ahead (body x) is image "up"
      (``dv < 0``), and azimuth grows counter-clockwise in the displayed image, i.e. to the LEFT,
      the same left-positive convention as :class:`PanoramaCamera`.

    Only the ring ``r_inner <= r <= r_outer`` carries the scene. :meth:`unwarp_maps` precomputes
    the lookup tables once; :meth:`unwarp` is then a single ``cv2.remap`` per frame.
    """

    width: int = 474
    height: int = 474
    cx: float = 236.5
    cy: float = 236.5
    r_inner: float = 40.0
    r_outer: float = 230.0
    elev_inner: float = math.radians(-56.0)
    elev_outer: float = math.radians(30.0)
    azimuth_offset: float = 0.0

    def __post_init__(self) -> None:
        _check_size(self.width, self.height)
        if not 0 <= self.r_inner < self.r_outer:
            raise ValueError(f"need 0 <= r_inner < r_outer, got {self.r_inner}, {self.r_outer}")
        if self.elev_inner == self.elev_outer:
            raise ValueError("elev_inner and elev_outer must differ")

    @property
    def kind(self) -> str:
        return "catadioptric"

    @property
    def _px_per_rad(self) -> float:
        return (self.r_outer - self.r_inner) / (self.elev_outer - self.elev_inner)

    def pixel_to_bearing(self, uv: np.ndarray) -> np.ndarray:
        pts = _as_uv(uv)
        du, dv = pts[:, 0] - self.cx, pts[:, 1] - self.cy
        r = np.hypot(du, dv)
        el = self.elev_inner + (r - self.r_inner) / self._px_per_rad
        az = np.arctan2(-du, -dv) + self.azimuth_offset
        ce = np.cos(el)
        return np.column_stack((ce * np.cos(az), ce * np.sin(az), np.sin(el)))

    def bearing_to_pixel(self, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        bearings = _as_bearings(b)
        az = np.arctan2(bearings[:, 1], bearings[:, 0]) - self.azimuth_offset
        el = np.arctan2(bearings[:, 2], np.hypot(bearings[:, 0], bearings[:, 1]))
        r = self.r_inner + (el - self.elev_inner) * self._px_per_rad
        uv = np.column_stack((self.cx - r * np.sin(az), self.cy - r * np.cos(az)))
        lo, hi = sorted((self.r_inner, self.r_outer))
        valid = (r >= lo - 1e-9) & (r <= hi + 1e-9) & _inside(uv, self.width, self.height)
        return uv, valid

    def unwarp_maps(self, panorama: PanoramaCamera) -> tuple[np.ndarray, np.ndarray]:
        """``cv2.remap`` tables (float32, panorama-sized) from this donut to ``panorama``.

        Panorama pixels whose bearing falls outside the ring map to -1 (black after remap).
        """
        us, vs = np.meshgrid(np.arange(panorama.width), np.arange(panorama.height))
        uv = np.column_stack((us.ravel(), vs.ravel())).astype(np.float64)
        src, valid = self.bearing_to_pixel(panorama.pixel_to_bearing(uv))
        src[~valid] = -1.0
        shape = (panorama.height, panorama.width)
        return src[:, 0].reshape(shape).astype(np.float32), src[:, 1].reshape(shape).astype(np.float32)

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "width": int(self.width),
            "height": int(self.height),
            "cx": float(self.cx),
            "cy": float(self.cy),
            "r_inner": float(self.r_inner),
            "r_outer": float(self.r_outer),
            "elev_inner": float(self.elev_inner),
            "elev_outer": float(self.elev_outer),
            "azimuth_offset": float(self.azimuth_offset),
        }


def unwarp(image: np.ndarray, maps: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Unwarp a donut image to a panorama with ONE ``cv2.remap`` (maps from ``unwarp_maps``)."""
    map_x, map_y = maps
    return cv2.remap(image, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)


@dataclass(frozen=True, slots=True)
class StereoRig:
    """A rectified parallel stereo pair: identical pinhole cameras, right one ``baseline`` m to the right.

    The rig's body frame is the LEFT camera's; the right camera centre is at ``(0, -baseline, 0)``
    (REP-103: y left, so -y is to the right). Bearings and pixels refer to the left camera.
    """

    left: PinholeCamera
    right: PinholeCamera
    baseline: float
    kind: str = field(default="stereo", init=False)

    def __post_init__(self) -> None:
        if not self.baseline > 0:
            raise ValueError(f"baseline must be positive, got {self.baseline}")
        if (self.left.width, self.left.height) != (self.right.width, self.right.height):
            raise ValueError("left and right images must have the same size")

    @property
    def width(self) -> int:
        return self.left.width

    @property
    def height(self) -> int:
        return self.left.height

    @property
    def right_centre(self) -> np.ndarray:
        """Position of the right camera in the rig (left camera body) frame."""
        return np.array([0.0, -self.baseline, 0.0])

    def pixel_to_bearing(self, uv: np.ndarray) -> np.ndarray:
        return self.left.pixel_to_bearing(uv)

    def bearing_to_pixel(self, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.left.bearing_to_pixel(b)

    def depth_from_disparity(self, disparity: np.ndarray) -> np.ndarray:
        """Depth along the optical axis (m) for disparities in pixels (``fx * baseline / d``)."""
        d = np.asarray(disparity, dtype=np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(d > 0, self.left.fx * self.baseline / d, np.inf)

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "baseline": float(self.baseline),
            "left": self.left.to_dict(),
            "right": self.right.to_dict(),
        }


_MODELS = {
    "pinhole": PinholeCamera,
    "panorama": PanoramaCamera,
    "catadioptric": CatadioptricCamera,
}


def camera_from_dict(d: dict[str, Any]) -> PinholeCamera | PanoramaCamera | CatadioptricCamera | StereoRig:
    """Build a camera model from plain data (the inverse of ``to_dict``).

    Raises ``ValueError`` with a readable message on unknown kinds, missing or extra keys and
    bad values; callers that read user files turn it into a located diagnostic. A ``calibration``
    key (metadata written by ``bearings calibrate``: board, rms, images) is accepted and ignored.
    """
    if not isinstance(d, dict):
        raise ValueError(f"a camera must be a mapping, got {type(d).__name__}")
    kind = d.get("kind")
    if kind == "stereo":
        return _stereo_from_dict(d)
    if kind not in _MODELS:
        known = ", ".join([*_MODELS, "stereo"])
        raise ValueError(f"unknown camera kind {kind!r} (known: {known})")
    cls = _MODELS[kind]
    fields = {f.name for f in dataclasses.fields(cls)}
    extra = set(d) - fields - {"kind", "calibration"}
    if extra:
        raise ValueError(f"unknown key(s) for a {kind} camera: {', '.join(sorted(map(str, extra)))}")
    kwargs = {name: _field(name, value) for name, value in d.items() if name not in ("kind", "calibration")}
    try:
        return cls(**kwargs)
    except TypeError as exc:  # a required field is missing
        raise ValueError(f"{kind} camera: {exc}") from None


def _stereo_from_dict(d: dict[str, Any]) -> StereoRig:
    missing = {"left", "right", "baseline"} - set(d)
    if missing:
        raise ValueError(f"stereo camera is missing {', '.join(sorted(missing))}")
    left, right = camera_from_dict(d["left"]), camera_from_dict(d["right"])
    if not (isinstance(left, PinholeCamera) and isinstance(right, PinholeCamera)):
        raise ValueError("both cameras of a stereo rig must be pinhole")
    return StereoRig(left=left, right=right, baseline=_number(d["baseline"], "baseline"))


def _field(name: str, value: Any) -> Any:
    """One camera field from plain data: ``dist`` a tuple of numbers, sizes integers, else a number."""
    if name == "dist":
        if not isinstance(value, (list, tuple)):
            raise ValueError("dist must be a list of numbers")
        return tuple(_number(x, "dist") for x in value)
    if name in ("width", "height"):
        return _integer(value, name)
    return _number(value, name)


def _number(value: Any, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def _integer(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    return int(value)
