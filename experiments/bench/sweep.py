"""Sweep throughput for ``bearings bench sweep --json``: episodes per second, 1 worker vs N workers.

Short episodes (the ``square`` mission with 10 cm sides in the empty world, ~0.02 s of ticking
each) make the per-episode cost of the sweep itself visible. Both phases run through
:func:`experiments.sweep.run_sweep` on a local process pool that is started and warmed up first
(pool start-up is not counted); the N-worker phase runs N times as many episodes.

- ``episodes_per_s_1_worker``, ``episodes_per_s_n_workers``: throughput of each phase.
- ``scaling_ratio``: N-worker rate / (N x the 1-worker rate); the target is >= 0.8.
- ``episode_elapsed_s``: one episode as the sweep sees it (its process, start to report), mean
  of the 1-worker phase; ``run_wall_s``: the part the runner itself reports (``wall_time_s``);
  ``isolation_overhead_s`` is the difference: process start, mission and world load, report.
- The same three for ``--start-method spawn`` (a fresh interpreter per episode, 1 worker):
  ``spawn_episode_elapsed_s``, ``spawn_isolation_overhead_s``, and ``fork_speedup`` = spawn
  episode / fork episode.
- References measured in the same run: ``python_startup_s`` (``python -c pass``) and
  ``stack_import_s`` (a process that imports the run command): the spawn overhead is about
  their sum; the fork server pays it once per worker.
- ``machine_scaling_ratio``: the same ratio for N copies of a pure-Python loop in N processes,
  i.e. what this machine gives N processes (on a shared machine it can be well under 1);
  ``scaling_vs_machine`` = ``scaling_ratio`` / that. Every figure is the best of 5 interleaved
  repeats (1 with ``--quick``), so that other jobs' load affects the phases alike.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time
from concurrent.futures import wait

from experiments.sweep import Episode, local_executor, run_sweep
from experiments.sweep.sweeper import default_workers
from experiments.sweep.worker import run_episode

MISSION = "square"
INPUTS = {"side": 0.1}
SPIN = "import time\nt = time.perf_counter()\nx = 0\nfor i in range(3_000_000): x += i\nprint(time.perf_counter() - t)"


def _episodes(count: int, first_seed: int) -> list[Episode]:
    return [Episode(MISSION, "empty", seed, INPUTS) for seed in range(first_seed, first_seed + count)]


def _timed(executor, count: int, first_seed: int, start_method: str) -> tuple[float, list[dict]]:
    start = time.perf_counter()
    rows = run_sweep(_episodes(count, first_seed), executor=executor, start_method=start_method)
    elapsed = time.perf_counter() - start
    failed = [r for r in rows if r["status"] != "SUCCESS"]
    if failed:
        raise RuntimeError(f"bench episode failed: {failed[0]['reason']}")
    return count / elapsed, rows


def _throughput(workers: int, per_worker: int, repeats: int,
                spawned: int) -> tuple[float, float, float, list[dict], list[dict]]:
    """Best-of-``repeats`` episodes per second on 1 and on N workers, and the machine's own scaling
    (:func:`_spin`), all interleaved so that load from other jobs on a shared machine hits each
    alike; then ``spawned`` episodes started with ``spawn`` on the 1-worker pool."""
    with local_executor(1) as one, local_executor(workers) as many:
        warm_up = [executor.submit(run_episode, episode)  # start the workers and their episode servers, together
                   for executor, count in ((one, 1), (many, workers)) for episode in _episodes(count, 10_000 + count)]
        wait(warm_up)
        best_1, best_n, spin_1, spin_n, rows_1 = 0.0, 0.0, float("inf"), float("inf"), []
        for repeat in range(repeats):
            spin_1 = min(spin_1, _spin(1))
            rate, rows = _timed(one, per_worker, 1000 * repeat, "fork")
            if rate > best_1:
                best_1, rows_1 = rate, rows
            spin_n = min(spin_n, _spin(workers))
            best_n = max(best_n, _timed(many, per_worker * workers, 1000 * repeat + 500, "fork")[0])
        spawn_rows = _timed(one, spawned, 20_000, "spawn")[1]
    return best_1, best_n, spin_1 / spin_n, rows_1, spawn_rows


def _process_time(code: str, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True)
        best = min(best, time.perf_counter() - start)
    return best


def _spin(copies: int) -> float:
    """Seconds for ``copies`` processes to each run the same loop at once (the slowest)."""
    processes = [subprocess.Popen([sys.executable, "-c", SPIN], stdout=subprocess.PIPE, text=True)
                 for _ in range(copies)]
    return max(float(p.communicate()[0]) for p in processes)


def _mean(rows: list[dict], key: str) -> float:
    return statistics.fmean(r[key] for r in rows)


def run(quick: bool = False) -> dict:
    workers = default_workers()
    per_worker = 3 if quick else 30
    rate_1, rate_n, machine, rows_1, spawned = _throughput(workers, per_worker, 1 if quick else 5, 1 if quick else 8)
    elapsed, wall = _mean(rows_1, "elapsed_s"), _mean(rows_1, "wall_time_s")
    spawn_elapsed, spawn_wall = _mean(spawned, "elapsed_s"), _mean(spawned, "wall_time_s")
    repeats = 1 if quick else 5
    startup = _process_time("pass", repeats)
    imports = _process_time("import missions.cli; missions.cli.build_parser()", repeats)
    return {
        "workers": workers,
        "episodes_1_worker": per_worker,
        "episodes_n_workers": per_worker * workers,
        "episodes_per_s_1_worker": round(rate_1, 3),
        "episodes_per_s_n_workers": round(rate_n, 3),
        "scaling_ratio": round(rate_n / (workers * rate_1), 3),
        "scaling_target": 0.8,
        "machine_scaling_ratio": round(machine, 3),
        "scaling_vs_machine": round(rate_n / (workers * rate_1) / machine, 3),
        "episode_elapsed_s": round(elapsed, 4),
        "run_wall_s": round(wall, 4),
        "isolation_overhead_s": round(elapsed - wall, 4),
        "spawn_episode_elapsed_s": round(spawn_elapsed, 4),
        "spawn_isolation_overhead_s": round(spawn_elapsed - spawn_wall, 4),
        "fork_speedup": round(spawn_elapsed / elapsed, 2),
        "python_startup_s": round(startup, 4),
        "stack_import_s": round(imports, 4),
    }
