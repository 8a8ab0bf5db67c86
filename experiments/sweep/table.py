"""The results table: one flat row per episode, appended as JSON lines that a crash cannot tear.

A row holds the episode's parameters (``id``, ``mission``, ``world``, ``seed``, ``max_time_s``,
``inputs.<name>``), its outcome (``status`` SUCCESS / FAILURE from the report, or ERROR when the
episode gave no report: it crashed, was killed, hung past its time limit or had invalid input;
``reason``; ``exit_code``), its times (``sim_time_s``, ``ticks``, ``wall_time_s`` of the run and
``elapsed_s`` of the whole episode process) and every scalar figure of the report's sections
flattened with dots (``ground_truth.goal_error_m``, ``ground_truth.final_pose.x``,
``ltmap.viewframes``, ...). Lists (the trajectory) stay in the report file only.

Rows are appended in the order episodes finish, each as one ``os.write`` of a whole line on an
``O_APPEND`` descriptor followed by ``fsync``; when a sweep ends the table is rewritten (atomically)
sorted by episode id, so it does not depend on completion order. Reading skips a torn or damaged
line with a warning.
"""

from __future__ import annotations

import json
import math
import os
import warnings
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from experiments.sweep.episode import Episode
from experiments.sweep.worker import EpisodeResult
from maps.store import json_text, write_text_atomic

TABLE = "results.jsonl"
REPORTS = "reports"
LOGS = "logs"
SUMMARY = "summary.json"
OUTPUTS = "outputs"  # a sweep's runs write their files in outputs/<id>/ (their --output-dir)

WALL_TIME_KEYS = frozenset({"wall_time_s", "elapsed_s"})
"""Row keys that measure wall-clock time: the only figures that differ between two runs of the same
episode. :func:`comparable` drops them (and any flattened key ending in ``wall_time_s``)."""

PARAMETER_KEYS = ("id", "mission", "world", "seed", "max_time_s")
OUTCOME_KEYS = ("status", "reason", "exit_code", "ticks", "sim_time_s", "wall_time_s", "elapsed_s")
_NOT_FLATTENED = frozenset({"inputs"})  # the report's resolved inputs: the parameters say what was set


class TornLineWarning(UserWarning):
    """A line of the results table that is not a whole JSON row (a killed writer); it is skipped."""


def make_row(episode: Episode, result: EpisodeResult) -> dict[str, Any]:
    """The table row of one finished episode (a pure function of the two)."""
    row: dict[str, Any] = {"id": episode.id, "mission": str(episode.mission), "world": str(episode.world),
                           "seed": episode.seed, "max_time_s": episode.max_time_s}
    row.update({f"inputs.{k}": v for k, v in episode.input_values.items()})
    report = _parse(result.report_text) if result.error is None else None
    if report is None:
        reason = result.reason or "the report could not be read"
        row.update({"status": "ERROR", "reason": reason, "exit_code": result.exit_code,
                    "error": result.error or "crash", "elapsed_s": result.elapsed_s})
        return row
    row.update({"status": report.get("status"), "reason": report.get("reason"), "exit_code": result.exit_code,
                "ticks": report.get("ticks"), "sim_time_s": report.get("sim_time_s"),
                "wall_time_s": report.get("wall_time_s"), "elapsed_s": result.elapsed_s})
    for section, value in report.items():
        if isinstance(value, dict) and section not in _NOT_FLATTENED:
            row.update(flatten(value, section))
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in row.items()}


def flatten(data: dict[str, Any], prefix: str, depth: int = 1) -> dict[str, Any]:
    """Scalars of nested mappings under dotted keys; lists (and what is nested deeper than
    :data:`MAX_ROW_DEPTH`, which a report's figures never are) are left out."""
    out: dict[str, Any] = {}
    for key, value in data.items():
        name = f"{prefix}.{key}"
        if isinstance(value, dict):
            if depth < MAX_ROW_DEPTH:
                out.update(flatten(value, name, depth + 1))
        elif value is None or isinstance(value, (bool, int, float, str)):
            out[name] = value
    return out


def comparable(row: dict[str, Any]) -> dict[str, Any]:
    """The row without its wall-clock figures: equal for two runs of the same episode."""
    return {k: v for k, v in row.items() if k not in WALL_TIME_KEYS and not k.endswith("wall_time_s")}


def is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


# --------------------------------------------------------------------------------------------
# The journal


class Journal:
    """Appends rows to ``results.jsonl``: one ``os.write`` of a whole line, then ``fsync``."""

    def __init__(self, path: Path) -> None:
        self.path = path
        path.parent.mkdir(parents=True, exist_ok=True)
        self.fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        _cut_torn_tail(self.fd, path)

    def append(self, row: dict[str, Any]) -> None:
        line = (json_text(row, separators=(",", ":"), default=str) + "\n").encode("utf-8")
        written = os.write(self.fd, line)
        if written != len(line):  # a full disk: say so rather than leave half a row
            raise OSError(f"{self.path}: short write ({written} of {len(line)} bytes)")
        os.fsync(self.fd)

    def close(self) -> None:
        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1

    def __enter__(self) -> Journal:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()


def _cut_torn_tail(fd: int, path: Path) -> None:
    """A last line without its newline was torn by a killed writer: cut it so appends start clean."""
    size = os.fstat(fd).st_size
    if size == 0:
        return
    with open(path, "rb") as handle:
        handle.seek(max(0, size - 65536))
        tail = handle.read()
    if tail.endswith(b"\n"):
        return
    cut = tail.rfind(b"\n")
    keep = size - len(tail) + cut + 1 if cut >= 0 else (0 if size <= 65536 else None)
    if keep is None:  # a torn line longer than the window: keep it, start a new line after it
        os.write(fd, b"\n")
        return
    warnings.warn(f"{path}: ignoring a torn last line ({size - keep} bytes, a killed writer)", TornLineWarning,
                  stacklevel=3)
    os.ftruncate(fd, keep)


def read_rows(path: Path) -> list[dict[str, Any]]:
    """Rows of a results table in file order, skipping (with a warning) lines that are not whole rows."""
    if not path.is_file():
        return []
    rows = []
    data = path.read_bytes()
    lines = data.split(b"\n")
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            row = json.loads(line)
            if not _is_row(row):
                raise ValueError("not a row")
        except (ValueError, RecursionError):  # RecursionError: nested deeper than the parser goes
            torn = number == len(lines)  # the last line, without its newline
            what = "a torn last line" if torn else f"line {number}: not a JSON row"
            warnings.warn(f"{path}: ignoring {what}", TornLineWarning, stacklevel=2)
            continue
        rows.append(row)
    return rows


MAX_ROW_DEPTH = 8
"""Rows are flat (a value may be a list of inputs): nesting deeper than this is not a row."""


def _is_row(row: Any) -> bool:
    """A mapping with a non-empty text ``id`` and values nested at most :data:`MAX_ROW_DEPTH` deep."""
    if not isinstance(row, dict) or not isinstance(row.get("id"), str) or not row["id"]:
        return False
    level: list[Any] = [row]
    for _ in range(MAX_ROW_DEPTH):
        level = [v for item in level for v in (item.values() if isinstance(item, dict) else item)
                 if isinstance(v, (dict, list))]
        if not level:
            return True
    return False


def latest_by_id(rows: Iterable[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """One row per episode id (the last one written), sorted by id."""
    by_id: dict[str, dict[str, Any]] = {}
    for row in rows:
        by_id[row["id"]] = row
    return dict(sorted(by_id.items()))


def write_sorted(path: Path, rows: Iterable[dict[str, Any]]) -> None:
    """Rewrite the table atomically: one row per id, sorted by id."""
    lines = [json_text(row, separators=(",", ":"), default=str) + "\n" for row in rows]
    write_text_atomic(path, "".join(lines))


def read_report(results_dir: str | os.PathLike, episode_id: str) -> dict[str, Any] | None:
    """The run report an episode left in a results folder; None when it left none, or an
    unreadable one (its row says why: the run is an ERROR)."""
    try:
        report = json.loads((Path(results_dir) / REPORTS / f"{episode_id}.json").read_text())
    except (OSError, ValueError, RecursionError):
        return None
    return report if isinstance(report, dict) else None


def load_table(results_dir: str | os.PathLike) -> list[dict[str, Any]]:
    """The rows of a results folder, one per episode, sorted by episode id."""
    return list(latest_by_id(read_rows(Path(results_dir) / TABLE)).values())


def _parse(text: str | None) -> dict[str, Any] | None:
    if text is None:
        return None
    try:
        data = json.loads(text)
    except (ValueError, RecursionError):
        return None
    return data if isinstance(data, dict) else None
