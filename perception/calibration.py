"""Chessboard calibration of a pinhole camera with OpenCV (images in, camera model out).

The images are numpy arrays already loaded by the caller (the ``bearings calibrate`` command);
this module does no I/O. Corners are found with ``cv2.findChessboardCorners``, refined to
sub-pixel accuracy with ``cv2.cornerSubPix`` and fed to ``cv2.calibrateCamera``.

Only views that add information are used. A view that shows the board in (nearly) the same
place and facing (nearly) the same way as an earlier view -- the same photograph twice, or two
shots from a tripod -- gives the same constraints on the intrinsics (Zhang 2000, section 3.3:
the constraints come from the board's plane, so even turning the board within its plane adds
nothing); it is refused and reported, and the camera is calibrated again without it. Views whose
boards are all parallel are the other degenerate set (the focal length trades off against the
board's distance), refused as a whole. Board size and square size are bounded before anything is
allocated.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import cv2
import numpy as np

from perception.camera import PinholeCamera

_SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 1e-3)
BOARD_CORNERS = (3, 100)  # inner corners per side: OpenCV's detector needs 3; 100 is a 101-square board
SQUARE_M = (1e-4, 1.0)  # side of a square in metres: 0.1 mm (printed micro-targets) to 1 m
SAME_POSE_DEG = 2.0  # boards whose planes differ by less than this, ...
SAME_POSE_SHIFT = 0.02  # ... and whose centres by less than this fraction of their distance, repeat a view
MIN_TILT_DEG = 5.0  # the views' boards must differ in orientation by at least this much
MIN_SQUARE_PX = 4  # a board square narrower than this in the image cannot be detected (OpenCV asserts below)


@dataclass(frozen=True, slots=True)
class CalibrationResult:
    """A calibrated camera and how well it explains the views it came from.

    ``rms`` is OpenCV's RMS reprojection error over all corners (px); ``per_view_errors`` the RMS
    error of each used view, in the order of ``used`` (indices into the input images);
    ``rejected`` lists the indices of images where the board was not found (or of another size);
    ``repeated`` pairs ``(index, earlier_index)`` of views refused because they show the board
    in nearly the same pose as an earlier used view (see the module docstring).
    """

    camera: PinholeCamera
    rms: float
    per_view_errors: tuple[float, ...]
    used: tuple[int, ...]
    rejected: tuple[int, ...]
    repeated: tuple[tuple[int, int], ...] = ()

    @property
    def images_used(self) -> int:
        return len(self.used)

    @property
    def images_rejected(self) -> int:
        return len(self.rejected)


def check_board(columns: int, rows: int) -> None:
    """Raise ``ValueError`` unless the board has ``BOARD_CORNERS`` inner corners per side."""
    low, high = BOARD_CORNERS
    if not (low <= columns <= high and low <= rows <= high):
        raise ValueError(f"a board has {low} to {high} inner corners per side, got {columns}x{rows}")


def check_square(square: float) -> None:
    """Raise ``ValueError`` unless the square side is a finite length within ``SQUARE_M``."""
    low, high = SQUARE_M
    if not (math.isfinite(square) and low <= square <= high):
        raise ValueError(f"the side of a square must be {low:g} to {high:g} m, got {square}")


def check_image_size(width: int, height: int, columns: int, rows: int) -> None:
    """Raise ``ValueError`` when images this small cannot show the board (``MIN_SQUARE_PX`` per
    square, in either orientation): OpenCV's detector fails on an assertion there, not a result."""
    short, long = sorted((columns + 1, rows + 1))
    need = (MIN_SQUARE_PX * short, MIN_SQUARE_PX * long)
    if min(width, height) < need[0] or max(width, height) < need[1]:
        raise ValueError(f"the images are {width}x{height} pixels: too small to show a {columns}x{rows} board "
                         f"(at least {need[1]}x{need[0]}, {MIN_SQUARE_PX} pixels per square)")


def board_points(columns: int, rows: int, square: float) -> np.ndarray:
    """Inner-corner positions of a ``columns`` x ``rows`` board on its own plane (z = 0), in m."""
    grid = np.mgrid[0:columns, 0:rows].T.reshape(-1, 2)
    return np.column_stack((grid * square, np.zeros(len(grid)))).astype(np.float32)


def find_corners(image: np.ndarray, columns: int, rows: int) -> np.ndarray | None:
    """Sub-pixel inner corners (N x 2 float32) of the board in ``image``, or None if not found."""
    gray = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    try:
        found, corners = cv2.findChessboardCorners(gray, (columns, rows), flags=flags)
        if not found:
            return None
        corners = cv2.cornerSubPix(gray, corners, (11, 11), (-1, -1), _SUBPIX_CRITERIA)
    except cv2.error:  # an image OpenCV cannot search (too small, degenerate): the board is not in it
        return None
    return corners.reshape(-1, 2)


def calibrate_chessboard(
    images: Sequence[np.ndarray],
    columns: int,
    rows: int,
    square: float,
    *,
    fix_aspect_ratio: bool = False,
    min_views: int = 3,
    names: Sequence[str] | None = None,
) -> CalibrationResult:
    """Calibrate a pinhole camera (5 distortion coefficients) from chessboard views.

    ``columns`` x ``rows`` counts INNER corners (a "9x6" board). All images must have the size
    of the first one. Raises ``ValueError`` (one line) on a board or square size out of range,
    when fewer than ``min_views`` views show the board in distinct poses, when all boards are
    parallel, or when OpenCV cannot calibrate from the views. ``names`` label the images in
    those messages (default: "image 0", "image 1", ...).
    """
    check_board(columns, rows)
    check_square(square)
    if not images:
        raise ValueError("no images given")
    height, width = images[0].shape[:2]
    check_image_size(width, height, columns, rows)
    corners, rejected = _detect_all(images, columns, rows)
    found = sorted(corners)
    if len(found) < min_views:
        raise ValueError(
            f"the {columns}x{rows} board was found in {len(found)} of {len(images)} images; "
            f"need at least {min_views}"
        )
    pattern = board_points(columns, rows, square)
    views = [corners[i] for i in found]
    fit = _calibrate(pattern, views, (width, height), fix_aspect_ratio)
    normals, centres = _board_poses(fit, pattern)
    kept, repeats = distinct_views(normals, centres)
    repeated = tuple((found[j], found[i]) for j, i in repeats)
    if len(kept) < min_views:
        label = (lambda k: str(names[k])) if names is not None else (lambda k: f"image {k}")
        pairs = ", ".join(f"{label(j)} repeats {label(i)}" for j, i in repeated)
        raise ValueError(
            f"the board was found in {len(found)} images but in only {len(kept)} distinct "
            f"pose{'s' if len(kept) != 1 else ''} ({pairs}); need at least {min_views}: "
            "move and tilt the board between photographs"
        )
    if repeats:  # calibrate again on the views that add information
        fit = _calibrate(pattern, [views[k] for k in kept], (width, height), fix_aspect_ratio)
        normals, centres = _board_poses(fit, pattern)
    tilt = _largest_angle_deg(normals)
    if tilt < MIN_TILT_DEG:
        raise ValueError(
            f"all {len(kept)} views show the board at the same tilt (within {tilt:.1f} deg, need "
            f"{MIN_TILT_DEG:g}): the focal length cannot be told from the distance; tilt the board"
        )
    K = fit.K
    camera = PinholeCamera(
        width=int(width),
        height=int(height),
        fx=float(K[0, 0]),
        fy=float(K[1, 1]),
        cx=float(K[0, 2]),
        cy=float(K[1, 2]),
        dist=tuple(float(d) for d in np.ravel(fit.dist)[:5]),
    )
    return CalibrationResult(
        camera=camera,
        rms=fit.rms,
        per_view_errors=tuple(float(e) for e in np.ravel(fit.per_view)),
        used=tuple(found[k] for k in kept),
        rejected=tuple(rejected),
        repeated=repeated,
    )


def _detect_all(images: Sequence[np.ndarray], columns: int, rows: int) -> tuple[dict[int, np.ndarray], list[int]]:
    """Corners per image index where the board was found (images of the first one's size only)."""
    size = images[0].shape[:2]
    corners, rejected = {}, []
    for index, image in enumerate(images):
        found = None if image.shape[:2] != size else find_corners(image, columns, rows)
        if found is None:
            rejected.append(index)
        else:
            corners[index] = found
    return corners, rejected


class _Fit(NamedTuple):
    rms: float
    K: np.ndarray
    dist: np.ndarray
    rvecs: Sequence[np.ndarray]
    tvecs: Sequence[np.ndarray]
    per_view: np.ndarray  # RMS reprojection error of each view (px)


def _calibrate(pattern: np.ndarray, views: list[np.ndarray], size: tuple[int, int], fix_aspect_ratio: bool) -> _Fit:
    """``cv2.calibrateCameraExtended`` on the views; an OpenCV failure is a one-line ValueError."""
    flags = cv2.CALIB_FIX_ASPECT_RATIO if fix_aspect_ratio else 0
    camera_matrix = np.eye(3)  # with FIX_ASPECT_RATIO, OpenCV keeps fx/fy of the initial guess (1)
    try:
        rms, K, dist, rvecs, tvecs, _, _, per_view = cv2.calibrateCameraExtended(
            [pattern] * len(views), [v.reshape(-1, 1, 2) for v in views], size, camera_matrix, None, flags=flags
        )
    except cv2.error as exc:
        reason = str(exc).strip().splitlines()[-1]
        raise ValueError(f"OpenCV could not calibrate from these views: {reason}") from None
    return _Fit(float(rms), K, dist, rvecs, tvecs, per_view)


def _board_poses(fit: _Fit, pattern: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals of the boards' planes and positions of the boards' centres (camera frame)."""
    rvecs, tvecs = fit.rvecs, fit.tvecs
    centre = pattern.mean(axis=0).astype(np.float64)
    rotations = [cv2.Rodrigues(np.asarray(r, dtype=np.float64))[0] for r in rvecs]
    normals = np.array([R[:, 2] for R in rotations])
    centres = np.array([R @ centre + np.ravel(t) for R, t in zip(rotations, tvecs, strict=True)])
    return normals, centres


def distinct_views(
    normals: np.ndarray,
    centres: np.ndarray,
    *,
    max_angle_deg: float = SAME_POSE_DEG,
    max_shift: float = SAME_POSE_SHIFT,
) -> tuple[list[int], list[tuple[int, int]]]:
    """Views in order, each kept unless it repeats an earlier kept one: its board's plane within
    ``max_angle_deg`` of that view's and its centre within ``max_shift`` times the distance.

    Returns ``(kept, repeats)`` with ``repeats`` as ``(index, index of the view it repeats)``. The
    comparison ignores a turn of the board within its plane (and so OpenCV's corner order, which
    may start from either end of a board).
    """
    kept: list[int] = []
    repeats: list[tuple[int, int]] = []
    cos_max = math.cos(math.radians(max_angle_deg))
    for j in range(len(normals)):
        for i in kept:
            same_plane = abs(float(normals[i] @ normals[j])) > cos_max
            distance = max(float(np.linalg.norm(centres[i])), float(np.linalg.norm(centres[j])), 1e-12)
            if same_plane and np.linalg.norm(centres[i] - centres[j]) < max_shift * distance:
                repeats.append((j, i))
                break
        else:
            kept.append(j)
    return kept, repeats


def _largest_angle_deg(normals: np.ndarray) -> float:
    """Largest angle (deg) between the planes of any two boards."""
    cosines = np.clip(np.abs(normals @ normals.T), 0.0, 1.0)
    return float(np.degrees(np.arccos(cosines.min())))
