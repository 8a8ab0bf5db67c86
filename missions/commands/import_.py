"""``bearings import``: a BehaviorTree.CPP v4 / Groot2 XML file to a mission file."""

from __future__ import annotations

import argparse
from pathlib import Path

from maps.store import InputError
from missions.commands.common import emit, print_input_error
from missions.importer import import_btcpp

DESCRIPTION = """Turn a BehaviorTree.CPP v4 XML file (as Groot2 saves it: several <BehaviorTree>s with
<SubTree> references, a TreeNodesModel) into a mission. Nodes and ports keep their names where
bearings has them; BT.CPP's control nodes map onto bearings' (ReactiveSequence -> Sequence
memory: false, Precondition -> Guard, Timeout msec -> Timeout duration, ...); SubTrees are
inlined. Every unknown node or port and every construct bearings has no equivalent for is
reported as file:line:col: message (exit 2), and nothing is written unless the mission
validates. The mapping is in docs/missions.md, "BehaviorTree.CPP and Groot2"."""


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("import", help="turn a BehaviorTree.CPP v4 / Groot2 XML file into a mission",
                            description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("tree", metavar="TREE.xml", help="BehaviorTree.CPP v4 XML file")
    parser.add_argument("-o", "--output", metavar="MISSION.yaml", help="write the mission to this file "
                        "(default: standard output)")
    parser.add_argument("--plugin", dest="plugins", action="append", default=[], metavar="MODULE|FILE.py",
                        help="a plugin whose node types the tree uses (repeatable): an installed module, or a .py "
                             "file in the mission's folder; the mission lists it under plugins:")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    folder = Path(args.output).parent if args.output else Path.cwd()  # where the mission will find its plugins
    try:
        text = import_btcpp(args.tree, plugins=tuple(args.plugins), plugin_folder=folder)
    except InputError as exc:
        return print_input_error(exc)
    return emit("import", text, args.output, inputs=[args.tree])
