"""The ``bearings`` command line: one sub-command per command module.

The built-in commands are the modules of :data:`missions.commands.COMMANDS`; the others (the
``experiments`` package's ``sweep``, ``eval`` and ``bench``, or a plugin package's) are found by
entry point, group :data:`missions.commands.ENTRY_POINT_GROUP`, each naming a module that exposes
``register(subparsers)`` (as ros2cli finds its verbs). The CLI never imports them by name, so
``missions`` does not depend on what is built on it. ``bearings --help`` lists the built-ins,
then the entry points by name. An entry point that cannot be loaded or registered costs its own
command only: one line on stderr names it and the others work.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import importlib
import os
import sys
import threading
from importlib.metadata import EntryPoint, entry_points
from typing import NoReturn

from missions.commands import COMMANDS, ENTRY_POINT_GROUP
from missions.threads import pin_thread_pools

EPILOG = """exit codes: 0 mission SUCCESS / command done, 1 mission FAILURE, 2 invalid input,
130/143 interrupted by SIGINT/SIGTERM.
Run 'bearings COMMAND --help' for the options of one command."""


@functools.cache
def command_entry_points() -> tuple[EntryPoint, ...]:
    """The installed entry points of the commands group, by name (then module: a stable order).
    Read once per process: the sweep's episode server forks children that all inherit it."""
    return tuple(sorted(entry_points(group=ENTRY_POINT_GROUP), key=lambda e: (e.name, e.value)))


def _add_builtin(sub: argparse._SubParsersAction) -> None:
    for module_name in COMMANDS:
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name == module_name:  # a command not written yet
                continue
            raise
        module.register(sub)


def _add_entry_point(sub: argparse._SubParsersAction, entry: EntryPoint) -> None:
    """Register the command of one entry point; if that fails, say so in one line and go on."""
    try:
        entry.load().register(sub)
    except Exception as exc:  # an entry point is someone else's code: whatever it raises, the CLI stays up
        said = str(exc).strip().splitlines()
        print(f"bearings: command {entry.name!r} ({entry.value}) is not available: {type(exc).__name__}"
              + (f": {said[0]}" if said else ""), file=sys.stderr)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bearings",
        description="Behaviour-tree robot missions that navigate by the bearings of visual landmarks.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    _add_builtin(sub)
    for entry in command_entry_points():
        _add_entry_point(sub, entry)
    return parser


def main(argv: list[str] | None = None) -> int:
    pin_thread_pools()  # before any command module imports numpy (missions/threads.py says why)
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
    except OSError as exc:  # the machine refused (a full disk, a vanished folder): one line, never a traceback
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"bearings {args.command}: {where}{exc.strerror or exc}", file=sys.stderr)
        return 1


def console(argv: list[str] | None = None) -> NoReturn:
    """The ``bearings`` program: :func:`main`, then the end of the process with its exit code."""
    end_process(main(argv))


def end_process(code: int) -> NoReturn:
    """Exit with ``code`` once the command is done (its report written, its summary printed), even
    when a plugin left threads running: Python would wait for every non-daemon thread before it
    exits, so one that never ends (a plugin's server, a forgotten loop) would keep the process, and
    with it the terminal or the sweep's episode, forever. Those threads are named on stderr and the
    process ends without waiting for them (``os._exit``, after flushing the standard streams)."""
    left = [t for t in threading.enumerate() if t.is_alive() and not t.daemon and t is not threading.main_thread()]
    if not left:
        sys.exit(code)
    names = ", ".join(sorted(t.name for t in left))
    print(f"bearings: ending the process with exit code {code}; {len(left)} thread(s) a plugin left running: "
          f"{names}", file=sys.stderr)
    with contextlib.suppress(Exception):
        sys.stdout.flush()
        sys.stderr.flush()
    os._exit(code)


if __name__ == "__main__":
    console()
