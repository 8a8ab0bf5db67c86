"""``bearings missions``: the shipped missions, each with the first sentence of its description."""

from __future__ import annotations

import argparse

from maps.store import InputError
from missions.commands.common import EXIT_OK
from missions.loader import LIBRARY, load_mission


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("missions", help="list the shipped missions (run them by name: bearings run NAME)",
                            description="List the missions that ship with bearings (missions/library/): their "
                                        "names, inputs and what they do. Run one by name: bearings run NAME.")
    parser.set_defaults(func=run)


def shipped_missions() -> list[str]:
    """The names of the shipped missions, sorted."""
    return sorted(path.stem for path in LIBRARY.glob("*.yaml"))


def run(args: argparse.Namespace) -> int:
    for name in shipped_missions():
        try:
            mission = load_mission(LIBRARY / f"{name}.yaml")
        except InputError as exc:  # a shipped mission always loads; say so rather than hide it
            print(f"{name}: does not load: {exc.diagnostics[0]}")
            continue
        first = " ".join(mission.description.split()).split(". ")[0].rstrip(".")
        inputs = ", ".join(f"{key}" + ("" if not port.required else " (required)")
                           for key, port in mission.inputs.items())
        print(f"{name}: {first}." + (f"\n    inputs: {inputs}" if inputs else ""))
    return EXIT_OK
