"""``bearings bench AREA --json``: named speed/accuracy/memory figures, comparable run to run."""

from __future__ import annotations

import argparse
import importlib
import sys

from experiments.bench import AREAS
from maps.store import json_text
from missions.commands.common import EXIT_INVALID, EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser(
        "bench", help="benchmark an area (" + ", ".join(AREAS) + ") and print named figures",
        description="Measure one area and print its figures. Speeds are reported next to a reference measured "
                    "in the same run (as a ratio), so results compare across machines and runs.",
    )
    parser.add_argument("area", choices=sorted(AREAS), help="what to measure")
    parser.add_argument("--json", action="store_true", help="print one JSON object (default: a readable table)")
    parser.add_argument("--quick", action="store_true", help="fewer repetitions (for smoke tests)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        module = importlib.import_module(AREAS[args.area])
    except ModuleNotFoundError as exc:
        print(f"bench {args.area}: not available in this version ({exc.name})", file=sys.stderr)
        return EXIT_INVALID
    if sys.stderr.isatty():
        print(f"benchmarking {args.area}...", file=sys.stderr)
    figures = module.run(quick=args.quick)
    figures = {"area": args.area, **figures}
    if args.json:
        print(json_text(figures, indent=2))
    else:
        width = max(len(k) for k in figures)
        for key, value in figures.items():
            shown = f"{value:.4g}" if isinstance(value, float) else value
            print(f"{key.ljust(width)}  {shown}")
    return EXIT_OK
