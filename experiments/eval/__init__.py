"""Evaluations behind ``bearings eval AREA``: one module per area, run through the sweep runner.

An area module exposes ``DESCRIPTION`` (one line), ``check_world(world)`` (raises ``InputError`` or
``ValueError`` for a world it cannot evaluate), ``run(options: EvalOptions, *, resume: bool) -> dict``
(one JSON object of named figures) and ``format_table(figures) -> str`` (the readable form). Every
episode goes through :func:`experiments.sweep.run_sweep` with the executor the command built (a local
process pool or a Dask cluster), on any world file the simulator reads. Evaluations may use the
simulator's ground truth (the run reports' ``ground_truth`` sections); the behaviours they evaluate
never do.

An area with options of its own declares them in ``OPTIONS`` (name -> one-line help). The command
takes them as ``--option NAME=VALUE`` (repeatable; a name the area does not declare is refused) and
passes them on as text in :attr:`EvalOptions.extra`; when the module has ``check_options(world,
extra)``, that may refuse a bad value (``ValueError``, exit 2) before any episode runs.

To add an area, write its module and name it in :data:`AREAS`.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO, TypeVar

N = TypeVar("N", int, float)  # the number an area option holds

AREAS = {
    "exploration": "experiments.eval.exploration",
    "ltmap": "experiments.eval.ltmap",
    "roadmap": "experiments.eval.roadmap",
}


@dataclass
class EvalOptions:
    """What every evaluation is given: where, how many seeds, how to run the episodes."""

    world: str
    seeds: list[int]
    executor: Executor
    results_dir: Path  # the sweep's folder: results.jsonl, reports/<id>.json
    timeout_s: float | None = None  # wall-clock limit per episode
    max_time_s: float | None = None  # each episode's --max-time (simulated seconds); None: the mission's
    progress: TextIO | None = None
    extra: dict[str, str] = field(default_factory=dict)  # the area's own options (--option NAME=VALUE)
    # what the area's check_world and check_options (or None) returned for these inputs, when the
    # caller has checked them already (the command does, before any episode); None: run() checks
    checked: tuple[Any, Any] | None = None


def bounded_option(name: str, text: str | None, *, convert: Callable[[str], N], default: N, maximum: N,
                   expected: str, unit: str = "") -> N:
    """An area option that is a number from 0 to ``maximum`` (``unit`` in the message); ``default``
    when not given; a ``ValueError`` naming the option otherwise (``expected``: what it should be)."""
    if text is None:
        return default
    try:
        value = convert(text)
    except ValueError:
        raise ValueError(f"{name}: {expected} expected, got {text!r}") from None
    if not 0 <= value <= maximum:
        raise ValueError(f"{name} must be 0 to {maximum:g}{unit}, got {value:g}")
    return value


def count_option(name: str, text: str | None, *, default: int, maximum: int) -> int:
    """An area option that counts something (``people``, ``starts``): 0 to ``maximum``; ``default``
    when not given; a ``ValueError`` naming the option otherwise."""
    return bounded_option(name, text, convert=int, default=default, maximum=maximum, expected="an integer")
