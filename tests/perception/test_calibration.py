"""Chessboard calibration on the real OpenCV sample photographs (tests/data/chessboard)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from maps.store import load_yaml
from missions.cli import main
from perception.calibration import board_points, calibrate_chessboard, find_corners
from perception.camera import PinholeCamera, camera_from_dict

DATA = Path(__file__).resolve().parents[1] / "data" / "chessboard"
IMAGES = sorted(DATA.glob("left*.jpg"))


@pytest.fixture(scope="module")
def reference() -> np.ndarray:
    storage = cv2.FileStorage(str(DATA / "left_intrinsics.yml"), cv2.FILE_STORAGE_READ)
    K = storage.getNode("camera_matrix").mat()
    storage.release()
    return K


@pytest.fixture(scope="module")
def images() -> list[np.ndarray]:
    assert len(IMAGES) == 13
    return [cv2.imread(str(p), cv2.IMREAD_GRAYSCALE) for p in IMAGES]


@pytest.mark.parametrize("fix_aspect_ratio", [False, True])
def test_focal_length_matches_opencv_sample_within_one_percent(images, reference, fix_aspect_ratio):
    result = calibrate_chessboard(images, 9, 6, 0.025, fix_aspect_ratio=fix_aspect_ratio)
    cam = result.camera
    assert cam.fx == pytest.approx(reference[0, 0], rel=0.01)
    assert cam.fy == pytest.approx(reference[1, 1], rel=0.01)
    assert cam.cx == pytest.approx(reference[0, 2], abs=3.0)
    assert cam.cy == pytest.approx(reference[1, 2], abs=3.0)
    assert result.rms < 0.5
    assert result.images_used == 13 and result.images_rejected == 0
    assert len(result.per_view_errors) == 13 and max(result.per_view_errors) < 1.5
    if fix_aspect_ratio:
        assert cam.fx == cam.fy


def test_calibrated_model_reprojects_the_board(images):
    result = calibrate_chessboard(images, 9, 6, 0.025)
    cam = result.camera
    # the image corners of the first view, turned into bearings and back, stay put
    corners = find_corners(images[0], 9, 6)
    uv, valid = cam.bearing_to_pixel(cam.pixel_to_bearing(corners))
    assert valid.all() and np.abs(uv - corners).max() < 1e-6


def test_views_without_the_board_are_rejected_not_fatal(images):
    blank = np.full_like(images[0], 128)
    result = calibrate_chessboard([blank, *images[:5]], 9, 6, 0.025)
    assert result.rejected == (0,) and result.used == (1, 2, 3, 4, 5)
    with pytest.raises(ValueError, match="found in 0 of 2"):
        calibrate_chessboard([blank, blank], 9, 6, 0.025)
    with pytest.raises(ValueError, match="board was found in 0"):
        calibrate_chessboard(images[:3], 7, 5, 0.025)  # wrong board size: not found anywhere


def test_board_points_scale():
    pts = board_points(9, 6, 0.025)
    assert pts.shape == (54, 3) and pts[1, 0] == pytest.approx(0.025) and pts[9, 1] == pytest.approx(0.025)


def test_calibrate_command_writes_a_loadable_camera_yaml(tmp_path, capsys):
    out = tmp_path / "camera.yaml"
    code = main(["calibrate", *map(str, IMAGES), "--board", "9x6", "--square", "0.025", "-o", str(out)])
    assert code == 0
    camera = camera_from_dict(dict(load_yaml(out)))
    assert isinstance(camera, PinholeCamera) and camera.width == 640 and camera.height == 480
    assert camera.fx == pytest.approx(535.9, rel=0.01)
    printed = capsys.readouterr().out
    assert "13 of 13 images" in printed and "rms" in printed


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--board", "nine"], "--board must look like 9x6"),
        (["--square", "-1"], "--square must be a positive"),
        (["--board", "7x5"], "board was found in 0 of"),
    ],
)
def test_calibrate_command_rejects_bad_input_with_exit_2(tmp_path, capsys, args, message):
    out = tmp_path / "camera.yaml"
    code = main(["calibrate", *map(str, IMAGES[:3]), *args, "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err
    assert not out.exists()


def test_calibrate_command_unreadable_files(tmp_path, capsys):
    text = tmp_path / "notes.txt"
    text.write_text("not an image")
    assert main(["calibrate", str(text), "-o", str(tmp_path / "c.yaml")]) == 2
    assert "not an image" in capsys.readouterr().err
    assert main(["calibrate", str(tmp_path / "missing.jpg"), "-o", str(tmp_path / "c.yaml")]) == 2
    assert "no such file" in capsys.readouterr().err
