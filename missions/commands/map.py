"""``bearings map``: inspect and prune saved maps (LT-maps of taught routes, roadmaps).

``info`` prints what the tree holds (a roadmap's targets and edges: :mod:`missions.commands.map_roadmap`);
``prune`` cuts its lowest levels until it fits a memory
budget (LT-map paper: the first and last viewframe keep their landmarks, viewframes left with too
few landmarks go) and writes the result atomically. Bad input is one line on stderr and exit 2,
never a traceback; a budget the map cannot meet writes nothing.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
from pathlib import Path

import numpy as np

from maps.ltmap.file import load_ltmap, save_ltmap
from maps.ltmap.prune import DEFAULT_MIN_LANDMARKS
from maps.ltmap.tree import LandmarkTree
from maps.mapfile import read_map_file
from maps.roadmap import Roadmap
from maps.store import InputError, output_problem
from missions.commands.common import EXIT_INVALID, EXIT_OK, fail
from missions.commands.map_roadmap import draw_roadmap, print_roadmap, roadmap_info
from perception.similarity import angle_of_cost

UNITS = {"": 1, "b": 1, "kb": 10**3, "mb": 10**6, "gb": 10**9, "kib": 2**10, "mib": 2**20, "gib": 2**30}
MAX_BUDGET = 2**40  # 1 TiB: far above any map; a larger "budget" is a typo
_SIZE = re.compile(r"\s*(\d+(?:\.\d*)?|\.\d+)\s*([A-Za-z]*)\s*")

DESCRIPTION = """Inspect and prune saved maps.

  info   an LT-map: viewframes, landmarks, tree height, bytes, landmarks per tree level (root first);
         a roadmap: targets, edges with their motions and sigmas (--plot F.png draws them)
  prune  cut the lowest tree levels until the map fits a memory budget

Bytes are the map's content as stored: per landmark its descriptor (or id) and bearing, per
node and per viewframe a few indices (the file adds a header of a few hundred bytes)."""

PRUNE_EPILOG = """budget sizes: a number with an optional unit, B, KB, MB, GB (powers of 1000) or KiB, MiB, GiB
(powers of 1024), case-insensitive: 200KB, 1.5MiB, 50000.

Pruning cuts the lowest level of the tree (the landmarks seen from one place only): the first and
last viewframe keep theirs by moving them up, viewframes that end in the same node merge, and
viewframes left with fewer than --min-landmarks landmarks are deleted (never the first or last).
Levels are cut until the map fits; when even a one-level tree is too large, nothing is written.

examples:
  bearings map info route.ltmap
  bearings map prune route.ltmap --budget 200KB -o route-200k.ltmap

exit codes: 0 done, 2 invalid input (unreadable or damaged map, bad budget, budget too small)."""


def parse_byte_size(text: str) -> int:
    """``"200KB"`` -> 200000, ``"1.5 MiB"`` -> 1572864 (whole bytes, rounded down); ValueError otherwise."""
    match = _SIZE.fullmatch(text)
    if not match or match.group(2).lower() not in UNITS:
        raise ValueError(f"expected a size such as 200KB, 1.5MiB or 50000 (units: B, KB, MB, GB, KiB, MiB, GiB), "
                         f"got {text!r}")
    value = float(match.group(1)) * UNITS[match.group(2).lower()]
    if not math.isfinite(value) or value < 1:
        raise ValueError(f"a budget must be at least 1 byte, got {text!r}")
    if value > MAX_BUDGET:
        raise ValueError(f"a budget above 1 TiB is surely a typo, got {text!r}")
    return int(value)


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("map", help="inspect and prune saved maps (LT-maps, roadmaps)", description=DESCRIPTION,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="map_command", metavar="SUBCOMMAND")
    info = commands.add_parser("info", help="what a map holds", description="Print what an LT-map file holds: "
                               "viewframes, landmarks, height, bytes and landmarks per level (root first); or what "
                               "a roadmap holds: targets, edges (motion, sigma_x, sigma_y, cost), connectivity.")
    info.add_argument("file", metavar="FILE", help="an LT-map or roadmap file")
    info.add_argument("--json", action="store_true", help="print one JSON object")
    info.add_argument("--plot", type=Path, metavar="F.png", help="a roadmap: also draw its targets and edges here")
    info.set_defaults(func=run_info)
    prune = commands.add_parser("prune", help="cut tree levels until a map fits a memory budget",
                                description="Prune an LT-map to a memory budget and write the result atomically.",
                                epilog=PRUNE_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    prune.add_argument("file", metavar="FILE", help="the LT-map file to prune (left unchanged unless -o names it)")
    prune.add_argument("--budget", required=True, metavar="SIZE", help="memory budget, e.g. 200KB or 1.5MiB")
    prune.add_argument("-o", "--output", required=True, metavar="OUT", help="where to write the pruned map")
    prune.add_argument("--min-landmarks", type=int, default=DEFAULT_MIN_LANDMARKS, metavar="N",
                       help="viewframes with fewer landmarks are deleted (default: %(default)s, the paper's minimum "
                            "for homing)")
    prune.set_defaults(func=run_prune)
    parser.set_defaults(func=lambda args: _help(parser))


def _help(parser: argparse.ArgumentParser) -> int:
    parser.print_help()
    return EXIT_INVALID


def _places_text(tree: LandmarkTree) -> str:
    """Whether the map knows where its viewframes were taught, and the route's length between them."""
    if not tree.has_places:
        return "none (followed by vision alone; a map written before version 3 or taught without odometry)"
    places = np.array([tree.place(i) for i in range(tree.viewframe_count)])
    length = float(np.linalg.norm(np.diff(places, axis=0), axis=1).sum()) if len(places) > 1 else 0.0
    return f"taught odometry, {length:.1f} m from the first viewframe to the last"


def run_info(args: argparse.Namespace) -> int:
    try:
        kind = read_map_file(args.file).header.kind
        if kind == "roadmap":
            return _roadmap_info(args)
        tree = load_ltmap(args.file)
    except InputError as exc:
        return fail("map", str(exc.diagnostics[0]))
    if args.plot is not None:
        return fail("map", f"--plot draws a roadmap; {args.file} is an LT-map (bearings plot draws a run's viewframes)")
    summary = tree.summary()
    change = math.degrees(angle_of_cost(summary.threshold, tree.scale))
    if args.json:
        print(json.dumps({"file": args.file, "landmark_kind": summary.kind, "viewframes": summary.viewframes,
                          "landmarks": summary.landmarks, "nodes": summary.nodes, "height": summary.height,
                          "bytes": summary.memory_bytes, "landmarks_per_level": list(summary.landmarks_per_level),
                          "threshold": summary.threshold, "places": tree.has_places}, indent=2))
        return EXIT_OK
    rows = [
        ("landmarks of", summary.kind),
        ("viewframes", summary.viewframes),
        ("landmarks", summary.landmarks),
        ("height", summary.height),
        ("bytes", f"{summary.memory_bytes} ({summary.memory_bytes / 1024:.1f} KiB)"),
        ("per level", " ".join(str(n) for n in summary.landmarks_per_level) + "  (root first)"),
        ("threshold", f"{summary.threshold:g} (eq. 1: a {change:.1f} deg bearing change)"),
        ("places", _places_text(tree)),
    ]
    print(args.file)
    for name, value in rows:
        print(f"  {name:<13}{value}")
    return EXIT_OK


def _roadmap_info(args: argparse.Namespace) -> int:
    info = roadmap_info(Roadmap.load(args.file))
    if args.plot is not None:
        problem = output_problem(args.plot)
        if problem:
            return fail("map", f"cannot write {args.plot}: {problem}")
        try:
            draw_roadmap(info, args.plot)
        except ImportError as exc:
            return fail("map", str(exc))
    print_roadmap(args.file, info, args.json)
    return EXIT_OK


def run_prune(args: argparse.Namespace) -> int:
    try:
        budget = parse_byte_size(args.budget)
    except ValueError as exc:
        return fail("map", f"--budget: {exc}")
    if args.min_landmarks < 0:
        return fail("map", f"--min-landmarks must be 0 or more, got {args.min_landmarks}")
    try:
        tree = load_ltmap(args.file)
    except InputError as exc:
        return fail("map", str(exc.diagnostics[0]))
    before = tree.summary()
    report = tree.prune_to(budget, args.min_landmarks)
    if not report.fits:
        return fail("map", f"{args.file}: cannot prune to {budget} bytes: with one level left the map still "
                           f"takes {report.smallest_bytes} bytes")
    replacing = os.path.isfile(args.output)
    try:
        save_ltmap(args.output, tree)
    except OSError as exc:
        return fail("map", f"{args.output}: cannot write: {exc.strerror or exc}")
    after = tree.summary()
    print(f"{args.file}: {before.memory_bytes} -> {after.memory_bytes} bytes (budget {budget}), "
          f"{report.levels_cut} level(s) cut, height {before.height} -> {after.height}, "
          f"viewframes {before.viewframes} -> {after.viewframes}; wrote {args.output}"
          + (" (replaced the previous file)" if replacing else ""))
    return EXIT_OK
