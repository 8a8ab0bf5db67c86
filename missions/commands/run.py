"""``bearings run``: run a mission in the simulator or on a robot."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from behaviours.clock import TickClock
from drivers.interfaces import Robot
from drivers.safety.settings import monitor_config
from maps.located import validate
from maps.store import Diagnostic, InputError, output_problem, write_json
from missions.clocks import Paced, WallClock
from missions.commands.common import add_mission_options, load_from_args, parse_pose, print_input_error
from missions.model import RunArguments
from missions.outputs import prepare_written_files
from missions.runner import Runner, RunOptions
from missions.safety import Interrupted, early_signals, exit_code
from perception.collision_monitor import MonitorConfig
from perception.geometry import Pose2D
from perception.polygons import disc

DESCRIPTION = """Run a mission until its tree ends in SUCCESS or FAILURE.

Without --robot the mission runs in the built-in simulator (--sim WORLD picks a shipped world by
name or a world file; the default is an empty plane), as fast as the machine allows unless
--realtime is given. The same seed gives the same run, bit for bit.

Every command passes the collision monitor on its way to the base: it stops the robot short of
what its range sensors see, slows it near obstacles, and crawls when they fall silent (the
robot profile's safety: section; in the simulator, zones around the world's robot disc). The
report's safety section and the last lines printed count its stops.

Whatever happens (the tree ends, a behaviour raises or blocks, Ctrl-C, SIGTERM, --max-time), the
base and the pan-tilt unit are commanded to stop before the drivers close, and --report is
written. On a robot, a tick that overruns its period by more than the mission's 'overrun' (1 s by
default; --overrun S overrides it) makes the watchdog stop the base and end the run; in the
simulator, where time stands still during a slow tick, the watchdog runs only with --overrun.

exit codes: 0 the mission succeeded, 1 it failed (the report says why), 2 invalid input,
130/143 interrupted by SIGINT/SIGTERM."""


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("run", help="run a mission in the simulator or on a robot", description=DESCRIPTION,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mission", metavar="MISSION", help="mission file, or the name of a shipped mission")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--sim", metavar="WORLD", default=None,
                       help="simulate in WORLD (shipped name or world file; default: empty plane)")
    where.add_argument("--robot", metavar="ROBOT.yaml", help="run on the robot described by this profile")
    parser.add_argument("--seed", type=int, default=0, help="simulator seed, 0 to 4294967295 (default 0)")
    parser.add_argument("--start", metavar="POSE", help="simulator only: the robot's true start pose, x,y,theta "
                        "(theta in rad, or with a deg suffix) or a named pose of the world (default: its start)")
    parser.add_argument("--report", type=Path, metavar="F.json",
                        help="write the run report (JSON) here; a missing folder is created")
    parser.add_argument("--save", type=Path, metavar="F.rrd",
                        help="record the run for the rerun viewer; a missing folder is created")
    parser.add_argument("--max-time", type=float, metavar="S", help="FAILURE after S seconds (sim or wall time)")
    parser.add_argument("--rate", type=float, metavar="HZ", help="tick rate (default: the mission's, else 10)")
    parser.add_argument("--overrun", type=float, metavar="S",
                        help="how far a tick may overrun its period before the watchdog stops the base")
    parser.add_argument("--realtime", action="store_true", help="pace the simulator at wall-clock speed")
    parser.add_argument("--quiet", action="store_true", help="no progress line")
    parser.add_argument("--debug", action="store_true", help="print the traceback when a behaviour raises")
    add_mission_options(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    with early_signals():  # a Ctrl-C while loading still ends with a report and the right exit code
        try:
            numbers = _numbers(args)
            _prepare_outputs(args)
            mission = load_from_args(args.mission, args)
            prepare_written_files(mission, lambda note: print(f"bearings run: {note}", file=sys.stderr))
            simulation, robot, clock, safety = _open(args, numbers.seed)
        except InputError as exc:
            return print_input_error(exc)
        except DeviceUnavailable as exc:
            return _device_fault(args, exc)
        except Interrupted as exc:
            return _interrupted_early(args, exc.signum)
        try:
            return _run(args, mission, (simulation, robot, clock), numbers, safety)
        finally:
            robot.close()


def _run(args: argparse.Namespace, mission: Any, opened: tuple[Any, Robot, TickClock], numbers: RunArguments,
         safety: MonitorConfig) -> int:
    simulation, robot, clock = opened
    missing = robot.missing_cameras(mission.cameras or ())
    if missing:
        where = args.robot or f"world {args.sim or 'empty'}"
        return print_input_error(InputError([Diagnostic(mission.file, 0, 0, f"the mission uses camera(s) "
                                 f"{', '.join(missing)}, which {where} does not have (it has: "
                                 f"{', '.join(robot.cameras) or 'none'})")]))
    options = RunOptions(
        rate_hz=numbers.rate, max_time_s=numbers.max_time, overrun_s=numbers.overrun, report_path=args.report,
        save_path=args.save, progress=not args.quiet and sys.stderr.isatty(), seed=numbers.seed, debug=args.debug,
    )  # fmt: skip
    if args.realtime and simulation is not None:
        clock = Paced(clock)
    result = Runner(mission, robot, clock=clock, options=options, observers=[simulation] if simulation else [],
                    safety=safety).run()
    clock_name = "sim" if simulation is not None else "wall"
    print(f"{mission.name}: {result.status} after {result.time_s:.1f} s {clock_name} time, {result.ticks} ticks "
          f"({result.reason})")
    for line in outcome_lines(result.report):
        print(line)
    if args.report:
        print(f"report: {args.report}")
    if args.save:
        print(f"recording: {args.save} (open with: rerun {args.save})")
    return result.exit_code


def outcome_lines(report: dict[str, Any]) -> list[str]:
    """The lines after the status: the collision monitor's count, and the ground truth in simulation
    (collisions and the true minimum clearance first: a run that touched something did not succeed)."""
    safety = report.get("safety", {})
    nearest = safety.get("min_range_m")
    lines = [f"safety: {safety.get('safety_stops', 0)} stops, {safety.get('slowdowns', 0)} slow-downs, "
             f"{safety.get('bumper_hits', 0)} bumper hits, nearest sensed "
             f"{'nothing' if nearest is None else f'{nearest:.3f} m'} (sensors: {safety.get('sources', 'none')})"]
    gt = report.get("ground_truth")
    if gt:
        figures = [f"collisions {gt.get('collisions', 0)}"]
        if gt.get("min_clearance_m") is not None:
            figures.append(f"min_clearance_m {gt['min_clearance_m']:.3f}")
        figures += [f"{k} {gt[k]:.3f}" for k in ("trajectory_length_m", "goal_error_m", "path_error_m") if k in gt]
        lines.append(f"ground truth: {', '.join(figures)}")
    return lines


def _numbers(args: argparse.Namespace) -> RunArguments:
    given = {"--rate": args.rate, "--max-time": args.max_time, "--overrun": args.overrun, "--seed": args.seed}
    return validate(RunArguments, {k: v for k, v in given.items() if v is not None}, file="command line")


def _prepare_outputs(args: argparse.Namespace) -> None:
    """Check --report and --save before anything runs; create a missing folder (and say so)."""
    problems = []
    for option, path in (("--report", args.report), ("--save", args.save)):
        if path is None:
            continue
        folder = path.resolve().parent
        if not folder.exists() and not output_problem(folder):
            folder.mkdir(parents=True)
            print(f"bearings run: created the folder {folder} for {option}", file=sys.stderr)
        problem = output_problem(path)
        if problem:
            problems.append(Diagnostic(f"{option} {path}", 0, 0, problem))
    if problems:
        raise InputError(problems)


class DeviceUnavailable(Exception):  # noqa: N818 - a state of the robot, as DriverFault
    """A device of the robot could not be opened or did not answer: a fault of the machine, not of
    the input (exit 1 with a report, as ``doctor`` says 1), the profile itself being valid."""


def _device_fault(args: argparse.Namespace, exc: DeviceUnavailable) -> int:
    reason = f"device fault: {exc}"
    print(f"{args.mission}: FAILURE ({reason})", file=sys.stderr)
    if args.report and not output_problem(args.report):
        write_json(args.report, {"mission": str(args.mission), "status": "FAILURE", "reason": reason,
                                 "ticks": 0, "wall_time_s": 0.0, "last_command": {"v": 0.0, "w": 0.0}})
    return 1


def _interrupted_early(args: argparse.Namespace, signum: int) -> int:
    reason = "interrupted before the mission started"
    print(f"{args.mission}: INTERRUPTED ({reason})", file=sys.stderr)
    if args.report and not output_problem(args.report):
        write_json(args.report, {"mission": str(args.mission), "status": "INTERRUPTED", "reason": reason,
                                 "ticks": 0, "wall_time_s": 0.0, "last_command": {"v": 0.0, "w": 0.0}})
    return exit_code(signum)


def _open(args: argparse.Namespace, seed: int) -> tuple[Any, Robot, TickClock, MonitorConfig]:
    """(simulation or None, robot, the clock the run ticks on, the collision monitor's configuration)."""
    if args.robot:
        from missions.profiles import open_robot, robot_safety

        if args.start:
            raise InputError([Diagnostic("--start", 0, 0, "sets the simulated robot's start; a real robot starts "
                                         "where it stands")])
        clock = WallClock()  # one time axis for the drivers' stamps and the tree
        try:
            robot = open_robot(args.robot, clock=clock.now)
        except OSError as exc:  # a valid profile whose robot does not answer: a device fault, not bad input
            raise DeviceUnavailable(f"cannot open the robot of {args.robot}: {exc}") from None
        try:
            return None, robot, clock, robot_safety(args.robot, robot)
        except InputError:
            robot.close()
            raise
    from drivers.sim.simulation import Simulation
    from drivers.sim.world import load_world

    try:
        world = load_world(args.sim)
    except (OSError, ValueError) as exc:  # InputError (a bad world file) passes through as it is
        raise InputError([Diagnostic(str(args.sim), 0, 0, str(exc))]) from None
    simulation = Simulation(world, seed=seed, start=_start_pose(args.start, world))
    return simulation, simulation.robot, simulation.clock(), monitor_config(None, disc(world.robot_radius))


def _start_pose(text: str | None, world: Any) -> Pose2D | None:
    """The ``--start`` pose in the world (named or x,y,theta), checked to be in free space."""
    if text is None:
        return None
    from drivers.sim.scene import free_space_problem

    try:
        pose = parse_pose(text, {"start": world.start, **world.poses}, option="--start")
    except ValueError as exc:
        raise InputError([Diagnostic("--start", 0, 0, str(exc).removeprefix("--start: "))]) from None
    problem = free_space_problem(world, pose)
    if problem:
        raise InputError([Diagnostic("--start", 0, 0, f"the pose {problem}")])
    return pose
