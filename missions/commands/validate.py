"""``bearings validate``: check mission files without running them."""

from __future__ import annotations

import argparse

from maps.store import InputError
from missions.commands.common import EXIT_INVALID, EXIT_OK, add_mission_options, load_from_args, print_input_error
from missions.profiles import mission_problems


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser(
        "validate", help="check mission files (syntax, node types, ports, data flow, includes)",
        description="Load and check each mission as 'run' would, without running it. Every problem of every "
                    "file is reported as file:line:col: message. Exit 0 when all are valid, 2 otherwise.",
    )
    parser.add_argument("missions", nargs="+", metavar="MISSION", help="mission files (or shipped mission names)")
    parser.add_argument("--robot", metavar="ROBOT.yaml", help="also check each mission against this robot profile: "
                        "the profile is valid, and it has the cameras the mission grabs and the pan-tilt unit it "
                        "reads or drives (nothing is opened)")
    add_mission_options(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    status = EXIT_OK
    for path in args.missions:
        try:
            mission = load_from_args(path, args)
            problems = mission_problems(mission, args.robot) if args.robot else []
            if problems:
                raise InputError(problems)
        except InputError as exc:
            print_input_error(exc)
            status = EXIT_INVALID
            continue
        nodes = sum(1 for _ in mission.tree.walk())
        robot = f", on {args.robot}" if args.robot else ""
        print(f"{mission.file}: ok ({mission.name}, {nodes} nodes, {len(mission.files) - 1} included files{robot})")
    return status
