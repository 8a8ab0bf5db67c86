"""Camera frames to ROS 2 messages and back: images, camera models, the ideal bearings sensor.

- Images are written as ``sensor_msgs/CompressedImage``: JPEG (quality 90 by default: about a
  quarter of the raw size) or PNG (lossless: a replay sees the very pixels the run saw). Read back
  are JPEG and PNG compressed images and raw ``sensor_msgs/Image`` in ``mono8``/``8UC1``,
  ``bgr8``/``8UC3``, ``rgb8``, ``bgra8`` and ``rgba8`` (colour comes back as OpenCV's BGR). Any
  other encoding is a ``ValueError`` naming it.
- A camera model is a ``sensor_msgs/CameraInfo``. A pinhole is what CameraInfo means:
  ``plumb_bob`` (0, 4 or 5 coefficients) or ``rational_polynomial`` (8), as OpenCV's coefficients
  (12 or 14 are written as ``bearings_opencv``); a stereo pair is two of them, the right one's
  projection holding ``Tx = -fx * baseline`` as ROS's stereo convention has it. A panorama or a
  catadioptric (donut) image has no CameraInfo model: it is written uncalibrated for ROS tools
  (``K`` all zero) with ``distortion_model`` ``bearings_panorama`` (``d`` = deg_per_px,
  horizon_row) or ``bearings_catadioptric`` (``d`` = cx, cy, r_inner, r_outer, elev_inner,
  elev_outer, azimuth_offset), which :func:`camera_from_info` reads back exactly.
- The ideal bearings sensor (:class:`~perception.frame.LandmarkBearings`) is a
  ``sensor_msgs/PointCloud2`` of unit bearings: float64 ``x, y, z`` and an int32 ``id`` per point.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

import cv2
import numpy as np

from drivers.logs.codec import header
from perception.camera import CatadioptricCamera, PanoramaCamera, PinholeCamera, StereoRig
from perception.frame import LandmarkBearings

PANORAMA_MODEL = "bearings_panorama"
CATADIOPTRIC_MODEL = "bearings_catadioptric"
OPENCV_MODEL = "bearings_opencv"
_CATADIOPTRIC_FIELDS = ("cx", "cy", "r_inner", "r_outer", "elev_inner", "elev_outer", "azimuth_offset")
_RAW_ENCODINGS = {"mono8": 1, "8uc1": 1, "bgr8": 3, "8uc3": 3, "rgb8": 3, "bgra8": 4, "rgba8": 4, "8uc4": 4}
_FLOAT64, _FLOAT32, _INT32, _UINT32 = 8, 7, 5, 6  # sensor_msgs/PointField datatypes
MAX_DECODED_PIXELS = 50_000_000
"""The largest compressed image a log may hold (a 50-megapixel camera; 150 MB as BGR): JPEG and PNG
compress a plain image a thousandfold, so a hostile message of a few kB could otherwise ask OpenCV for
gigabytes (its own limit is 2^30 pixels, over 3 GB)."""
_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_JPEG_FRAME_MARKERS = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}  # SOF0-SOF15 (not DHT, JPG, DAC)


@dataclass(frozen=True, slots=True)
class ImageFormat:
    """How images are compressed in a recording: ``jpeg`` at a quality (1-100) or lossless ``png``."""

    kind: Literal["jpeg", "png"] = "jpeg"
    quality: int = 90

    def __str__(self) -> str:
        return f"jpeg:{self.quality}" if self.kind == "jpeg" else "png"


def parse_image_format(text: str) -> ImageFormat:
    """``jpeg``, ``jpeg:Q`` (Q in 1..100) or ``png``; ValueError otherwise."""
    kind, _, quality = text.strip().lower().partition(":")
    if kind == "png" and not quality:
        return ImageFormat("png")
    if kind in ("jpeg", "jpg"):
        if not quality:
            return ImageFormat("jpeg")
        if quality.isdigit() and 1 <= int(quality) <= 100:
            return ImageFormat("jpeg", int(quality))
    raise ValueError(f"images are jpeg, jpeg:Q (quality 1 to 100) or png, got {text!r}")


# -- images --------------------------------------------------------------------------------------------
def compressed_image_message(image: np.ndarray, seconds: float, frame_id: str, fmt: ImageFormat) -> dict[str, Any]:
    """A ``sensor_msgs/CompressedImage`` of an 8-bit grey or BGR image."""
    if image.dtype != np.uint8 or image.ndim not in (2, 3):
        raise ValueError(f"an image to record is 8-bit grey or colour, got {image.dtype} {image.shape}")
    params = [cv2.IMWRITE_JPEG_QUALITY, fmt.quality] if fmt.kind == "jpeg" else [cv2.IMWRITE_PNG_COMPRESSION, 3]
    ok, data = cv2.imencode(".jpg" if fmt.kind == "jpeg" else ".png", image, params)
    if not ok:
        raise ValueError(f"OpenCV could not encode a {image.shape} image as {fmt.kind}")
    return {"header": header(seconds, frame_id), "format": fmt.kind, "data": data.tobytes()}


def image_from_compressed(message: Mapping[str, Any]) -> np.ndarray:
    """The pixels of a JPEG or PNG ``sensor_msgs/CompressedImage`` (grey stays grey, colour is BGR)."""
    declared = str(message.get("format", "")).lower()
    if not any(name in declared for name in ("jpeg", "jpg", "png")):
        raise ValueError(f"compressed image format {declared!r} is not one we read (jpeg, png)")
    raw = bytes(message["data"])
    size = compressed_image_size(raw)
    if size is not None and size[0] * size[1] > MAX_DECODED_PIXELS:
        raise ValueError(f"the {declared} image declares {size[0]}x{size[1]} pixels "
                         f"(at most {MAX_DECODED_PIXELS / 1e6:.0f} megapixels are decoded)")
    data = np.frombuffer(raw, dtype=np.uint8)
    image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
    if image is None or image.dtype != np.uint8:
        raise ValueError(f"the {declared} image data ({data.size} bytes) does not decode to an 8-bit image")
    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    return image


def compressed_image_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) from a PNG's IHDR or a JPEG's frame header, read before anything is decoded;
    None when neither is found (OpenCV then refuses the data itself). OpenCV's Python API offers no
    header-only read, hence these few bytes of the two formats' public specifications."""
    if data[:8] == _PNG_SIGNATURE and len(data) >= 24 and data[12:16] == b"IHDR":
        return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    at = 2 if data[:2] == b"\xff\xd8" else len(data)
    while at + 4 <= len(data):
        if data[at] != 0xFF:
            return None
        marker = data[at + 1]
        if marker == 0xFF:  # fill byte
            at += 1
            continue
        if marker in _JPEG_FRAME_MARKERS:
            if at + 9 > len(data):
                return None
            return int.from_bytes(data[at + 7:at + 9], "big"), int.from_bytes(data[at + 5:at + 7], "big")
        if marker == 0xD8 or 0xD0 <= marker <= 0xD7:  # standalone markers carry no length
            at += 2
            continue
        at += 2 + int.from_bytes(data[at + 2:at + 4], "big")
    return None


def image_from_raw(message: Mapping[str, Any]) -> np.ndarray:
    """The pixels of a raw ``sensor_msgs/Image`` in an 8-bit encoding (colour as BGR)."""
    encoding = str(message["encoding"]).lower()
    channels = _RAW_ENCODINGS.get(encoding)
    if channels is None:
        raise ValueError(f"image encoding {message['encoding']!r} is not one we read "
                         f"({', '.join(sorted(_RAW_ENCODINGS))})")
    height, width, step = int(message["height"]), int(message["width"]), int(message["step"])
    data = np.frombuffer(bytes(message["data"]), dtype=np.uint8)
    if height <= 0 or width <= 0 or step < width * channels or data.size < height * step:
        raise ValueError(f"a {width}x{height} {encoding} image needs {height} rows of {width * channels} bytes "
                         f"(step {step}), the message holds {data.size} bytes")
    rows = data[:height * step].reshape(height, step)[:, :width * channels]
    image = rows.reshape(height, width, channels) if channels > 1 else rows.reshape(height, width)
    if encoding.startswith("rgb"):
        return cv2.cvtColor(image, cv2.COLOR_RGB2BGR if channels == 3 else cv2.COLOR_RGBA2BGR)
    if channels == 4:
        return cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    return np.ascontiguousarray(image)


# -- camera models -------------------------------------------------------------------------------------
CameraModel = PinholeCamera | PanoramaCamera | CatadioptricCamera | StereoRig


def camera_info_messages(model: Any, seconds: float, frame_id: str) -> list[dict[str, Any]]:
    """The ``sensor_msgs/CameraInfo`` of a camera model: one, or [left, right] for a stereo pair."""
    if isinstance(model, StereoRig):
        right = _pinhole_info(model.right, seconds, f"{frame_id}_right", tx=-model.right.fx * model.baseline)
        return [_pinhole_info(model.left, seconds, frame_id), right]
    if isinstance(model, PinholeCamera):
        return [_pinhole_info(model, seconds, frame_id)]
    if isinstance(model, PanoramaCamera):
        return [_info(model.width, model.height, PANORAMA_MODEL, [model.deg_per_px, model.horizon_row],
                      seconds, frame_id)]
    if isinstance(model, CatadioptricCamera):
        return [_info(model.width, model.height, CATADIOPTRIC_MODEL,
                      [float(getattr(model, name)) for name in _CATADIOPTRIC_FIELDS], seconds, frame_id)]
    raise ValueError(f"no CameraInfo for a camera model of type {type(model).__name__}")


def _info(width: int, height: int, distortion: str, d: list[float], seconds: float, frame_id: str,
          k: list[float] | None = None, p: list[float] | None = None) -> dict[str, Any]:
    return {"header": header(seconds, frame_id), "width": int(width), "height": int(height),
            "distortion_model": distortion, "d": [float(x) for x in d], "k": k or [0.0] * 9,
            "r": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], "p": p or [0.0] * 12}


def _pinhole_info(model: PinholeCamera, seconds: float, frame_id: str, tx: float = 0.0) -> dict[str, Any]:
    count = len(model.dist)
    distortion = "plumb_bob" if count in (0, 4, 5) else "rational_polynomial" if count == 8 else OPENCV_MODEL
    k = [model.fx, 0.0, model.cx, 0.0, model.fy, model.cy, 0.0, 0.0, 1.0]
    p = [model.fx, 0.0, model.cx, tx, 0.0, model.fy, model.cy, 0.0, 0.0, 0.0, 1.0, 0.0]
    return _info(model.width, model.height, distortion, list(model.dist), seconds, frame_id, k, p)


def camera_from_info(message: Mapping[str, Any], right: Mapping[str, Any] | None = None) -> CameraModel:
    """The camera model of a ``sensor_msgs/CameraInfo`` (with ``right``: the stereo pair's).

    ValueError when the model is not one we read (an uncalibrated pinhole, a fisheye...): the
    topic map can then name the camera's model file instead.
    """
    distortion = str(message.get("distortion_model", ""))
    d = [float(x) for x in message.get("d", [])]
    width, height = int(message["width"]), int(message["height"])
    if distortion == PANORAMA_MODEL and len(d) == 2:
        return PanoramaCamera(width, height, deg_per_px=d[0], horizon_row=d[1])
    if distortion == CATADIOPTRIC_MODEL and len(d) == len(_CATADIOPTRIC_FIELDS):
        return CatadioptricCamera(width, height, **dict(zip(_CATADIOPTRIC_FIELDS, d, strict=True)))
    left = _pinhole_from_info(message, distortion, d, width, height)
    if right is None:
        return left
    right_model = _pinhole_from_info(right, str(right.get("distortion_model", "")),
                                     [float(x) for x in right.get("d", [])], int(right["width"]), int(right["height"]))
    p = [float(x) for x in right["p"]]
    if not p[0] > 0 or not -p[3] / p[0] > 0:
        raise ValueError(f"the right camera's projection gives no baseline (Tx = {p[3]:g}, fx = {p[0]:g})")
    return StereoRig(left, right_model, baseline=-p[3] / p[0])


def _pinhole_from_info(message: Mapping[str, Any], distortion: str, d: list[float], width: int,
                       height: int) -> PinholeCamera:
    if distortion not in ("plumb_bob", "rational_polynomial", OPENCV_MODEL, "", "none"):
        raise ValueError(f"camera model {distortion!r} is not one we read (plumb_bob, rational_polynomial, "
                         f"{PANORAMA_MODEL}, {CATADIOPTRIC_MODEL})")
    k = [float(x) for x in message.get("k", [])]
    if len(k) != 9 or not (k[0] > 0 and k[4] > 0):
        raise ValueError("the camera is not calibrated (CameraInfo K has no focal length)")
    while d and len(d) not in (0, 4, 5, 8, 12, 14) and d[-1] == 0.0:
        d = d[:-1]  # trailing zero coefficients some drivers pad with
    if len(d) not in (0, 4, 5, 8, 12, 14):
        raise ValueError(f"{len(d)} distortion coefficients: OpenCV takes 0, 4, 5, 8, 12 or 14")
    if not all(math.isfinite(x) for x in (*k, *d)):
        raise ValueError("the camera calibration holds a number that is not finite")
    return PinholeCamera(width, height, fx=k[0], fy=k[4], cx=k[2], cy=k[5], dist=tuple(d))


# -- the ideal bearings sensor -------------------------------------------------------------------------
_CLOUD = np.dtype({"names": ["x", "y", "z", "id"], "formats": ["<f8", "<f8", "<f8", "<i4"],
                   "offsets": [0, 8, 16, 24], "itemsize": 28})


def bearings_message(bearings: LandmarkBearings) -> dict[str, Any]:
    """A ``sensor_msgs/PointCloud2`` of the unit bearings and ids of the landmarks seen."""
    ids = np.asarray(bearings.ids, dtype=np.int64)
    if ids.size and (ids.min() < np.iinfo(np.int32).min or ids.max() > np.iinfo(np.int32).max):
        raise ValueError("landmark ids beyond 32 bits cannot be written")
    points = np.zeros(len(ids), dtype=_CLOUD)
    xyz = np.asarray(bearings.bearings, dtype=np.float64).reshape(-1, 3)
    points["x"], points["y"], points["z"], points["id"] = xyz[:, 0], xyz[:, 1], xyz[:, 2], ids
    fields = [{"name": n, "offset": o, "datatype": t, "count": 1}
              for n, o, t in (("x", 0, _FLOAT64), ("y", 8, _FLOAT64), ("z", 16, _FLOAT64), ("id", 24, _INT32))]
    return {"header": header(bearings.stamp, bearings.camera_name), "height": 1, "width": len(ids),
            "fields": fields, "is_bigendian": False, "point_step": _CLOUD.itemsize,
            "row_step": _CLOUD.itemsize * len(ids), "data": points.tobytes(), "is_dense": True}


def bearings_from_cloud(message: Mapping[str, Any], stamp: float, camera_name: str) -> LandmarkBearings:
    """The landmark bearings of a point cloud with ``x, y, z`` and ``id`` fields (sorted by id)."""
    types = {_FLOAT64: "<f8", _FLOAT32: "<f4", _INT32: "<i4", _UINT32: "<u4"}
    fields = {str(f["name"]): f for f in message.get("fields", [])}
    missing = [n for n in ("x", "y", "z", "id") if n not in fields]
    if missing or bool(message.get("is_bigendian", False)):
        raise ValueError(f"a bearings cloud has little-endian fields x, y, z and id (missing: {', '.join(missing)})"
                         if missing else "a big-endian point cloud is not one we read")
    try:
        dtype = np.dtype({"names": ["x", "y", "z", "id"],
                          "formats": [types[int(fields[n]["datatype"])] for n in ("x", "y", "z", "id")],
                          "offsets": [int(fields[n]["offset"]) for n in ("x", "y", "z", "id")],
                          "itemsize": int(message["point_step"])})
    except (KeyError, ValueError, TypeError) as exc:
        raise ValueError(f"the bearings cloud's fields cannot be read ({exc})") from None
    count = int(message["width"]) * int(message["height"])
    data = bytes(message["data"])
    if len(data) < count * dtype.itemsize:
        raise ValueError(f"the cloud declares {count} points of {dtype.itemsize} bytes, it holds {len(data)} bytes")
    points = np.frombuffer(data, dtype=dtype, count=count)
    order = np.argsort(points["id"], kind="stable")
    xyz = np.column_stack([points[n].astype(np.float64) for n in ("x", "y", "z")])[order]
    return LandmarkBearings(points["id"].astype(np.int64)[order], xyz.reshape(-1, 3), stamp, camera_name)
