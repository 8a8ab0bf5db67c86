"""Cameras: a video file written with cv2.VideoWriter, and a local HTTP server serving JPEG snapshots."""

from __future__ import annotations

import base64
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import cv2
import numpy as np
import pytest

from drivers.cameras import CameraError, HttpCameraSettings, OpenCVCameraSettings, open_http_camera, open_opencv_camera
from drivers.interfaces import Camera
from maps.store import InputError, write_yaml
from perception.camera import CatadioptricCamera, PanoramaCamera, PinholeCamera, StereoRig


def _write_video(path: Path, frames: int, size: tuple[int, int] = (64, 48), fps: float = 20.0) -> Path:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, size)
    assert writer.isOpened()
    for i in range(frames):
        image = np.zeros((size[1], size[0], 3), np.uint8)
        image[:, : (i * 7) % size[0] + 1] = (i * 20) % 255
        writer.write(image)
    writer.release()
    return path


def _wait_frame(camera: Camera, timeout: float = 2.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        frame = camera.grab()
        if frame is not None:
            return frame
        time.sleep(0.005)
    return None


@pytest.fixture
def video(tmp_path) -> Path:
    return _write_video(tmp_path / "clip.avi", frames=12)


def test_video_file_frames_and_end(video, devices):
    camera = devices(open_opencv_camera(device=str(video), fps=200.0, name="front"))
    assert isinstance(camera, Camera)
    frames = []
    while len(frames) < 3:
        frame = _wait_frame(camera)
        assert frame is not None
        frames.append(frame)
    assert frames[0].image.shape == (48, 64, 3) and frames[0].camera_name == "front"
    assert isinstance(frames[0].camera, PinholeCamera) and frames[0].camera.width == 64
    assert frames[0].stamp < frames[1].stamp < frames[2].stamp
    end = time.monotonic() + 2.0
    while camera.fault is None and time.monotonic() < end:
        time.sleep(0.01)
    assert "end of" in camera.fault  # the file ended: reported, not raised
    assert camera.grab() is not None  # the last frame, once
    assert camera.grab() is None and camera.grab() is None  # nothing new: None, not a repeat
    stats = camera.stats()
    assert stats.captured == 12 and stats.size == (64, 48) and stats.failures == 0
    assert stats.delivered == 4 and stats.empty_grabs >= 2 and stats.overwritten == 12 - 4


def test_video_file_loops_when_asked(video, devices):
    camera = devices(open_opencv_camera(device=str(video), fps=200.0, loop=True))
    end = time.monotonic() + 2.0
    while camera.stats().captured < 20 and time.monotonic() < end:
        time.sleep(0.01)
    assert camera.stats().captured >= 20 and camera.fault is None
    assert camera.stats().overwritten > 0  # nobody grabbed: older frames were replaced, not queued
    assert camera.stats().rate > 50


def test_grab_hands_over_the_newest_frame_only(tmp_path, devices):
    clip = _write_video(tmp_path / "three.avi", frames=3)
    camera = devices(open_opencv_camera(device=str(clip), fps=200.0))
    end = time.monotonic() + 2.0
    while camera.fault is None and time.monotonic() < end:
        time.sleep(0.01)
    frame = camera.grab()
    assert frame is not None and int(frame.image[0, 0, 0]) > 30  # the third frame, not the first
    assert camera.grab() is None
    assert camera.stats().delivered == 1 and camera.stats().overwritten == 2


def test_calibration_gives_the_model_and_checks_the_size(tmp_path, video, devices):
    good = tmp_path / "front.yaml"
    write_yaml(good, PinholeCamera(64, 48, 60.0, 60.0, 31.5, 23.5).to_dict())
    camera = devices(open_opencv_camera(device=str(video), calibration=str(good), fps=200.0))
    assert _wait_frame(camera).camera == PinholeCamera(64, 48, 60.0, 60.0, 31.5, 23.5)
    wrong = tmp_path / "wrong.yaml"
    write_yaml(wrong, PinholeCamera(640, 480, 500.0, 500.0, 319.5, 239.5).to_dict())
    with pytest.raises(CameraError, match="64x48 but the camera model is 640x480"):
        open_opencv_camera(device=str(video), calibration=str(wrong), timeout=1.0)
    broken = tmp_path / "broken.yaml"
    broken.write_text("kind: fisheye\nwidth: 64\n")
    with pytest.raises(InputError, match="unknown camera kind"):
        open_opencv_camera(device=str(video), calibration=str(broken))
    with pytest.raises(InputError, match="no such file"):
        open_opencv_camera(device=str(video), calibration=str(tmp_path / "none.yaml"))


def test_a_stereo_pair_side_by_side_is_split_into_left_and_right(tmp_path, devices):
    eye = PinholeCamera(32, 48, 40.0, 40.0, 15.5, 23.5)
    calibration = tmp_path / "stereo.yaml"
    write_yaml(calibration, StereoRig(eye, eye, 0.12).to_dict())
    both = _write_video(tmp_path / "pair.avi", frames=4, size=(64, 48))  # 32 px wide each, side by side
    camera = devices(open_opencv_camera(device=str(both), calibration=str(calibration), fps=100.0))
    frame = _wait_frame(camera)
    assert isinstance(frame.camera, StereoRig) and frame.image.shape[:2] == (48, 32)
    assert frame.right is not None and frame.right.shape[:2] == (48, 32)
    single = _write_video(tmp_path / "one.avi", frames=2, size=(32, 48))
    with pytest.raises(CameraError, match="32x48 but the camera model is 64x48 \\(a stereo pair side by side\\)"):
        open_opencv_camera(device=str(single), calibration=str(calibration), timeout=1.0)


def test_catadioptric_frames_are_unwarped_to_a_panorama(tmp_path, devices):
    mirror = CatadioptricCamera(width=96, height=96, cx=47.5, cy=47.5, r_inner=8.0, r_outer=46.0)
    calibration = tmp_path / "omni.yaml"
    write_yaml(calibration, mirror.to_dict())
    donut = _write_video(tmp_path / "donut.avi", frames=4, size=(96, 96))
    raw = devices(open_opencv_camera(device=str(donut), calibration=str(calibration), fps=100.0))
    assert isinstance(_wait_frame(raw).camera, CatadioptricCamera)
    camera = devices(open_opencv_camera(device=str(donut), calibration=str(calibration), unwarp=True, fps=100.0))
    frame = _wait_frame(camera)
    assert isinstance(frame.camera, PanoramaCamera) and frame.image.shape[:2] == (172, 720)
    pinhole = tmp_path / "pin.yaml"
    write_yaml(pinhole, PinholeCamera(96, 96, 50.0, 50.0, 47.5, 47.5).to_dict())
    with pytest.raises(InputError, match="catadioptric"):
        open_opencv_camera(device=str(donut), calibration=str(pinhole), unwarp=True)


def test_open_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="no video file"):
        open_opencv_camera(device=str(tmp_path / "missing.avi"))
    (tmp_path / "not-a-video.avi").write_bytes(b"\x00" * 100)
    with pytest.raises(OSError):
        open_opencv_camera(device=str(tmp_path / "not-a-video.avi"), timeout=0.5)
    with pytest.raises(InputError, match="device"):
        open_opencv_camera(width=640)
    schema = OpenCVCameraSettings.model_json_schema()["properties"]
    assert all(p.get("description") for p in schema.values())
    assert all(p.get("description") for p in HttpCameraSettings.model_json_schema()["properties"].values())


# -- HTTP snapshots ------------------------------------------------------------------------------------
class _Snapshots(BaseHTTPRequestHandler):
    plan: list[str] = []  # what to answer, one item per request: "jpeg", "500", "junk", "held"
    seen_auth: list[str | None] = []
    counter = 0
    requests = 0
    holding = threading.Event()  # set while a "held" request waits for `release`
    release = threading.Event()

    def do_GET(self) -> None:  # noqa: N802 - the http.server API
        cls = type(self)
        cls.requests += 1
        cls.seen_auth.append(self.headers.get("Authorization"))
        mode = cls.plan.pop(0) if cls.plan else "jpeg"
        if mode == "held":  # a camera that does not answer until the test lets it
            cls.holding.set()
            cls.release.wait(10.0)
            mode = "jpeg"
        if mode == "500":
            self.send_error(500, "sensor busy")
            return
        if mode == "junk":
            body = b"this is not a jpeg"
        else:
            cls.counter += 1
            image = np.full((30, 40, 3), cls.counter % 255, np.uint8)
            body = cv2.imencode(".jpg", image)[1].tobytes()
        self.send_response(200)
        self.send_header("Content-Type", "image/jpeg")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, *args: object) -> None:
        pass


@pytest.fixture
def http_camera_server():
    _Snapshots.plan, _Snapshots.seen_auth, _Snapshots.counter, _Snapshots.requests = [], [], 0, 0
    _Snapshots.holding.clear()
    _Snapshots.release.clear()
    server = ThreadingHTTPServer(("127.0.0.1", 0), _Snapshots)
    server.daemon_threads = True
    thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.02}, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}/axis-cgi/jpg/image.cgi"
    _Snapshots.release.set()
    server.shutdown()
    server.server_close()
    thread.join(timeout=2.0)


def test_http_snapshots_with_errors_counted(http_camera_server, devices):
    camera = devices(open_http_camera(url=http_camera_server, period=0.01, name="axis", username="op",
                                      password="pw"))
    frame = _wait_frame(camera)
    assert frame.image.shape == (30, 40, 3) and frame.camera_name == "axis"
    _Snapshots.plan[:] = ["500", "junk", "jpeg"]
    end = time.monotonic() + 2.0
    while camera.stats().failures < 2 and time.monotonic() < end:
        camera.grab()
        time.sleep(0.01)
    stats = camera.stats()
    assert stats.failures == 2 and camera.fault is None
    assert "not an image" in stats.last_error or "500" in stats.last_error
    assert _wait_frame(camera) is not None  # still delivering
    assert _Snapshots.seen_auth[0] == "Basic " + base64.b64encode(b"op:pw").decode()


def test_http_grab_never_waits_for_the_camera(http_camera_server, devices):
    """While the grab thread is stuck in a request the camera does not answer, grab() keeps returning
    (the newest frame once, then None) and never asks the camera itself."""
    camera = devices(open_http_camera(url=http_camera_server, period=0.01))
    _Snapshots.plan[:] = ["held"]
    assert _Snapshots.holding.wait(5.0)  # the grab thread is now inside a request that does not end
    requests, empty = _Snapshots.requests, camera.stats().empty_grabs
    results: list[object] = []
    caller = threading.Thread(target=lambda: results.extend(camera.grab() for _ in range(20)), daemon=True)
    caller.start()
    caller.join(10.0)  # only a hang detector: if grab() waited for the camera it would never come back
    assert not caller.is_alive() and len(results) == 20
    assert _Snapshots.holding.is_set() and not _Snapshots.release.is_set()  # still stuck all along
    assert results[1:] == [None] * 19 and camera.stats().empty_grabs >= empty + 19
    assert _Snapshots.requests == requests  # grab() sent no request of its own
    _Snapshots.release.set()
    assert _wait_frame(camera) is not None  # the answer, when it comes, is delivered


def test_http_camera_that_never_answers(http_camera_server):
    _Snapshots.plan[:] = ["500"] * 100
    with pytest.raises(CameraError, match="gave no frame within 0.2 s: HTTP 500"):
        open_http_camera(url=http_camera_server, period=0.02, timeout=0.2)
    with pytest.raises(CameraError):
        open_http_camera(url="http://127.0.0.1:9/snap.jpg", timeout=0.2)
    with pytest.raises(InputError, match="url"):
        open_http_camera(url="ftp://camera/snap.jpg")
