"""``bearings calibrate``: calibrate a pinhole camera from chessboard photographs.

Reads the images with ``cv2.imread``, calibrates with :mod:`perception.calibration` and writes
the camera YAML (``perception.camera.camera_from_dict`` reads it back) atomically through
``maps.store``. Bad input prints a message on stderr and exits 2, never a traceback.
"""

from __future__ import annotations

import argparse
import os
import re
from pathlib import Path

import cv2

from maps.store import write_yaml
from missions.commands.common import fail, same_as_input
from perception.calibration import (
    BOARD_CORNERS,
    SQUARE_M,
    CalibrationResult,
    calibrate_chessboard,
    check_square,
)

DESCRIPTION = """Calibrate a pinhole camera (focal lengths, principal point and 5 OpenCV distortion
coefficients k1 k2 p1 p2 k3) from photographs of a flat chessboard, and write the camera model as
YAML for a robot profile. Take 10-20 sharp photographs with the board filling different parts of
the image at different tilts; images where the board is not found are skipped and reported, and so
are photographs that repeat an earlier one's board pose (they add no information). The error of
each photograph used is printed and written to the YAML."""

EPILOG = """example:
  bearings calibrate shots/*.jpg --board 9x6 --square 0.025 -o camera.yaml

exit codes: 0 calibrated, 2 invalid input (unreadable image, board not found in enough images or
not in enough distinct poses, all boards parallel, bad option values)."""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "calibrate",
        help="calibrate a camera from chessboard photographs",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("images", nargs="+", metavar="IMAGES", help="chessboard photographs (any format OpenCV reads)")
    parser.add_argument(
        "--board",
        default="9x6",
        metavar="COLSxROWS",
        help="number of INNER corners along the board's two sides, e.g. 9x6 for a 10 x 7 squares board; "
        f"{BOARD_CORNERS[0]} to {BOARD_CORNERS[1]} each (default: %(default)s)",
    )
    parser.add_argument(
        "--square",
        type=float,
        default=0.025,
        metavar="METRES",
        help=f"side of one chessboard square in metres ({SQUARE_M[0]:g} to {SQUARE_M[1]:g}); sets the scale "
        "of the board poses, not the intrinsics (default: %(default)s)",
    )
    parser.add_argument(
        "--fix-aspect",
        action="store_true",
        help="force fx = fy (square pixels), as OpenCV's calibration sample does",
    )
    parser.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="FILE",
        help="camera YAML to write (replaced atomically)",
    )
    parser.set_defaults(func=run)



def parse_board(text: str) -> tuple[int, int]:
    """``"9x6"`` to ``(9, 6)``; ``ValueError`` (naming ``--board``) unless both sides are in range."""
    shown = repr(text) if len(text) <= 40 else repr(text[:40]) + "..."
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not match:
        raise ValueError(f"--board must look like 9x6 (inner corners), got {shown}")
    low, high = BOARD_CORNERS
    sides = [int(side) if len(side) <= 6 else high + 1 for side in match.groups()]  # no 5000-digit ints
    if not all(low <= side <= high for side in sides):
        raise ValueError(f"--board must have {low} to {high} inner corners per side, got {shown}")
    return sides[0], sides[1]


def run(args: argparse.Namespace) -> int:
    try:
        columns, rows = parse_board(args.board)
    except ValueError as exc:
        return fail("calibrate", str(exc))
    try:
        check_square(args.square)
    except ValueError:
        low, high = SQUARE_M
        return fail("calibrate", f"--square must be {low:g} to {high:g} m (the side of one square), got {args.square}")
    problem = same_as_input(args.output, args.images)
    if problem:
        return fail("calibrate", f"cannot write {args.output}: {problem}")
    images = []
    for name in args.images:
        if not Path(name).is_file():
            return fail("calibrate", f"{name}: no such file")
        image = cv2.imread(name, cv2.IMREAD_GRAYSCALE)
        if image is None:
            return fail("calibrate", f"{name}: not an image OpenCV can read")
        images.append(image)
    sizes = {image.shape for image in images}
    if len(sizes) > 1:
        found = ", ".join(f"{w}x{h}" for h, w in sorted(sizes))
        return fail("calibrate", f"all images must have the same size, got {found}")
    try:
        result = calibrate_chessboard(
            images, columns, rows, args.square, fix_aspect_ratio=args.fix_aspect, names=args.images
        )
    except ValueError as exc:
        return fail("calibrate", str(exc))
    names = args.images
    data = {
        **result.camera.to_dict(),
        "calibration": {
            "board": f"{columns}x{rows}",
            "square_m": float(args.square),
            "rms_px": round(result.rms, 4),
            "images_used": [names[i] for i in result.used],
            "per_view_rms_px": [round(e, 4) for e in result.per_view_errors],  # in the order of images_used
            "images_rejected": [names[i] for i in result.rejected],
            "images_repeated": [{"image": names[j], "same_pose_as": names[i]} for j, i in result.repeated],
        },
    }
    replacing = os.path.isfile(args.output)
    try:
        write_yaml(args.output, data, header="camera calibration written by 'bearings calibrate'")
    except OSError as exc:
        return fail("calibrate", f"{args.output}: cannot write: {exc.strerror or exc}")
    _print_summary(result, names, len(images))
    print(f"wrote {args.output}" + (" (replaced the previous file)" if replacing else ""))
    return 0


def _print_summary(result: CalibrationResult, names: list[str], count: int) -> None:
    cam = result.camera
    print(
        f"calibrated from {result.images_used} of {count} images ({result.images_rejected} rejected, "
        f"{len(result.repeated)} repeating a pose)"
    )
    for i in result.rejected:
        print(f"  rejected (board not found): {names[i]}")
    for j, i in result.repeated:
        print(f"  refused (same board pose as {names[i]}, adds no information): {names[j]}")
    print(f"fx {cam.fx:.2f}  fy {cam.fy:.2f}  cx {cam.cx:.2f}  cy {cam.cy:.2f} px")
    print("dist " + " ".join(f"{d:.5f}" for d in cam.dist))
    print(f"reprojection error: rms {result.rms:.3f} px; per view:")
    worst = max(result.per_view_errors)
    for index, error in zip(result.used, result.per_view_errors, strict=True):
        print(f"  {error:7.3f} px  {names[index]}{'  (worst)' if error == worst else ''}")
