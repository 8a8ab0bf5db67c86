"""Evaluations behind ``bearings eval AREA``: one module per area, run through the sweep runner.

An area module exposes ``DESCRIPTION`` (one line), ``run(options: EvalOptions) -> dict`` (one JSON
object of named figures) and ``format_table(figures) -> str`` (the readable form). Every episode
goes through :func:`missions.sweep.run_sweep` with the executor the command built (a local process
pool or a Dask cluster), on any world file the simulator reads. Evaluations may use the simulator's
ground truth (the run reports' ``ground_truth`` sections); the behaviours they evaluate never do.
To add an area, write its module and name it in :data:`AREAS`.
"""

from __future__ import annotations

from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

AREAS = {
    "exploration": "missions.eval.exploration",
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
