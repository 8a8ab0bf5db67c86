"""Chessboard calibration of a pinhole camera with OpenCV (images in, camera model out).

The images are numpy arrays already loaded by the caller (the ``bearings calibrate`` command);
this module does no I/O. Corners are found with ``cv2.findChessboardCorners``, refined to
sub-pixel accuracy with ``cv2.cornerSubPix`` and fed to ``cv2.calibrateCamera``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from perception.camera import PinholeCamera

_SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 1e-3)


@dataclass(frozen=True, slots=True)
class CalibrationResult:
    """A calibrated camera and how well it explains the views it came from.

    ``rms`` is OpenCV's RMS reprojection error over all corners (px); ``per_view_errors`` the RMS
    error of each used view, in the order of ``used`` (indices into the input images);
    ``rejected`` lists the indices of images where the board was not found (or of another size).
    """

    camera: PinholeCamera
    rms: float
    per_view_errors: tuple[float, ...]
    used: tuple[int, ...]
    rejected: tuple[int, ...]

    @property
    def images_used(self) -> int:
        return len(self.used)

    @property
    def images_rejected(self) -> int:
        return len(self.rejected)


def board_points(columns: int, rows: int, square: float) -> np.ndarray:
    """Inner-corner positions of a ``columns`` x ``rows`` board on its own plane (z = 0), in m."""
    grid = np.mgrid[0:columns, 0:rows].T.reshape(-1, 2)
    return np.column_stack((grid * square, np.zeros(len(grid)))).astype(np.float32)


def find_corners(image: np.ndarray, columns: int, rows: int) -> np.ndarray | None:
    """Sub-pixel inner corners (N x 2 float32) of the board in ``image``, or None if not found."""
    gray = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    found, corners = cv2.findChessboardCorners(gray, (columns, rows), flags=flags)
    if not found:
        return None
    corners = cv2.cornerSubPix(gray, corners, (11, 11), (-1, -1), _SUBPIX_CRITERIA)
    return corners.reshape(-1, 2)


def calibrate_chessboard(
    images: Sequence[np.ndarray],
    columns: int,
    rows: int,
    square: float,
    *,
    fix_aspect_ratio: bool = False,
    min_views: int = 3,
) -> CalibrationResult:
    """Calibrate a pinhole camera (5 distortion coefficients) from chessboard views.

    ``columns`` x ``rows`` counts INNER corners (a "9x6" board). All images must have the size
    of the first one. Raises ``ValueError`` when fewer than ``min_views`` views show the board.
    """
    if columns < 2 or rows < 2:
        raise ValueError(f"a board needs at least 2x2 inner corners, got {columns}x{rows}")
    if not square > 0:
        raise ValueError(f"square size must be positive, got {square}")
    if not images:
        raise ValueError("no images given")
    height, width = images[0].shape[:2]
    pattern = board_points(columns, rows, square)
    object_points, image_points, used, rejected = [], [], [], []
    for index, image in enumerate(images):
        corners = None if image.shape[:2] != (height, width) else find_corners(image, columns, rows)
        if corners is None:
            rejected.append(index)
            continue
        object_points.append(pattern)
        image_points.append(corners.reshape(-1, 1, 2))
        used.append(index)
    if len(used) < min_views:
        raise ValueError(
            f"the {columns}x{rows} board was found in {len(used)} of {len(images)} images; "
            f"need at least {min_views}"
        )
    flags = cv2.CALIB_FIX_ASPECT_RATIO if fix_aspect_ratio else 0
    camera_matrix = np.eye(3)  # with FIX_ASPECT_RATIO, OpenCV keeps fx/fy of the initial guess (1)
    rms, K, dist, rvecs, tvecs, _, _, per_view = cv2.calibrateCameraExtended(
        object_points, image_points, (width, height), camera_matrix, None, flags=flags
    )
    camera = PinholeCamera(
        width=int(width),
        height=int(height),
        fx=float(K[0, 0]),
        fy=float(K[1, 1]),
        cx=float(K[0, 2]),
        cy=float(K[1, 2]),
        dist=tuple(float(d) for d in np.ravel(dist)[:5]),
    )
    return CalibrationResult(
        camera=camera,
        rms=float(rms),
        per_view_errors=tuple(float(e) for e in np.ravel(per_view)),
        used=tuple(used),
        rejected=tuple(rejected),
    )
