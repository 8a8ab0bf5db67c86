"""Cameras on a robot: OpenCV ``VideoCapture`` (device, file, RTSP/MJPEG URL) and HTTP snapshots.

Both implement :class:`drivers.interfaces.Camera`. A thread per camera grabs continuously and
keeps only the newest image; ``grab()`` hands that image over as a :class:`perception.frame.Frame`
if it is new since the last ``grab()`` and returns ``None`` otherwise, so a tick never waits for a
device. Failures (a read that returns nothing, an HTTP error or timeout, a JPEG that does not
decode, a frame of the wrong size) are counted in :meth:`stats` with the last error text and never
raise from ``grab()``; a capture that keeps failing is re-opened, and a camera that cannot deliver
any more (a file at its end without ``loop``, a device that cannot be re-opened) sets ``fault``.

The frame's camera model comes from the ``calibration`` file (the YAML that ``bearings calibrate``
writes, or any model of :func:`perception.camera.camera_from_dict`, e.g. a catadioptric mirror);
with ``unwarp: true`` a catadioptric donut is unwarped to a 720 x 172 panorama in the grab thread
(one ``cv2.remap`` with tables made once). With a stereo calibration (``kind: stereo``, a rectified
pair) the device delivers both images side by side in one frame, left then right (as USB stereo
cameras do): the frame is split, and its ``right`` image is the right half. Without a calibration
the model is a nominal pinhole of ``fov_deg`` across, good enough for ``bearings doctor`` and for
tests, not for navigation.
"""

from __future__ import annotations

import base64
import contextlib
import dataclasses
import logging
import math
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal, Self

import cv2
import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from drivers.common import Stamp, build_settings, monotonic_stamp, quantity
from maps.store import Diagnostic, InputError, YamlMap, load_yaml
from perception.camera import CatadioptricCamera, PanoramaCamera, PinholeCamera, StereoRig, camera_from_dict, unwarp
from perception.frame import Frame

log = logging.getLogger(__name__)

MAX_SNAPSHOT_BYTES = 32 * 1024 * 1024
FAILURE_PAUSE_S = 0.05  # after a failed capture, before trying again
BACKENDS = {"any": cv2.CAP_ANY, "v4l2": cv2.CAP_V4L2, "ffmpeg": cv2.CAP_FFMPEG, "gstreamer": cv2.CAP_GSTREAMER}


class CameraError(OSError):
    """A camera that cannot be opened or does not deliver its first frame."""


class _CameraSettings(BaseModel):
    model_config = ConfigDict(extra="forbid")

    name: str | None = Field(None, min_length=1, max_length=64, description="camera name stamped on its "
                             "frames (default: 'camera'; the profile loader passes the entry's key)")
    calibration: str | None = Field(None, description="camera model YAML (from 'bearings calibrate', or a "
                                    "catadioptric/panorama model); its size must match the frames")
    unwarp: bool = Field(False, description="deliver a catadioptric camera's frames unwarped to a 720 x 172 "
                         "panorama (needs a catadioptric calibration)")
    fov_deg: float = quantity(60.0, "horizontal field of view of the nominal pinhole model used without a "
                              "calibration", "deg", ge=1.0, le=179.0)
    timeout: float = quantity(5.0, "time allowed to open the camera and get its first frame; for HTTP also "
                              "each request's timeout", "s", ge=0.1, le=120.0)


class OpenCVCameraSettings(_CameraSettings):
    """A camera read with ``cv2.VideoCapture`` (``cameras: {front: {driver: opencv, device: 0}}``)."""

    device: Annotated[int, Field(ge=0, le=255)] | Annotated[str, Field(min_length=1)] = Field(
        description="device index (0 = /dev/video0), a video file, or a stream URL (rtsp://..., "
        "http://.../video.mjpg)")
    width: int | None = quantity(None, "frame width to ask the device for", "px", ge=16, le=8192)
    height: int | None = quantity(None, "frame height to ask the device for", "px", ge=16, le=8192)
    fps: float | None = quantity(None, "frame rate to ask the device for; for a file, the playback rate "
                                 "(default: the file's)", "Hz", ge=0.1, le=240.0)
    loop: bool = Field(False, description="for a file: start again at its end instead of ending")
    backend: Literal["any", "v4l2", "ffmpeg", "gstreamer"] = Field("any", description="OpenCV capture backend")
    reopen_after: int = Field(10, ge=1, le=10000, description="failed reads in a row after which the "
                              "capture is re-opened (a stream that dropped)")


class HttpCameraSettings(_CameraSettings):
    """A network camera polled for JPEG snapshots (Axis: http://HOST/axis-cgi/jpg/image.cgi)."""

    url: str = Field(pattern=r"^https?://", description="snapshot URL returning one JPEG (or PNG) per request")
    period: float = quantity(0.1, "time between the starts of two requests", "s", ge=0.01, le=60.0)
    username: str | None = Field(None, description="user for HTTP basic authentication")
    password: str | None = Field(None, description="password for HTTP basic authentication")


@dataclass(frozen=True, slots=True)
class CameraStats:
    """How a camera is doing: ``failures`` are dropped frames (the device gave none or a bad one),
    ``empty_grabs`` ticks that found no new frame, ``overwritten`` frames never handed over because
    a newer one came first (normal when the camera is faster than the tick rate)."""

    captured: int = 0
    delivered: int = 0
    overwritten: int = 0
    empty_grabs: int = 0
    failures: int = 0
    reopens: int = 0
    rate: float = 0.0  # frames per second captured, smoothed
    size: tuple[int, int] | None = None  # width, height of the delivered frames
    last_error: str | None = None


class _ThreadedCamera:
    """The grab thread and the newest-frame hand-over shared by the camera kinds."""

    kind = "camera"

    def __init__(self, settings: _CameraSettings, *, clock: Stamp | None = None) -> None:
        self.settings = settings
        self.name = settings.name or "camera"
        self.fault: str | None = None
        self._stamp = monotonic_stamp(clock)
        self._model, self._maps, self._output = load_calibration(settings)
        self._lock = threading.Lock()
        self._newest: Frame | None = None
        self._fresh = False
        self._stats = CameraStats()
        self._first = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._last_capture: float | None = None

    # -- the Camera interface --------------------------------------------------------------------
    def grab(self) -> Frame | None:
        """The newest frame if it is new since the last call, else None; never blocks, never raises."""
        with self._lock:
            if not self._fresh or self._newest is None:
                self._count(empty_grabs=1)
                return None
            self._fresh = False
            self._count(delivered=1)
            return self._newest

    def close(self) -> None:
        """Stop the grab thread and release the device; never raises."""
        self._stop.set()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=self.settings.timeout + 1.0)
        if thread is None or not thread.is_alive():  # else the thread releases it when its read returns
            self._release()
        if self.fault is None:
            self.fault = "the camera is closed"

    def stats(self) -> CameraStats:
        with self._lock:
            return self._stats

    @property
    def model(self) -> Any:
        """The camera model stamped on delivered frames."""
        return self._output

    # -- the grab thread ---------------------------------------------------------------------------
    def start(self) -> Self:
        self._thread = threading.Thread(target=self._run, name=f"{self.kind} {self.name}", daemon=True)
        self._thread.start()
        if not self._first.wait(self.settings.timeout) or self._newest is None:
            self.close()
            detail = self._stats.last_error or self.fault or "no frame"
            raise CameraError(f"camera {self.name} ({self.describe()}) gave no frame within "
                              f"{self.settings.timeout:g} s: {detail}")
        return self

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                started = time.monotonic()
                try:
                    image = self._capture()
                except Exception as exc:  # noqa: BLE001 - a dropped frame, counted, never raised
                    self._fail(f"{type(exc).__name__}: {exc}")
                    continue
                if image is not None:
                    self._deliver(image)
                self._pace(started)
        finally:
            self._first.set()
            self._release()

    def _deliver(self, image: np.ndarray) -> None:
        model = self._model_for(image)
        height, width = image.shape[:2]
        pair = isinstance(model, StereoRig)  # side by side: left | right
        if (model.width * (2 if pair else 1), model.height) != (width, height):
            size = f"{2 * model.width}x{model.height} (a stereo pair side by side)" if pair else \
                f"{model.width}x{model.height}"
            self._fail(f"frame is {width}x{height} but the camera model is {size}")
            if self._newest is None:
                self.fault = self._stats.last_error
                self._stop.set()
            return
        right = None
        if pair:
            image, right = image[:, : model.width], image[:, model.width :]
        if self._maps is not None:
            image = unwarp(image, self._maps)
        frame = Frame(image=image, camera=self._output, stamp=self._stamp(), camera_name=self.name, right=right)
        now = time.monotonic()
        with self._lock:
            rate = self._stats.rate
            if self._last_capture is not None and now > self._last_capture:
                instant = 1.0 / (now - self._last_capture)
                rate = instant if rate == 0.0 else 0.8 * rate + 0.2 * instant
            self._last_capture = now
            self._count(captured=1, overwritten=int(self._fresh))
            self._stats = _replace(self._stats, rate=rate, size=(frame.image.shape[1], frame.image.shape[0]))
            self._newest, self._fresh = frame, True
        self._first.set()

    def _model_for(self, image: np.ndarray) -> Any:
        if self._model is None:  # no calibration: a nominal pinhole for this frame size
            height, width = image.shape[:2]
            focal = width / 2.0 / math.tan(math.radians(self.settings.fov_deg) / 2.0)
            self._model = PinholeCamera(width, height, focal, focal, (width - 1) / 2.0, (height - 1) / 2.0)
            self._output = self._model
        return self._model

    def _fail(self, message: str) -> None:
        with self._lock:
            self._count(failures=1)
            self._stats = _replace(self._stats, last_error=message)
        log.debug("camera %s: %s", self.name, message)
        self._stop.wait(FAILURE_PAUSE_S)

    def _count(self, **increments: int) -> None:
        values = {key: getattr(self._stats, key) + value for key, value in increments.items()}
        self._stats = _replace(self._stats, **values)

    def _pace(self, started: float) -> None:
        period = self._period()
        if period:
            self._stop.wait(max(0.0, period - (time.monotonic() - started)))

    # -- per kind ----------------------------------------------------------------------------------
    def _capture(self) -> np.ndarray | None:
        raise NotImplementedError

    def _period(self) -> float:
        return 0.0

    def _release(self) -> None:
        pass

    def describe(self) -> str:
        return self.kind


class OpenCVCamera(_ThreadedCamera):
    """A ``cv2.VideoCapture`` read in a thread; build it with :func:`open_opencv_camera`."""

    kind = "opencv"

    def __init__(self, settings: OpenCVCameraSettings, *, clock: Stamp | None = None) -> None:
        super().__init__(settings, clock=clock)
        self.settings: OpenCVCameraSettings = settings
        self._source, self._is_file = _source(settings.device)
        self._cap: cv2.VideoCapture | None = None
        self._failed_in_row = 0
        self._file_period = 0.0
        self._open_capture()

    def describe(self) -> str:
        return f"opencv {self._source}"

    def _open_capture(self) -> None:
        settings = self.settings
        if self._is_file and not Path(str(self._source)).is_file():
            raise FileNotFoundError(f"camera {self.name}: no video file {self._source}")
        params: list[int] = []
        if isinstance(self._source, str) and not self._is_file:
            ms = int(settings.timeout * 1000)
            params = [cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, ms, cv2.CAP_PROP_READ_TIMEOUT_MSEC, ms]
        cap = cv2.VideoCapture(self._source, BACKENDS[settings.backend], params)
        if not cap.isOpened():
            cap.release()
            raise CameraError(f"camera {self.name}: OpenCV cannot open {self._source!r} "
                              f"(no such device, unsupported format, or unreachable stream)")
        for prop, value in ((cv2.CAP_PROP_FRAME_WIDTH, settings.width), (cv2.CAP_PROP_FRAME_HEIGHT, settings.height),
                            (cv2.CAP_PROP_FPS, None if self._is_file else settings.fps)):
            if value is not None:
                cap.set(prop, float(value))
        if self._is_file:
            rate = settings.fps or cap.get(cv2.CAP_PROP_FPS) or 25.0
            self._file_period = 1.0 / rate
        self._cap = cap

    def _capture(self) -> np.ndarray | None:
        cap = self._cap
        if cap is None:
            self._reopen()
            return None
        ok, image = cap.read()
        if ok and image is not None:
            self._failed_in_row = 0
            return image
        if self._is_file and self.settings.loop and self._stats.captured:
            cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
            return None
        if self._is_file:
            self.fault = f"camera {self.name}: end of {self._source}"
            self._stop.set()
            return None
        self._failed_in_row += 1
        self._fail(f"no frame from {self._source}")
        if self._failed_in_row >= self.settings.reopen_after:
            self._reopen()
        return None

    def _reopen(self) -> None:
        self._release()
        try:
            self._open_capture()
        except OSError as exc:
            self._fail(str(exc))
            return
        self._failed_in_row = 0
        with self._lock:
            self._count(reopens=1)

    def _period(self) -> float:
        return self._file_period

    def _release(self) -> None:
        cap, self._cap = self._cap, None
        if cap is not None:
            with contextlib.suppress(Exception):
                cap.release()


class HttpCamera(_ThreadedCamera):
    """JPEG snapshots over HTTP, polled in a thread; build it with :func:`open_http_camera`."""

    kind = "http"

    def __init__(self, settings: HttpCameraSettings, *, clock: Stamp | None = None) -> None:
        super().__init__(settings, clock=clock)
        self.settings: HttpCameraSettings = settings
        self._headers = {"User-Agent": "bearings"}
        if settings.username is not None:
            token = base64.b64encode(f"{settings.username}:{settings.password or ''}".encode()).decode()
            self._headers["Authorization"] = f"Basic {token}"

    def describe(self) -> str:
        return f"http {self.settings.url}"

    def _capture(self) -> np.ndarray | None:
        request = urllib.request.Request(self.settings.url, headers=self._headers)
        try:
            with urllib.request.urlopen(request, timeout=self.settings.timeout) as response:  # noqa: S310
                data = response.read(MAX_SNAPSHOT_BYTES + 1)
        except urllib.error.HTTPError as exc:
            self._fail(f"HTTP {exc.code} {exc.reason} from {self.settings.url}")
            return None
        except (urllib.error.URLError, OSError, TimeoutError) as exc:
            reason = getattr(exc, "reason", exc)
            self._fail(f"{self.settings.url}: {reason}")
            return None
        if len(data) > MAX_SNAPSHOT_BYTES:
            self._fail(f"snapshot larger than {MAX_SNAPSHOT_BYTES} bytes")
            return None
        image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
        if image is None:
            self._fail(f"{self.settings.url} returned {len(data)} bytes that are not an image")
        return image

    def _period(self) -> float:
        return self.settings.period


# -- calibration ---------------------------------------------------------------------------------------
def load_calibration(settings: _CameraSettings) -> tuple[Any, tuple[np.ndarray, np.ndarray] | None, Any]:
    """``(model of the raw frames, unwarp tables or None, model of the delivered frames)``."""
    if settings.calibration is None:
        if settings.unwarp:
            raise InputError([Diagnostic("camera", 0, 0, "unwarp: true needs a catadioptric calibration file")])
        return None, None, None
    path = settings.calibration
    doc = load_yaml(path)
    try:
        model = camera_from_dict(dict(doc) if isinstance(doc, dict) else doc)
    except ValueError as exc:
        mark = doc.mark if isinstance(doc, YamlMap) else None
        raise InputError([Diagnostic(str(path), mark.line if mark else 1, mark.col if mark else 1,
                                     f"not a camera model: {exc}")]) from None
    if not settings.unwarp:
        return model, None, model
    if not isinstance(model, CatadioptricCamera):
        raise InputError([Diagnostic(str(path), 1, 1, f"unwarp: true needs a catadioptric model, "
                                     f"this file holds a {model.kind} camera")])
    panorama = PanoramaCamera()
    return model, model.unwarp_maps(panorama), panorama


def _source(device: int | str) -> tuple[int | str, bool]:
    """``(what VideoCapture opens, whether it is a local file)``."""
    if isinstance(device, int):
        return device, False
    text = device.strip()
    if text.isdigit():
        return int(text), False
    if "://" in text:
        return text, False
    return str(Path(text).expanduser()), True


def _replace(stats: CameraStats, **changes: Any) -> CameraStats:
    return dataclasses.replace(stats, **changes)


# -- openers -----------------------------------------------------------------------------------------
def open_opencv_camera(settings: OpenCVCameraSettings | Mapping[str, Any] | None = None, /, *,
                       clock: Stamp | None = None, **fields: Any) -> OpenCVCamera:
    """Open a VideoCapture camera and wait for its first frame; ``OSError`` when it cannot deliver."""
    model = build_settings(OpenCVCameraSettings, settings, fields, where="camera (opencv)")
    camera = OpenCVCamera(model, clock=clock)
    try:
        camera.start()
    except BaseException:
        camera.close()
        raise
    return camera


def open_http_camera(settings: HttpCameraSettings | Mapping[str, Any] | None = None, /, *,
                     clock: Stamp | None = None, **fields: Any) -> HttpCamera:
    """Start polling a snapshot URL and wait for the first image; ``OSError`` when none comes."""
    model = build_settings(HttpCameraSettings, settings, fields, where="camera (http)")
    camera = HttpCamera(model, clock=clock)
    return camera.start()
