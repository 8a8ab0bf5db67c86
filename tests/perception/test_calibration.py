"""Chessboard calibration on the real OpenCV sample photographs (tests/data/chessboard)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from maps.store import load_yaml
from missions.cli import main
from perception.calibration import (
    board_points,
    calibrate_chessboard,
    check_board,
    check_square,
    distinct_views,
    find_corners,
)
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
        (["--square", "-1"], "--square must be 0.0001 to 1 m"),
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


# --- views that add no information (issue 10, section 3) -----------------------------------------

K_SYNTHETIC = np.array([[500.0, 0.0, 320.0], [0.0, 500.0, 240.0], [0.0, 0.0, 1.0]])


def render_board(rotvec_deg, position, columns=9, rows=6, square=0.025) -> np.ndarray:
    """A 640 x 480 photograph of a ``columns`` x ``rows`` (inner corners) board by ``K_SYNTHETIC``:
    the board's centre at ``position`` (m, camera frame), turned by ``rotvec_deg`` from facing it."""
    ppm = 4000.0  # pixels per metre of the flat board image
    margin = square  # the white border findChessboardCorners needs
    w, h = (columns + 1) * square + 2 * margin, (rows + 1) * square + 2 * margin
    board = np.full((int(h * ppm), int(w * ppm)), 255, np.uint8)
    side = int(square * ppm)
    for i in range(columns + 1):
        for j in range(rows + 1):
            if (i + j) % 2 == 0:
                x0, y0 = int((margin + i * square) * ppm), int((margin + j * square) * ppm)
                board[y0 : y0 + side, x0 : x0 + side] = 0
    R = Rotation.from_rotvec(np.radians(rotvec_deg)).as_matrix()
    to_metres = np.array([[1 / ppm, 0, -w / 2], [0, 1 / ppm, -h / 2], [0, 0, 1]])
    H = K_SYNTHETIC @ np.column_stack((R[:, 0], R[:, 1], position)) @ to_metres
    return cv2.warpPerspective(board, H, (640, 480), flags=cv2.INTER_AREA, borderValue=200)


def test_one_photograph_three_times_is_refused(images):
    # it used to "succeed" with fx 943 (the sample camera has 536)
    with pytest.raises(ValueError, match=r"found in 3 images but in only 1 distinct pose \(a repeats a, a repeats a\)"):
        calibrate_chessboard([images[0]] * 3, 9, 6, 0.025, names=["a", "a", "a"])


def test_a_repeated_view_is_dropped_reported_and_changes_nothing(images):
    clean = calibrate_chessboard(images[:4], 9, 6, 0.025)
    result = calibrate_chessboard([images[0], *images[:4]], 9, 6, 0.025)
    assert result.repeated == ((1, 0),) and result.used == (0, 2, 3, 4) and result.rejected == ()
    # calibrated again without it: as if it was never given, up to where OpenCV's solver stops (two
    # runs of the same call on CI differed by 1.6e-7 in k2; a view counted twice moves far more)
    a, b = result.camera, clean.camera
    assert np.allclose([a.fx, a.fy, a.cx, a.cy, *a.dist], [b.fx, b.fy, b.cx, b.cy, *b.dist], rtol=1e-5, atol=1e-6)
    assert np.allclose(result.per_view_errors, clean.per_view_errors, rtol=1e-4)


def test_a_near_identical_view_is_refused(images):
    # the same board pose photographed again with the camera nudged by a pixel and a half
    nudged = cv2.warpAffine(images[0], np.float32([[1, 0, 1.5], [0, 1, -1.0]]), (640, 480),
                            borderMode=cv2.BORDER_REPLICATE)
    result = calibrate_chessboard([images[0], nudged, *images[1:4]], 9, 6, 0.025)
    assert result.repeated == ((1, 0),) and 1 not in result.used


def test_the_sample_photographs_all_add_information(images):
    result = calibrate_chessboard(images, 9, 6, 0.025)
    assert result.repeated == () and len(result.per_view_errors) == len(result.used) == 13


def test_parallel_boards_are_refused_tilted_ones_calibrate():
    tilted = [
        render_board(r, np.array(t))
        for r, t in [((0, 0, 0), (0, 0, 0.6)), ((25, 0, 0), (0.02, 0, 0.6)), ((0, 30, 0), (0, 0.03, 0.55)),
                     ((-20, 15, 5), (-0.03, 0, 0.65)), ((10, -25, 0), (0, -0.02, 0.6))]
    ]
    result = calibrate_chessboard(tilted, 9, 6, 0.025)
    assert result.used == (0, 1, 2, 3, 4)
    assert result.camera.fx == pytest.approx(500.0, rel=0.02) and result.camera.fy == pytest.approx(500.0, rel=0.02)
    # the same tilt everywhere, the board moved around: the old code said fx 975, fy 1176
    parallel = [render_board((20, 0, 0), np.array(t))
                for t in [(0, 0, 0.6), (0.08, 0, 0.6), (-0.08, 0.04, 0.6), (0, -0.05, 0.7), (0.05, 0.05, 0.5)]]
    with pytest.raises(ValueError, match="all 5 views show the board at the same tilt"):
        calibrate_chessboard(parallel, 9, 6, 0.025)


def test_distinct_views_ignores_a_turn_within_the_board_plane():
    normals = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.0, np.sin(0.1), np.cos(0.1)], [0.0, 0.0, 1.0]])
    centres = np.array([[0.0, 0.0, 1.0], [0.005, 0.0, 1.0], [0.0, 0.0, 1.0], [0.1, 0.0, 1.0]])
    kept, repeats = distinct_views(normals, centres)
    # 1: same plane (the corner order flipped the normal), 5 mm away at 1 m: a repeat of 0;
    # 2: tilted by 5.7 deg; 3: moved by 10 cm: both add information
    assert kept == [0, 2, 3] and repeats == [(1, 0)]


@pytest.mark.parametrize(("columns", "rows"), [(99999, 99999), (2, 2), (9, 101), (0, 6)])
def test_board_size_is_bounded_before_anything_is_allocated(images, columns, rows):
    with pytest.raises(ValueError, match="3 to 100 inner corners per side"):
        check_board(columns, rows)
    with pytest.raises(ValueError, match="3 to 100 inner corners per side"):  # was MemoryError / cv2.error
        calibrate_chessboard(images[:3], columns, rows, 0.025)


@pytest.mark.parametrize("square", [float("inf"), float("nan"), 0.0, -0.025, 1e-9, 2.0])
def test_square_size_is_bounded(images, square):
    with pytest.raises(ValueError, match="side of a square must be 0.0001 to 1 m"):
        check_square(square)
    with pytest.raises(ValueError, match="side of a square"):  # inf was an OpenCV assertion
        calibrate_chessboard(images[:3], 9, 6, square)


def test_calibrate_command_refuses_one_photograph_three_times(tmp_path, capsys):
    out = tmp_path / "camera.yaml"
    first = str(IMAGES[0])
    assert main(["calibrate", first, first, first, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "in only 1 distinct pose" in err and f"{first} repeats {first}" in err
    assert not out.exists()


def test_calibrate_command_reports_repeats_and_per_view_errors(tmp_path, capsys):
    out = tmp_path / "camera.yaml"
    names = [str(IMAGES[0]), *map(str, IMAGES[:4])]
    assert main(["calibrate", *names, "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "4 of 5 images (0 rejected, 1 repeating a pose)" in printed
    assert f"refused (same board pose as {names[0]}, adds no information): {names[1]}" in printed
    for name in names[1:]:
        assert sum(line.endswith(name) or line.endswith(f"{name}  (worst)") for line in printed.splitlines()) >= 1
    block = dict(load_yaml(out))["calibration"]
    assert block["images_used"] == names[1:] and len(block["per_view_rms_px"]) == 4
    assert all(0 < e < 2 for e in block["per_view_rms_px"])
    assert block["images_repeated"] == [{"image": names[1], "same_pose_as": names[0]}]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--board", "99999x99999"], "--board must have 3 to 100 inner corners per side, got '99999x99999'"),
        (["--board", "2x2"], "--board must have 3 to 100 inner corners per side"),
        (["--board", "1" + "0" * 5000 + "x3"], "--board must have 3 to 100"),  # no 5000-digit int
        (["--square", "inf"], "--square must be 0.0001 to 1 m (the side of one square), got inf"),
        (["--square", "nan"], "--square must be 0.0001 to 1 m"),
        (["--square", "1e-9"], "--square must be 0.0001 to 1 m"),
        (["--square", "5"], "--square must be 0.0001 to 1 m"),
    ],
)
def test_calibrate_command_bounds_board_and_square(tmp_path, capsys, args, message):
    out = tmp_path / "camera.yaml"
    code = main(["calibrate", *map(str, IMAGES[:3]), *args, "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err
    assert err.count("\n") == 1 and len(err) < 200  # one short line, naming the option
    assert not out.exists()
