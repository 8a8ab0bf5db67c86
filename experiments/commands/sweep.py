"""``bearings sweep``: run a mission over worlds x seeds x input values, one row per run."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import re
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

from experiments.sweep import episode as spec
from experiments.sweep.lifeline import lifeline
from experiments.sweep.summary import format_summary, plot, resolve_column, summarise
from experiments.sweep.sweeper import (
    SweepError,
    SweepInterrupted,
    cap_workers,
    check_episodes,
    default_workers,
    executor_for,
    prepare_results_folder,
    progress_stream,
    run_sweep,
)
from experiments.sweep.table import OUTPUTS, SUMMARY, TABLE, TornLineWarning, load_table
from experiments.sweep.worker import run_number_problem
from maps.store import write_json
from missions.commands.common import EXIT_FAILURE, EXIT_OK, fail

DESCRIPTION = """Run MISSION once per world x seed x combination of --set values, each run a normal
'bearings run' in its own process (same report JSON), in parallel on this machine's cores or on a
Dask cluster. Results go to RESULTS_DIR: results.jsonl (one row per run: its parameters, status,
reason, times and the report's figures flattened), reports/<id>.json, logs/<id>.log (output of
runs that crashed, hung or were killed) and summary.json (per combination: success rate, mean and
spread of every figure), which is also printed. A run succeeded when its mission ended in SUCCESS
without a collision; the table counts the runs that collided, the collision monitor's stops and
the true minimum clearance.

A run that fails, crashes, is killed or hangs past --timeout is one row with its reason; the sweep
goes on. Ctrl-C kills the running episodes and keeps every finished row; --resume continues.
Rows depend on the parameters and the seed only, never on --workers or the order runs finish in
(wall times aside)."""

EPILOG = """examples:
  bearings sweep showcase --sim lab,corridor --seeds 0-7 --set speed=0.3,0.5 -o out/speeds
  bearings sweep square --seeds 0-99 --cluster tcp://scheduler:8786 --timeout 300 -o out/sq
  bearings sweep --summary out/speeds --plot goal_error_m --against speed

exit codes: 0 every episode has its row (whatever the missions did), 1 interrupted or some
episodes could not be run (--resume runs them), 2 invalid input."""


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("sweep", help="run a mission over worlds x seeds x input values, in parallel",
                            description=DESCRIPTION, epilog=EPILOG,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mission", nargs="?", metavar="MISSION", help="mission file, or the name of a shipped mission")
    parser.add_argument("--sim", default="empty", metavar="WORLD[,WORLD...]",
                        help="worlds: shipped names or world files (default: the empty plane)")
    parser.add_argument("--seeds", default="0", metavar="SPEC", help="seeds: 0-99, 7, 0-3,10 (default: 0)")
    parser.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=V1,V2,...",
                        help="values of a mission input, one run each (repeatable; every combination is run)")
    parser.add_argument("--max-time", type=float, metavar="S", help="each run's --max-time (simulated seconds)")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N",
                       help=f"local worker processes (default: {default_workers()}, the cores here)")
    where.add_argument("--cluster", metavar="ADDRESS", help="run on this Dask scheduler, e.g. tcp://host:8786 "
                       "(needs: pip install 'bearings[cluster]')")
    parser.add_argument("--timeout", type=float, metavar="S",
                        help="kill a run after S seconds of wall time (an ERROR row)")
    parser.add_argument("--start-method", choices=("fork", "spawn"), default="fork",
                        help="each run's process: forked from a warm server per worker (default; saves the imports) "
                             "or a fresh interpreter")
    parser.add_argument("--resume", action="store_true", help="skip the runs RESULTS_DIR already has")
    parser.add_argument("--retry-errors", action="store_true",
                        help="with --resume: run the runs that crashed, hung or were killed again")
    parser.add_argument("--progress", action="store_true", help="progress on stderr even when it is not a terminal")
    parser.add_argument("-o", "--output", type=Path, metavar="RESULTS_DIR", help="folder for the results")
    parser.add_argument("--summary", type=Path, metavar="RESULTS_DIR", help="print the summary of earlier results")
    parser.add_argument("--figures", metavar="A,B,...", help="figures the printed summary shows (default: sim time "
                        "and the ground-truth errors); summary.json has them all")
    parser.add_argument("--plot", metavar="FIGURE", help="plot FIGURE (e.g. goal_error_m, success) against --against")
    parser.add_argument("--against", metavar="PARAM",
                        help="the swept parameter on the plot's x axis (speed, seed, world)")
    parser.add_argument("--png", type=Path, metavar="FILE", help="where the plot goes (default: RESULTS_DIR/"
                        "FIGURE-vs-PARAM.png)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    with _one_line_warnings():
        if args.summary is not None:
            return _run(args)
        with lifeline("sweep"):  # whatever ends the sweep, its processes and temporary folders end with it
            return _run(args)


def _run(args: argparse.Namespace) -> int:
    if args.summary is not None:
        if args.mission or args.output:
            return fail("sweep", "--summary RESULTS_DIR takes no MISSION and no -o")
        return _show(args.summary, args)
    try:
        episodes = _episodes(args)
        with executor_for(cap_workers(args.workers, "sweep"), args.cluster) as executor:
            check_episodes(episodes, executor, start_method=args.start_method)
            run_sweep(episodes, executor=executor, results_dir=args.output, timeout_s=args.timeout,
                      resume=args.resume, retry_errors=args.retry_errors, progress=progress_stream(args.progress),
                      start_method=args.start_method)
    except spec.SweepInputError as exc:  # bad options, a run command's diagnostic, no cluster
        return fail("sweep", str(exc))
    except SweepInterrupted as exc:
        _finish(args.output, args)
        print(f"bearings sweep: interrupted; {len(exc.rows)} of {exc.total} runs recorded in {args.output} "
              "(--resume continues)", file=sys.stderr)
        return EXIT_FAILURE
    except SweepError as exc:
        _finish(args.output, args)
        print(f"bearings sweep: {exc}", file=sys.stderr)
        return EXIT_FAILURE
    return _finish(args.output, args)


def _episodes(args: argparse.Namespace) -> list[spec.Episode]:
    """The grid the options describe; :class:`SweepInputError` for any invalid option."""
    if not args.mission or args.output is None:
        raise spec.SweepInputError("give MISSION and -o RESULTS_DIR (or --summary RESULTS_DIR)")
    problem = _check_plot_options(args)
    if problem:
        raise spec.SweepInputError(problem)
    if args.retry_errors and not args.resume:
        raise spec.SweepInputError("--retry-errors goes with --resume")
    if args.workers is not None and args.workers < 1:
        raise spec.SweepInputError("--workers must be at least 1")
    problem = run_number_problem(args.max_time, args.timeout)
    if problem:
        raise spec.SweepInputError(problem)
    mission = spec.absolute_if_file(args.mission)
    worlds = spec.parse_worlds(args.sim)
    seeds = spec.parse_seeds(args.seeds)
    sets = spec.parse_sets(args.sets)
    episodes = spec.grid(mission, worlds, seeds, sets, max_time_s=args.max_time)
    prepare_results_folder(args.output)
    outputs = args.output.resolve() / OUTPUTS  # each run's files apart: runs of one mission name the same ones
    return [dataclasses.replace(e, output_dir=str(outputs / e.id)) for e in episodes]


@contextlib.contextmanager
def _one_line_warnings() -> Iterator[None]:
    """A torn row and the like: ``bearings sweep: warning: ...`` on stderr, not a source line."""

    def show(message, category, filename, lineno, file=None, line=None) -> None:  # noqa: ANN001
        print(f"bearings sweep: warning: {message}", file=sys.stderr)

    with warnings.catch_warnings():
        warnings.simplefilter("default", TornLineWarning)
        warnings.showwarning = show
        yield


def _finish(folder: Path, args: argparse.Namespace) -> int:
    rows = load_table(folder)
    summary = summarise(rows)
    write_json(folder / SUMMARY, summary)
    print(format_summary(summary, _figures(args)))
    print(f"{len(rows)} runs: {folder / TABLE}, summary: {folder / SUMMARY}")
    return _plot(rows, folder, args)


def _show(folder: Path, args: argparse.Namespace) -> int:
    if not (folder / TABLE).is_file():
        return fail("sweep", f"{folder}: no {TABLE} here (not a sweep's results folder)")
    problem = _check_plot_options(args)
    if problem:
        return fail("sweep", problem)
    rows = load_table(folder)
    print(format_summary(summarise(rows), _figures(args)))
    return _plot(rows, folder, args)


def _check_plot_options(args: argparse.Namespace) -> str | None:
    if (args.plot is None) != (args.against is None):
        return "--plot FIGURE and --against PARAM go together"
    if args.png is not None and args.plot is None:
        return "--png needs --plot FIGURE --against PARAM"
    if args.plot is not None:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            return "--plot needs matplotlib: pip install 'bearings[plot]'"
    return None


def _plot(rows: list[dict], folder: Path, args: argparse.Namespace) -> int:
    if args.plot is None:
        return EXIT_OK
    try:
        figure = resolve_column(rows, args.plot, parameter=False)
        against = resolve_column(rows, args.against, parameter=True)
    except ValueError as exc:
        return fail("sweep", str(exc))
    path = args.png or folder / f"{_file_name(figure)}-vs-{_file_name(against)}.png"
    print(f"plot: {plot(rows, figure, against, path)}")
    return EXIT_OK


def _file_name(column: str) -> str:
    return re.sub(r"[^\w.=+-]+", "-", column)


def _figures(args: argparse.Namespace) -> list[str] | None:
    return [f.strip() for f in args.figures.split(",") if f.strip()] if args.figures else None

