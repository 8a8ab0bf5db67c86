"""Pieces the sub-commands share: mission options, --set parsing, input-error reporting."""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import sys
from collections.abc import Iterable
from pathlib import Path

from drivers.sim.world_file import MAX_COORD
from maps.store import Diagnostic, InputError, output_problem, write_text_atomic
from missions.language import MissionSpec
from missions.loader import load_mission
from perception.geometry import Pose2D

EXIT_OK, EXIT_FAILURE, EXIT_INVALID = 0, 1, 2


def add_mission_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE",
                        help="override a mission input (repeatable); the value is parsed as YAML (2, true, abc)")
    parser.add_argument("--output-dir", type=Path, metavar="DIR",
                        help="where the mission's files go (maps it saves): relative paths resolve here, and a "
                             "file outside DIR and the mission's folder is refused (default: the mission's "
                             "folder; the current one for a shipped mission)")
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


def load_from_args(path: str, args: argparse.Namespace, *, to_run: bool = False) -> MissionSpec:
    """The mission a command names, with its ``--set`` and ``--path``; ``to_run``: every required
    input must be given."""
    return load_mission(path, overrides=parse_sets(args.sets), search_path=args.search_path, require_inputs=to_run,
                        output_dir=getattr(args, "output_dir", None))


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


def parse_pose(text: str, named: dict[str, Pose2D], *, option: str) -> Pose2D:
    """``x,y,theta`` (theta in rad, or degrees with a ``deg`` suffix) or a named pose of a world."""
    if text in named:
        return named[text]
    parts = [p.strip() for p in text.split(",")]
    if len(parts) not in (2, 3):
        known = ", ".join(sorted(named)) or "none"
        raise ValueError(f"{option} must be x,y,theta or a named pose (this world has: {known}), got {text!r}")
    try:
        x, y = float(parts[0]), float(parts[1])
        theta = 0.0
        if len(parts) == 3:
            raw = parts[2].lower()
            theta = math.radians(float(raw[:-3])) if raw.endswith("deg") else float(raw)
    except ValueError:
        raise ValueError(f"{option}: numbers expected in x,y,theta, got {text!r}") from None
    if not all(math.isfinite(v) for v in (x, y, theta)):
        raise ValueError(f"{option}: finite numbers expected, got {text!r}")
    if len(parts) == 3 and not parts[2].lower().endswith("deg") and abs(theta) > 2.0 * math.pi:
        raise ValueError(f"{option}: theta {parts[2]} rad is more than a full turn; degrees take a deg suffix "
                         f"({parts[0]},{parts[1]},{parts[2]}deg), got {text!r}")
    if max(abs(x), abs(y)) > MAX_COORD:
        raise ValueError(f"{option}: x and y must be within {MAX_COORD:g} m (the extent of any world), got {text!r}")
    return Pose2D(x, y, theta)


def emit(command: str, text: str, output: str | os.PathLike | None, inputs: Iterable[str | os.PathLike] = ()) -> int:
    """Write a command's result to ``output`` (atomically) or to stdout. Exit 2 with the reason when
    ``output`` cannot be written or is one of the command's ``inputs`` (``import t.xml -o t.xml``
    would replace the tree by the mission); a file replaced is named on stderr; a write that fails
    (a full disk) is one line and exit 1, the previous file kept whole."""
    if output is None:
        sys.stdout.write(text)
        return EXIT_OK
    problem = output_problem(output) or same_as_input(output, inputs)
    if problem:
        return fail(command, f"cannot write {output}: {problem}")
    replacing = os.path.isfile(output)
    try:
        write_text_atomic(output, text)
    except OSError as exc:
        print(f"bearings {command}: cannot write {output}: {exc.strerror or exc} (nothing was changed)",
              file=sys.stderr)
        return EXIT_FAILURE
    if replacing:
        print(f"bearings {command}: replaced {output}", file=sys.stderr)
    return EXIT_OK


def same_as_input(output: str | os.PathLike, inputs: Iterable[str | os.PathLike]) -> str | None:
    """Why ``output`` must not be written: it is (a link to) one of the command's input files
    (``import t.xml -o t.xml``, ``calibrate a.png -o a.png``), else None."""
    for given in inputs:
        with contextlib.suppress(OSError):
            if os.path.exists(output) and os.path.samefile(output, given):
                return f"it is the input file {given}: write the result elsewhere"
    return None
