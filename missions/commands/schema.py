"""``bearings schema``: JSON Schemas of the files users write (missions, worlds, robot profiles)."""

from __future__ import annotations

import argparse
import json
from typing import Any

from missions.commands.common import emit, fail

DESCRIPTION = """Print a JSON Schema (draft 2020-12) for editors to complete and check files.

By default: missions, with every node type and its ports (types, units, defaults). --world: the
simulator's world files; --profile: robot profiles, with each installed driver's settings. The
schemas come from the same declarations the loaders check files against. Plugins listed with
--plugin are added so their node types appear in the mission schema."""


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("schema", help="print the JSON Schema of missions, worlds or robot profiles",
                            description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    which = parser.add_mutually_exclusive_group()
    which.add_argument("--world", action="store_true", help="the schema of simulated world files")
    which.add_argument("--profile", action="store_true", help="the schema of robot profiles")
    parser.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of standard output")
    parser.add_argument("--plugin", action="append", default=[], metavar="MODULE",
                        help="add this module's node types to the mission schema (repeatable)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        schema = _schema(args)
    except ValueError as exc:
        return fail("schema", str(exc))
    text = json.dumps(schema, indent=2) + "\n"
    return emit("schema", text, args.output)


def _schema(args: argparse.Namespace) -> dict[str, Any]:
    if args.world:
        from drivers.sim.world_file import WorldFile

        schema = WorldFile.model_json_schema()
        schema["title"] = "bearings simulated world"
        return schema
    if args.profile:
        from missions.profiles import profile_schema

        return profile_schema()
    from pathlib import Path

    from behaviours.registry import Registry
    from missions.plugins import PluginError, load_plugin
    from missions.schema import mission_schema

    registry = Registry.default().child()
    for module in args.plugin:
        try:
            load_plugin(module, Path.cwd(), registry)
        except PluginError as exc:
            raise ValueError(f"--plugin {exc}") from None
    return mission_schema(registry)
