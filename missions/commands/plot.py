"""``bearings plot``: a picture of a run from its report (needs the ``plot`` extra: matplotlib)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from maps.store import output_problem
from missions.commands.common import EXIT_OK, fail


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser(
        "plot", help="draw a run from its report: floor plan, paths, viewframes, roadmap, explored map",
        description="Draw what a run report holds as an image, without the rerun viewer: the world's floor plan, "
                    "the true and odometry paths, the taught route's viewframes, the roadmap's targets and edges, "
                    "the explored map, collisions and safety stops. Needs matplotlib: pip install 'bearings[plot]'.",
    )
    parser.add_argument("report", type=Path, metavar="REPORT.json", help="a report written by bearings run --report")
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="F.png",
                        help="the image to write (PNG, or SVG/PDF by its suffix)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        report = json.loads(args.report.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        return fail("plot", f"cannot read {args.report}: {exc}")
    except json.JSONDecodeError as exc:
        return fail("plot", f"{args.report}:{exc.lineno}:{exc.colno}: not a JSON report: {exc.msg}")
    if not isinstance(report, dict):
        return fail("plot", f"{args.report}: not a run report (a JSON object with mission, status, ...)")
    problem = output_problem(args.output)
    if problem:
        return fail("plot", f"cannot write {args.output}: {problem}")
    try:
        from missions.plot import save_plot

        save_plot(report, args.output)
    except ImportError as exc:
        return fail("plot", str(exc))
    except (KeyError, TypeError, ValueError) as exc:
        return fail("plot", f"{args.report}: a part of the report is malformed ({type(exc).__name__}: {exc})")
    print(f"plot: {args.output}")
    return EXIT_OK
