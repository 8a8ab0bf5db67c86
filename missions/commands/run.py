"""``bearings run``: run a mission in the simulator or on a robot."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from behaviours.clock import TickClock
from drivers.interfaces import KeyboardOpener, Robot
from drivers.keyboard import TerminalKeys
from drivers.logs.camera_codec import parse_image_format
from drivers.pioneer_body import BODIES
from drivers.safety.settings import monitor_config
from maps.located import validate
from maps.store import Diagnostic, InputError, output_problem, write_json
from missions.clocks import Paced, WallClock, paced_when_operated
from missions.commands.common import add_mission_options, load_from_args, parse_pose, print_input_error
from missions.images import DEFAULT_RATE_HZ
from missions.model import RunArguments
from missions.outputs import prepare_written_files
from missions.progress import progress_for
from missions.runner import Runner, RunOptions
from missions.safety import Interrupted, early_signals, exit_code
from missions.summary import summary_line
from missions.trace import Trace
from perception.collision_monitor import MonitorConfig
from perception.geometry import Pose2D
from perception.polygons import disc

DESCRIPTION = """Run a mission until its tree ends in SUCCESS or FAILURE.

Without --robot the mission runs in the built-in simulator (--sim WORLD picks a shipped world by
name or a world file; the default is an empty plane), as fast as the machine allows unless
--realtime is given or an operator drives by keys (real time from when a key node first runs).
The same seed gives the same run, bit for bit.

--record F.mcap records every sensed input and command as ROS 2 messages (MCAP: Foxglove and the
ROS 2 tools open it); --replay LOG runs the mission on such a recording, or on a ROS 2 or ROS 1
bag, instead of a robot: open loop, its commands go nowhere (docs/recorded-data.md).

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
    where.add_argument("--replay", metavar="LOG", type=Path, help="play a log back as the robot: an MCAP file "
                       "(--record writes one), a ROS 2 bag folder or a ROS 1 .bag (docs/recorded-data.md)")
    parser.add_argument("--topics", metavar="MAP.yaml", type=Path,
                        help="with --replay: which topics of the log are the odometry, cameras, ... (default: "
                        "the names --record writes)")
    parser.add_argument("--record", type=Path, metavar="F.mcap",
                        help="record every sensed input and command as ROS 2 messages in MCAP (Foxglove, the ROS 2 "
                        "tools and --replay read it); a missing folder is created")
    parser.add_argument("--record-images", type=_image_format, default="jpeg", metavar="jpeg[:Q]|png",
                        help="how --record compresses images: jpeg (quality 90, or Q) or png (lossless: a replay "
                        "sees the very pixels); default jpeg")
    parser.add_argument("--seed", type=int, default=0, help="simulator seed, 0 to 4294967295 (default 0)")
    parser.add_argument("--start", metavar="POSE", help="simulator only: the robot's true start pose, x,y,theta "
                        "(theta in rad, or with a deg suffix) or a named pose of the world (default: its start)")
    parser.add_argument("--report", type=Path, metavar="F.json",
                        help="write the run report (JSON) here; a missing folder is created")
    parser.add_argument("--save", type=Path, metavar="F.rrd",
                        help="record the run for the rerun viewer; a missing folder is created")
    parser.add_argument("--image-rate", type=float, metavar="HZ", default=DEFAULT_RATE_HZ,
                        help=f"camera images per second and camera in the --save recording, JPEG-encoded "
                             f"(default {DEFAULT_RATE_HZ:g}; 0: every frame grabbed)")
    parser.add_argument("--max-time", type=float, metavar="S", help="FAILURE after S seconds (sim or wall time)")
    parser.add_argument("--rate", type=float, metavar="HZ", help="tick rate (default: the mission's, else 10)")
    parser.add_argument("--overrun", type=float, metavar="S",
                        help="how far a tick may overrun its period before the watchdog stops the base")
    parser.add_argument("--realtime", action="store_true", help="pace the simulator at wall-clock speed")
    parser.add_argument("--quiet", action="store_true", help="no progress line")
    parser.add_argument("--progress", action="store_true",
                        help="print progress even when stderr is not a terminal: a line every few seconds")
    parser.add_argument("--trace", type=float, metavar="S",
                        help="print a line every S seconds of run time on stdout: the command, the collision "
                        "monitor, the avoidance's phase, every running behaviour's feedback; in the simulator also "
                        "the true pose, the nearest people and every new closest approach under 5 cm")
    parser.add_argument("--debug", action="store_true", help="print the traceback when a behaviour raises")
    add_mission_options(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    with early_signals():  # a Ctrl-C while loading still ends with a report and the right exit code
        try:
            numbers = _numbers(args)
            _prepare_outputs(args)
            mission = load_from_args(args.mission, args, to_run=True)
            prepare_written_files(mission, lambda note: print(f"bearings run: {note}", file=sys.stderr))
            simulation, robot, clock, safety = _open(args, numbers.seed, mission)
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
        save_path=args.save, image_rate_hz=numbers.image_rate, seed=numbers.seed, debug=args.debug,
        record_path=args.record, record_images=args.record_images,
    )  # fmt: skip
    keyboard: KeyboardOpener = TerminalKeys
    if args.replay is not None:  # a replay's keyboard: the logged keys; its clock, paced when asked
        keyboard = simulation.keyboard
        if args.realtime:
            clock = Paced(clock)
    elif simulation is not None:  # real time when asked, or from when an operator takes the keyboard
        clock = Paced(clock, engaged=args.realtime)
        keyboard = paced_when_operated(TerminalKeys, clock, said=lambda line: print(line, file=sys.stderr))
    progress = progress_for(mission.name, sys.stderr, asked=args.progress, quiet=args.quiet)
    trace = None if numbers.trace is None else Trace(numbers.trace, sys.stdout)
    try:
        result = Runner(mission, robot, clock=clock, options=options, observers=[simulation] if simulation else [],
                        on_tick=_every_tick(progress, trace), keyboard=keyboard, safety=safety).run()
    finally:
        if progress is not None:
            progress.close()
    clock_name = {"sim_time": "sim", "replay_time": "log"}.get(clock.timeline, "wall")
    print(f"{mission.name}: {result.status} after {result.time_s:.1f} s {clock_name} time, {result.ticks} ticks "
          f"({result.reason})")
    summary = summary_line(result.report)  # collisions, safety stops, clearance, each capability's headline
    if summary:
        print(summary)
    if args.report:
        print(f"report: {args.report}")
    if args.save:
        print(f"recording: {args.save} (open with: rerun {args.save})")
    if args.record:
        record = result.report.get("record", {})
        print(f"sensor log: {args.record} ({record.get('messages', 0)} messages, {record.get('bytes', 0) / 1e6:.1f} MB;"
              f" bearings log info {args.record})")
    return result.exit_code


def _every_tick(*hooks: Callable[[Runner], None] | None) -> Callable[[Runner], None] | None:
    """The runner's ``on_tick``: each of ``hooks`` given, in turn (None when none is)."""
    given = [hook for hook in hooks if hook is not None]
    if len(given) <= 1:
        return given[0] if given else None

    def both(runner: Runner) -> None:
        for hook in given:
            hook(runner)
    return both


def _numbers(args: argparse.Namespace) -> RunArguments:
    given = {"--rate": args.rate, "--max-time": args.max_time, "--overrun": args.overrun, "--seed": args.seed,
             "--image-rate": args.image_rate, "--trace": args.trace}
    return validate(RunArguments, {k: v for k, v in given.items() if v is not None}, file="command line")


def _prepare_outputs(args: argparse.Namespace) -> None:
    """Check --report, --save and --record before anything runs; create a missing folder (and say so)."""
    problems = []
    for option, path in (("--report", args.report), ("--save", args.save), ("--record", args.record)):
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


def _open(args: argparse.Namespace, seed: int, mission: Any) -> tuple[Any, Robot, TickClock, MonitorConfig]:
    """(the run's observer: the simulation, the replay or None; the robot; the clock the run ticks on; the
    collision monitor's configuration)."""
    if args.topics is not None and args.replay is None:
        raise InputError([Diagnostic("--topics", 0, 0, "maps the topics of a log: it goes with --replay LOG")])
    if args.replay is not None:
        from missions.log_check import open_replay

        if args.start:
            raise InputError([Diagnostic("--start", 0, 0, "sets the simulated robot's start; a replay starts where "
                                         "the log does")])
        if args.record is not None and args.record.resolve() == args.replay.resolve():
            raise InputError([Diagnostic("--record", 0, 0, "would overwrite the log --replay reads")])
        replay = open_replay(args.replay, args.topics, mission)  # exit 2 with what the log lacks
        logged = replay.contents.footprint()  # the recorded robot's outline; a P3-DX's when the log gives none
        footprint = BODIES["p3dx"].footprint if logged is None else logged
        return replay, replay.robot, replay.clock(), monitor_config(None, footprint)
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


def _image_format(text: str) -> Any:
    try:
        return parse_image_format(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
