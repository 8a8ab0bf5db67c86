"""``bearings bench run``: the BLAS-thread and unused-camera figures as ratios of runs in the same bench."""

from __future__ import annotations

import json

from experiments.bench import run as bench_run
from missions.cli import main


def test_bench_run_prints_both_figures_as_ratios_of_its_own_runs(monkeypatch, capsys):
    monkeypatch.setattr(bench_run, "EXPLORE_TIME_S", 3.0)  # --quick runs a third: one second of explore
    monkeypatch.setattr(bench_run, "SQUARE", bench_run.SQUARE.replace("distance: 1.0", "distance: 0.1"))
    assert main(["bench", "run", "--quick", "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["area"] == "run" and figures["explore_sim_time_s"] == 1.0
    assert abs(figures["blas_cpu_ratio"] - figures["blas_unpinned_cpu_s"] / figures["blas_pinned_cpu_s"]) < 0.01
    assert figures["cameras_in_world"] == 5
    assert figures["cameras_recording_ratio"] > 1  # images of five cameras against none
    for key in ("blas_pinned_cpu_s", "blas_unpinned_cpu_s", "cameras_read_wall_s", "cameras_all_wall_s",
                "cameras_wall_ratio"):
        assert figures[key] > 0


def test_the_runs_are_timed_as_bearings_run_processes_with_their_thread_pools_set():
    cost = bench_run.bearings_run(["square", "--set", "side=0.1", "--max-time", "1"], threads=1)
    assert cost.exit_code == 1 and cost.cpu_s > 0 and cost.wall_s > 0  # the time limit: FAILURE, timed all the same
