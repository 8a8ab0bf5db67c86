"""``bearings eval AREA --world NAME|PATH --seeds N --json``: an evaluation's named figures.

The area's episodes run through the sweep runner (``experiments.sweep.run_sweep``) on a local process
pool (``--workers``) or a Dask cluster (``--cluster``); ``-o DIR`` keeps the sweep's folder (the
table, every run's report) and ``--resume`` continues it. The areas are the modules of
:data:`experiments.eval.AREAS`.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import sys
import tempfile
from pathlib import Path
from typing import Any

from experiments.eval import AREAS, EvalOptions
from experiments.sweep import SweepError, SweepInputError, SweepInterrupted, executor_for
from experiments.sweep.episode import parse_seeds
from experiments.sweep.lifeline import lifeline
from experiments.sweep.sweeper import cap_workers, prepare_results_folder, progress_stream
from experiments.sweep.table import TABLE
from experiments.sweep.worker import run_number_problem
from maps.store import InputError, json_text
from missions.commands.common import EXIT_FAILURE, EXIT_OK, fail, print_input_error

MAX_SEEDS = 10_000


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser(
        "eval", help=f"evaluate an area ({', '.join(sorted(AREAS))}) in a simulated world over seeds and print "
                     "named figures",
        description="Run an area's evaluation episodes through the sweep runner and print one JSON object of "
                    "named figures (--json) or a table. Works on any world file the simulator reads.",
        epilog="Areas and their --option names (an unknown name is refused with the list): exploration "
               "(localisation, people, rest, variants; docs/exploration.md), ltmap (camera, route, min_landmarks, "
               "goal_tolerance, rotation, gap_filling, odometry, cuts, people, rest; docs/ltmap.md), roadmap "
               "(targets, starts, people, rest; docs/roadmap.md). people=N: N people drawn from the seed in the way "
               "of the robot; rest=S: the most each walking person rests at each end of their walk (default 2 s).",
    )
    parser.add_argument("area", choices=sorted(AREAS), help="what to evaluate")
    parser.add_argument("--world", required=True, metavar="NAME|PATH", help="a shipped world or a world file")
    which = parser.add_mutually_exclusive_group()
    which.add_argument("--seeds", type=int, default=1, metavar="N", help="seeds 0 to N-1 (default 1)")
    which.add_argument("--seed-list", metavar="SPEC",
                       help="these seeds instead: 7, 2-4 or 0,3,5-6 (e.g. one seed that failed, alone)")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N", help="local worker processes (default: the cores here)")
    where.add_argument("--cluster", metavar="ADDRESS", help="run the episodes on this Dask scheduler")
    parser.add_argument("--timeout", type=float, metavar="S", help="kill an episode after S s of wall time")
    parser.add_argument("--max-time", type=float, metavar="S", help="each episode's --max-time (simulated s)")
    parser.add_argument("-o", "--output", type=Path, metavar="DIR", help="keep the sweep's results here")
    parser.add_argument("--resume", action="store_true", help="with -o: reuse the episodes DIR already has")
    parser.add_argument("--progress", action="store_true", help="progress on stderr even when not a terminal")
    parser.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                        help="an option of the area (repeatable), e.g. ltmap: camera=landmarks")
    parser.add_argument("--json", action="store_true", help="print one JSON object (default: a table)")
    parser.set_defaults(func=run)


def _problem(args: argparse.Namespace) -> str | None:
    if not 1 <= args.seeds <= MAX_SEEDS:
        return f"--seeds must be 1 to {MAX_SEEDS}, got {args.seeds}"
    if args.workers is not None and args.workers < 1:
        return f"--workers must be at least 1, got {args.workers}"
    problem = run_number_problem(args.max_time, args.timeout)
    if problem:
        return problem
    if args.resume and args.output is None:
        return "--resume needs -o DIR"
    if args.output is not None and not args.resume and (args.output / TABLE).exists():
        return f"{args.output} already has results: --resume continues them, or choose another folder"
    return None


def area_options(module: Any, area: str, given: list[str]) -> dict[str, str]:
    """``--option NAME=VALUE`` texts as a mapping; ``ValueError`` for a malformed, repeated or unknown name."""
    known: dict[str, str] = getattr(module, "OPTIONS", {})
    extra: dict[str, str] = {}
    for text in given:
        name, equals, value = text.partition("=")
        name = name.strip()
        if not equals or not name:
            raise ValueError(f"--option must be NAME=VALUE, got {text!r}")
        if name not in known:
            has = ", ".join(sorted(known)) or "none"
            raise ValueError(f"--option: the {area} evaluation has no option {name!r} (its options: {has})")
        if name in extra:
            raise ValueError(f"--option {name} is given twice")
        extra[name] = value.strip()
    return extra


def run(args: argparse.Namespace) -> int:
    problem = _problem(args)
    if problem:
        return fail("eval", problem)
    module = importlib.import_module(AREAS[args.area])
    try:
        world = module.check_world(args.world)
        extra = area_options(module, args.area, args.option)
        seeds = parse_seeds(args.seed_list, option="--seed-list") if args.seed_list else list(range(args.seeds))
        settings = module.check_options(args.world, extra) if hasattr(module, "check_options") else None
        if args.output is not None:
            prepare_results_folder(args.output)
    except InputError as exc:
        return print_input_error(exc)
    except ValueError as exc:  # SweepInputError too
        return fail("eval", str(exc))
    with contextlib.ExitStack() as stack:
        stack.enter_context(lifeline("eval"))  # whatever ends the evaluation, its processes and folders end with it
        folder = args.output or Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="bearings-eval-")))
        try:
            executor = stack.enter_context(executor_for(cap_workers(args.workers, "eval"), args.cluster))
            options = EvalOptions(args.world, seeds, executor, folder, args.timeout,
                                  args.max_time, progress_stream(args.progress), extra, (world, settings))
            figures = module.run(options, resume=args.resume)
        except SweepInputError as exc:
            return fail("eval", str(exc))
        except (SweepInterrupted, SweepError) as exc:
            print(f"bearings eval: {exc}", file=sys.stderr)
            return EXIT_FAILURE
    figures = {"area": args.area, **figures}
    print(json_text(figures, indent=2) if args.json else module.format_table(figures))
    return EXIT_OK
