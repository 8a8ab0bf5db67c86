"""``bearings show``: print a mission's tree as text, Graphviz dot or BehaviorTree.CPP XML."""

from __future__ import annotations

import argparse

from maps.store import InputError
from missions.commands.common import add_mission_options, emit, load_from_args, print_input_error
from missions.export import btcpp_xml, dot_tree, unicode_tree

FORMATS = {"unicode": unicode_tree, "dot": dot_tree, "xml": btcpp_xml}


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser(
        "show", help="print a mission's tree (unicode, dot, or BehaviorTree.CPP v4 XML for Groot2)",
        description="Print the validated tree of a mission with its parameters. --format xml writes "
                    "BehaviorTree.CPP v4 XML (<root BTCPP_format=\"4\">) with a TreeNodesModel, which Groot2 opens.",
    )
    parser.add_argument("mission", metavar="MISSION", help="mission file (or shipped mission name)")
    parser.add_argument("--format", choices=sorted(FORMATS), default="unicode", help="output format")
    parser.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of standard output")
    add_mission_options(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        mission = load_from_args(args.mission, args)
        text = FORMATS[args.format](mission)  # the XML export refuses what BT.CPP cannot express
    except InputError as exc:
        return print_input_error(exc)
    return emit("show", text, args.output, inputs=mission.files)
