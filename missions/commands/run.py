"""``bearings run``: run a mission in the simulator or on a robot."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from maps.store import Diagnostic, InputError
from missions.commands.common import add_mission_options, load_from_args, print_input_error
from missions.runner import Runner, RunOptions

DESCRIPTION = """Run a mission until its tree ends in SUCCESS or FAILURE.

Without --robot the mission runs in the built-in simulator (--sim WORLD picks a shipped world by
name or a world file; the default is an empty plane), as fast as the machine allows unless
--realtime is given. The same seed gives the same run, bit for bit.

Whatever happens (the tree ends, a behaviour raises, Ctrl-C, SIGTERM, --max-time), the base and
the pan-tilt unit are commanded to stop before the drivers close, and --report is written.

exit codes: 0 the mission succeeded, 1 it failed (the report says why), 2 invalid input."""


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("run", help="run a mission in the simulator or on a robot", description=DESCRIPTION,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mission", metavar="MISSION", help="mission file, or the name of a shipped mission")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--sim", metavar="WORLD", default=None,
                       help="simulate in WORLD (shipped name or world file; default: empty plane)")
    where.add_argument("--robot", metavar="ROBOT.yaml", help="run on the robot described by this profile")
    parser.add_argument("--seed", type=int, default=0, help="simulator seed (default 0)")
    parser.add_argument("--report", type=Path, metavar="F.json", help="write the run report (JSON) here")
    parser.add_argument("--save", type=Path, metavar="F.rrd", help="record the run for the rerun viewer")
    parser.add_argument("--max-time", type=float, metavar="S", help="FAILURE after S seconds (sim or wall time)")
    parser.add_argument("--rate", type=float, metavar="HZ", help="tick rate (default: the mission's, else 10)")
    parser.add_argument("--realtime", action="store_true", help="pace the simulator at wall-clock speed")
    parser.add_argument("--quiet", action="store_true", help="no progress line")
    parser.add_argument("--debug", action="store_true", help="print the traceback when a behaviour raises")
    add_mission_options(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        mission = load_from_args(args.mission, args)
        _check_numbers(args)
        simulation, robot = _open(args)
    except InputError as exc:
        return print_input_error(exc)
    missing = robot.missing_cameras(mission.cameras or ())
    if missing:
        robot.close()
        where = args.robot or f"world {args.sim or 'empty'}"
        return print_input_error(InputError([Diagnostic(mission.file, 0, 0, f"the mission uses camera(s) "
                                 f"{', '.join(missing)}, which {where} does not have (it has: "
                                 f"{', '.join(robot.cameras) or 'none'})")]))
    options = RunOptions(
        rate_hz=args.rate, max_time_s=args.max_time, realtime=args.realtime, report_path=args.report,
        save_path=args.save, progress=not args.quiet and sys.stderr.isatty(), seed=args.seed, debug=args.debug,
    )
    try:
        result = Runner(mission, robot, simulation=simulation, options=options).run()
    finally:
        robot.close()
    clock = "sim" if simulation is not None else "wall"
    print(f"{mission.name}: {result.status} after {result.time_s:.1f} s {clock} time, {result.ticks} ticks "
          f"({result.reason})")
    gt = result.report.get("ground_truth")
    if gt:
        figures = ", ".join(f"{k} {gt[k]:.3f}" for k in ("trajectory_length_m", "goal_error_m", "path_error_m")
                            if k in gt)
        print(f"ground truth: {figures}")
    if args.report:
        print(f"report: {args.report}")
    if args.save:
        print(f"recording: {args.save} (open with: rerun {args.save})")
    return result.exit_code


def _check_numbers(args: argparse.Namespace) -> None:
    problems = []
    if args.rate is not None and not 0.1 <= args.rate <= 1000:
        problems.append(Diagnostic("--rate", 0, 0, "must be between 0.1 and 1000 Hz"))
    if args.max_time is not None and args.max_time <= 0:
        problems.append(Diagnostic("--max-time", 0, 0, "must be positive"))
    if problems:
        raise InputError(problems)


def _open(args: argparse.Namespace):
    if args.robot:
        from missions.profiles import open_robot

        try:
            return None, open_robot(args.robot)
        except OSError as exc:
            raise InputError([Diagnostic(args.robot, 0, 0, f"cannot open the robot: {exc}")]) from None
    from drivers.sim.simulation import Simulation

    try:
        simulation = Simulation.load(args.sim, seed=args.seed)
    except (OSError, ValueError) as exc:  # InputError (a bad world file) passes through as it is
        raise InputError([Diagnostic(str(args.sim), 0, 0, str(exc))]) from None
    return simulation, simulation.robot

