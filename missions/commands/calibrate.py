"""``bearings calibrate``: calibrate a pinhole camera from chessboard photographs.

Reads the images with ``cv2.imread``, calibrates with :mod:`perception.calibration` and writes
the camera YAML (``perception.camera.camera_from_dict`` reads it back) atomically through
``maps.store``. Bad input prints a message on stderr and exits 2, never a traceback.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import cv2

from maps.store import write_yaml
from missions.commands.common import fail
from perception.calibration import calibrate_chessboard

DESCRIPTION = """Calibrate a pinhole camera (focal lengths, principal point and 5 OpenCV distortion
coefficients k1 k2 p1 p2 k3) from photographs of a flat chessboard, and write the camera model as
YAML for a robot profile. Take 10-20 sharp photographs with the board filling different parts of
the image at different tilts; images where the board is not found are skipped and reported."""

EPILOG = """example:
  bearings calibrate shots/*.jpg --board 9x6 --square 0.025 -o camera.yaml

exit codes: 0 calibrated, 2 invalid input (unreadable image, board not found in enough images,
bad option values)."""


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
        help="number of INNER corners along the board's two sides, e.g. 9x6 for a 10 x 7 squares board "
        "(default: %(default)s)",
    )
    parser.add_argument(
        "--square",
        type=float,
        default=0.025,
        metavar="METRES",
        help="side of one chessboard square in metres; sets the scale of the board poses, not the "
        "intrinsics (default: %(default)s)",
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



def run(args: argparse.Namespace) -> int:
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", args.board)
    if not match:
        return fail("calibrate", f"--board must look like 9x6 (inner corners), got {args.board!r}")
    columns, rows = int(match.group(1)), int(match.group(2))
    if not args.square > 0:
        return fail("calibrate", f"--square must be a positive length in metres, got {args.square}")
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
        result = calibrate_chessboard(images, columns, rows, args.square, fix_aspect_ratio=args.fix_aspect)
    except ValueError as exc:
        return fail("calibrate", str(exc))
    data = {
        **result.camera.to_dict(),
        "calibration": {
            "board": f"{columns}x{rows}",
            "square_m": float(args.square),
            "rms_px": round(result.rms, 4),
            "images_used": [args.images[i] for i in result.used],
            "images_rejected": [args.images[i] for i in result.rejected],
        },
    }
    try:
        write_yaml(args.output, data, header="camera calibration written by 'bearings calibrate'")
    except OSError as exc:
        return fail("calibrate", f"{args.output}: cannot write: {exc.strerror or exc}")
    cam = result.camera
    print(f"calibrated from {result.images_used} of {len(images)} images ({result.images_rejected} rejected)")
    for i in result.rejected:
        print(f"  rejected (board not found): {args.images[i]}")
    print(f"fx {cam.fx:.2f}  fy {cam.fy:.2f}  cx {cam.cx:.2f}  cy {cam.cy:.2f} px")
    print("dist " + " ".join(f"{d:.5f}" for d in cam.dist))
    worst = max(range(len(result.used)), key=lambda k: result.per_view_errors[k])
    print(
        f"reprojection error: rms {result.rms:.3f} px, worst view {result.per_view_errors[worst]:.3f} px "
        f"({args.images[result.used[worst]]})"
    )
    print(f"wrote {args.output}")
    return 0
