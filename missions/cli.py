"""The ``bearings`` command line: one sub-command per module of :mod:`missions.commands`."""

from __future__ import annotations

import argparse
import importlib
import sys

from missions.commands import COMMANDS

EPILOG = """exit codes: 0 mission SUCCESS / command done, 1 mission FAILURE, 2 invalid input,
130/143 interrupted by SIGINT/SIGTERM.
Run 'bearings COMMAND --help' for the options of one command."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bearings",
        description="Behaviour-tree robot missions that navigate by the bearings of visual landmarks.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module_name in COMMANDS:
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name == module_name:  # a command not written yet
                continue
            raise
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args))
    except KeyboardInterrupt:
        print("bearings: interrupted", file=sys.stderr)
        return 1
    except BrokenPipeError:  # e.g. `bearings schema | head`
        return 0


if __name__ == "__main__":
    sys.exit(main())
