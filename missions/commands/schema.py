"""``bearings schema``: the JSON Schema of the mission language, for editors."""

from __future__ import annotations

import argparse
import json
import sys

from maps.store import write_text_atomic
from missions.commands.common import EXIT_OK
from missions.schema import mission_schema


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser(
        "schema", help="print the JSON Schema of missions (every node type and its ports)",
        description="Print a JSON Schema (draft 2020-12) of the mission language with every registered node type "
                    "and its parameters, so editors can complete and check missions. Plugins listed with "
                    "--plugin are imported first so their behaviours appear too.",
    )
    parser.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of standard output")
    parser.add_argument("--plugin", action="append", default=[], metavar="MODULE",
                        help="import this module first (repeatable)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from behaviours.registry import import_plugin

    for module in args.plugin:
        try:
            import_plugin(module)
        except Exception as exc:  # noqa: BLE001 - user input
            print(f"--plugin {module}: cannot import: {type(exc).__name__}: {exc}", file=sys.stderr)
            return 2
    text = json.dumps(mission_schema(), indent=2) + "\n"
    if args.output:
        write_text_atomic(args.output, text)
    else:
        sys.stdout.write(text)
    return EXIT_OK
