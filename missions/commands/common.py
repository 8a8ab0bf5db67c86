"""Pieces the sub-commands share: mission options, --set parsing, input-error reporting."""

from __future__ import annotations

import argparse
import sys

from maps.store import Diagnostic, InputError
from missions.language import MissionSpec
from missions.loader import load_mission

EXIT_OK, EXIT_FAILURE, EXIT_INVALID = 0, 1, 2


def add_mission_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE",
                        help="override a mission input (repeatable); the value is parsed as YAML (2, true, abc)")
    parser.add_argument("--path", dest="search_path", action="append", default=[], metavar="DIR",
                        help="extra folder where 'include:' looks for mission files (repeatable; "
                             "also $BEARINGS_PATH)")


def parse_sets(sets: list[str]) -> dict[str, str]:
    """``["a=1", "b=x"]`` to ``{"a": "1", "b": "x"}``; a malformed item is an input error."""
    out: dict[str, str] = {}
    problems = []
    for item in sets:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            problems.append(Diagnostic("--set", 0, 0, f"expected NAME=VALUE, got {item!r}"))
            continue
        out[name.strip()] = value
    if problems:
        raise InputError(problems)
    return out


def load_from_args(path: str, args: argparse.Namespace) -> MissionSpec:
    return load_mission(path, overrides=parse_sets(args.sets), search_path=args.search_path)


def print_input_error(exc: InputError) -> int:
    """Print every diagnostic as ``file:line:col: message`` on stderr; the exit code for it."""
    for diagnostic in exc.diagnostics:
        print(f"{diagnostic}", file=sys.stderr)
    count = len(exc.diagnostics)
    print(f"{count} problem{'s' if count != 1 else ''} found", file=sys.stderr)
    return EXIT_INVALID


def fail(command: str, message: str) -> int:
    """Report invalid input of a sub-command in one line on stderr; the exit code for it."""
    print(f"bearings {command}: {message}", file=sys.stderr)
    return EXIT_INVALID
