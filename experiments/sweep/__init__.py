"""Sweeps: many simulated runs of missions, on this machine or on a Dask cluster, one row each.

The API that ``bearings sweep`` and every ``bearings eval`` use (see ``docs/sweeps.md``)::

    from experiments.sweep import Episode, grid, run_sweep, local_executor

    episodes = grid("square", ["lab", "corridor"], range(8), {"speed": [0.2, 0.4]}, max_time_s=60)
    with local_executor(workers=4) as executor:
        rows = run_sweep(episodes, executor=executor, results_dir="out/sweep", timeout_s=120)
"""

from experiments.sweep.episode import Episode, SweepInputError, grid, parse_seeds, parse_set, parse_sets
from experiments.sweep.summary import format_summary, plot, summarise
from experiments.sweep.sweeper import (
    SweepError,
    SweepInterrupted,
    cluster_executor,
    default_workers,
    executor_for,
    local_executor,
    run_sweep,
)
from experiments.sweep.table import WALL_TIME_KEYS, comparable, load_table

__all__ = [
    "WALL_TIME_KEYS",
    "Episode",
    "SweepError",
    "SweepInputError",
    "SweepInterrupted",
    "cluster_executor",
    "executor_for",
    "comparable",
    "default_workers",
    "format_summary",
    "grid",
    "load_table",
    "local_executor",
    "parse_seeds",
    "parse_set",
    "parse_sets",
    "plot",
    "run_sweep",
    "summarise",
]
