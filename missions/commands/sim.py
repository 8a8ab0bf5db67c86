"""``bearings sim``: render what the simulated robot would see, and list the shipped worlds.

``bearings sim snapshot`` is how a user makes target images for missions in the simulator. Bad
input prints a message on stderr and exits 2, never a traceback.
"""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

import cv2
import numpy as np

from maps.located import validate
from maps.store import InputError, write_bytes_atomic
from missions.commands.common import EXIT_INVALID, EXIT_OK, fail, parse_pose, print_input_error
from missions.model import RunArguments

SNAPSHOT_DESCRIPTION = """Render the image a simulated camera sees with the robot at a given TRUE pose, and
write it as an image file (PNG, or any format OpenCV writes, chosen by the file extension). A stereo
camera writes its left and right images side by side. Pan-tilt mounted cameras look straight ahead
unless --pan/--tilt are given."""

SNAPSHOT_EPILOG = """poses:
  --pose 2.5,1.0,90deg    x, y in metres, heading in radians, or in degrees with a 'deg' suffix
  --pose door             a named pose of the world ('start' is always there)
  --pose=-1.5,2,0         a pose that starts with a minus sign needs the '=' form

examples:
  bearings sim snapshot --world lab --pose 4,3,0 -o target.png
  bearings sim snapshot --world my_world.yaml --pose door --camera front --tilt 10 -o door.png

exit codes: 0 written, 2 invalid input (unknown world or camera, bad pose, unwritable file)."""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "sim",
        help="simulator tools: render snapshots, list worlds",
        description="Tools for the built-in simulator.",
    )
    sub = parser.add_subparsers(dest="sim_command", metavar="SUBCOMMAND")
    snap = sub.add_parser(
        "snapshot",
        help="render what a simulated camera sees at a pose",
        description=SNAPSHOT_DESCRIPTION,
        epilog=SNAPSHOT_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    snap.add_argument("--world", required=True, metavar="W", help="a shipped world name (see 'bearings sim worlds') "
                      "or a world YAML file")  # fmt: skip
    snap.add_argument("--pose", required=True, metavar="X,Y,THETA", help="robot pose: x,y,theta or a named pose")
    snap.add_argument("--camera", default="panorama", metavar="C", help="camera name (default: %(default)s)")
    snap.add_argument("--seed", type=int, default=0, metavar="N", help="simulation seed (lighting) (default: 0)")
    snap.add_argument("--pan", type=float, default=0.0, metavar="DEG", help="pan angle of the pan-tilt unit, degrees")
    snap.add_argument("--tilt", type=float, default=0.0, metavar="DEG", help="tilt angle of the pan-tilt unit, degrees")
    snap.add_argument("-o", "--output", required=True, metavar="FILE", help="image file to write (atomically)")
    snap.set_defaults(func=run_snapshot)
    worlds = sub.add_parser(
        "worlds",
        help="list the shipped worlds",
        description="List the worlds shipped with bearings, with their cameras and named poses.",
    )
    worlds.set_defaults(func=run_worlds)
    parser.set_defaults(func=lambda args: _help(parser))


def _help(parser: argparse.ArgumentParser) -> int:
    parser.print_help()
    return EXIT_INVALID



def run_snapshot(args: argparse.Namespace) -> int:
    from drivers.sim.simulation import Simulation

    try:
        validate(RunArguments, {"--seed": args.seed}, file="command line")  # the same range as 'run --seed'
        sim = Simulation.load(args.world, seed=args.seed)
    except InputError as exc:
        return print_input_error(exc)
    named = {"start": sim.world.start, **sim.world.poses}
    try:
        pose = parse_pose(args.pose, named, option="--pose")
    except ValueError as exc:
        return fail("sim", str(exc))
    if args.camera not in sim.cameras:
        return fail("sim", f"no camera {args.camera!r} in world {sim.name!r} (cameras: {', '.join(sim.cameras)})")
    camera = sim.cameras[args.camera]
    if not camera.is_image:
        images = [n for n, c in sim.cameras.items() if c.is_image]
        return fail("sim", f"camera {args.camera!r} is a bearings sensor and makes no image (image cameras: "
                     f"{', '.join(images)})")  # fmt: skip
    if not (math.isfinite(args.pan) and math.isfinite(args.tilt)):
        return fail("sim", "--pan and --tilt must be finite")
    frame = sim.snapshot(pose, args.camera, pan=math.radians(args.pan), tilt=math.radians(args.tilt))
    image = frame.image if frame.right is None else np.hstack([frame.image, frame.right])
    suffix = Path(args.output).suffix.lower() or ".png"
    try:
        ok, encoded = cv2.imencode(suffix, image)
    except cv2.error:
        ok = False
    if not ok:
        return fail("sim", f"cannot encode an image as {suffix!r}: use .png (or another format OpenCV writes)")
    replacing = os.path.isfile(args.output)
    try:
        write_bytes_atomic(args.output, encoded.tobytes())
    except OSError as exc:
        return fail("sim", f"cannot write {args.output}: {exc.strerror or exc}")
    print(f"wrote {args.output} ({image.shape[1]} x {image.shape[0]}, camera {args.camera!r} of {sim.name!r})"
          + (", replaced the previous file" if replacing else ""))
    return EXIT_OK


def run_worlds(args: argparse.Namespace) -> int:
    from drivers.sim.world import load_world, shipped_worlds

    for name, path in shipped_worlds().items():
        try:
            world = load_world(name)
        except InputError as exc:  # a broken shipped world is a bug: say so, keep listing
            print(f"{name}: invalid ({exc.diagnostics[0]})")
            continue
        description = ""
        try:
            from maps.store import load_yaml

            description = str(load_yaml(path).get("description", ""))
        except InputError:
            pass
        cameras = ", ".join(f"{s.name} ({s.kind})" for s in world.cameras)
        poses = ", ".join(["start", *world.poses])
        print(f"{name}: {description}")
        print(f"    cameras: {cameras}")
        print(f"    poses: {poses}")
    return EXIT_OK
