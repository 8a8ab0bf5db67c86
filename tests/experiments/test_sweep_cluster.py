"""``bearings sweep --cluster``: the same episodes on a Dask scheduler give the same rows as locally."""

from __future__ import annotations

import json

import distributed  # a dev dependency: its absence fails the test, it never skips it

from experiments.sweep import comparable
from missions.cli import main


def rows_of(folder) -> list[dict]:
    return [json.loads(line) for line in (folder / "results.jsonl").read_text().splitlines()]


def test_cluster_sweep_gives_the_same_rows_as_the_local_one(tmp_path):
    args = ["sweep", "square", "--max-time", "30", "--sim", "lab", "--seeds", "0-1", "--set", "side=0.1"]
    assert main([*args, "--workers", "2", "-o", str(tmp_path / "local")]) == 0
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        assert main([*args, "--cluster", cluster.scheduler_address, "-o", str(tmp_path / "cluster")]) == 0
    local, remote = rows_of(tmp_path / "local"), rows_of(tmp_path / "cluster")
    assert len(local) == 2 and all(r["status"] == "SUCCESS" for r in local)
    assert [comparable(r) for r in remote] == [comparable(r) for r in local]


def test_unreachable_scheduler_is_invalid_input(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("experiments.sweep.sweeper.CONNECT_TIMEOUT_S", 0.5)
    assert main(["sweep", "square", "--cluster", "tcp://127.0.0.1:9", "-o", str(tmp_path)]) == 2
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in capsys.readouterr().err


def test_eval_says_an_unreachable_scheduler_in_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("experiments.sweep.sweeper.CONNECT_TIMEOUT_S", 0.5)
    assert main(["eval", "exploration", "--world", "lab", "--cluster", "tcp://127.0.0.1:9", "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in err and "Traceback" not in err
