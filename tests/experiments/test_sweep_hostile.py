"""Hostile results folders and options for sweeps and evaluations (issue 22, items 6 and 7): odd
rows, huge figures, unusable folders and non-finite limits are one line, never a traceback, and
the JSON written stays strict."""

from __future__ import annotations

import errno
import json
import os

import pytest

from experiments.sweep.episode import Episode
from experiments.sweep.summary import summarise
from experiments.sweep.sweeper import run_sweep
from experiments.sweep.table import read_rows
from missions.cli import main


def _rows(folder, lines: list[str]) -> None:
    folder.mkdir()
    (folder / "results.jsonl").write_text("".join(line + "\n" for line in lines))


def test_odd_rows_are_skipped_with_a_warning_and_huge_figures_summarised(tmp_path, capsys):
    good = {"mission": "m", "world": "w", "max_time_s": None, "status": "SUCCESS", "seed": 0}
    deep = "[" * 100_000 + "]" * 100_000
    _rows(tmp_path / "res", [
        json.dumps({**good, "id": "a", "x": 1e308}), json.dumps({**good, "id": "b", "x": 1e308, "seed": 1}),
        json.dumps({**good, "id": 7}), json.dumps({**good, "id": ["a"]}), json.dumps({**good, "id": ""}),
        '{"id": "c", "v": ' + deep + "}", json.dumps({**good, "id": "d", "v": [[[[[[[[[[1]]]]]]]]]]}),
    ])
    with pytest.warns(UserWarning) as caught:
        rows = read_rows(tmp_path / "res" / "results.jsonl")
    # the reader's own warnings: pytest.warns records every warning raised in the block, and a garbage
    # collection there (the deep row is a big allocation) can add another test's ResourceWarning
    # (one CI run in many failed with 6)
    ours = [w for w in caught if issubclass(w.category, UserWarning)]
    assert [r["id"] for r in rows] == ["a", "b"] and len(ours) == 5, [str(w.message) for w in caught]
    [entry] = summarise(rows)
    assert entry["figures"]["x"] == {"n": 2, "mean": 1e308, "std": 0.0, "min": 1e308, "max": 1e308}
    assert main(["sweep", "--summary", str(tmp_path / "res"), "--figures", "x"]) == 0
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err and "1e+308 +- 0" in captured.out, captured.err


def test_a_spread_past_the_largest_float_is_null_in_strict_json(tmp_path):
    rows = [{"id": f"e{k}", "mission": "m", "world": "w", "max_time_s": None, "status": "SUCCESS", "x": x}
            for k, x in enumerate((1.7e308, -1.7e308, 1.7e308))]
    [entry] = summarise(rows)
    assert entry["figures"]["x"]["std"] == float("inf")
    from maps.store import json_text

    assert json.loads(json_text(entry))["figures"]["x"]["std"] is None


@pytest.mark.parametrize("command", ["sweep", "eval"])
def test_a_results_folder_that_cannot_be_used_is_one_line(tmp_path, capsys, command):
    afile = tmp_path / "afile"
    afile.write_text("")
    args = ["square", "--workers", "1"] if command == "sweep" else ["exploration", "--world", "rooms"]
    for output, reason in ((afile, "not a folder"), ("/proc/bearings-results", "cannot write results there")):
        assert main([command, *args, "-o", str(output)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"bearings {command}: {output}: {reason}") and err.count("\n") == 1


def test_eval_refuses_an_infinite_time_limit_before_any_episode(capsys):
    assert main(["eval", "exploration", "--world", "rooms", "--max-time", "inf"]) == 2
    assert capsys.readouterr().err == "bearings eval: --max-time expects a finite number in s, got inf\n"


def test_a_disk_that_fills_up_under_a_sweep_stops_it_with_the_rows_so_far(tmp_path, monkeypatch):
    """The journal's write fails as on a full file system: the sweep ends with SweepError (the
    command's exit 1 and --resume), not a traceback; what was recorded stays."""
    from experiments.sweep.table import Journal

    real = Journal.append
    written = []

    def fills_up(journal, row):
        if written:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        written.append(row)
        real(journal, row)

    monkeypatch.setattr(Journal, "append", fills_up)
    episodes = [Episode("square", "empty", seed, {}, 1.0) for seed in range(3)]
    from concurrent.futures import ThreadPoolExecutor

    from experiments.sweep import SweepError

    with ThreadPoolExecutor(1) as executor, pytest.raises(SweepError) as info:
        run_sweep(episodes, executor=executor, results_dir=tmp_path / "out")
    assert "No space left on device" in str(info.value) and len(info.value.rows) == 1
    assert len(info.value.lost) == 2
    assert len(read_rows(tmp_path / "out" / "results.jsonl")) == 1  # the one row the disk took


def test_workers_are_capped_at_what_the_machine_has(capsys, monkeypatch):
    from experiments.sweep import sweeper

    cores = sweeper.default_workers()
    monkeypatch.setattr(sweeper, "_available_memory", lambda: 64 * sweeper.WORKER_BYTES)
    assert sweeper.cap_workers(cores, "sweep") == cores and capsys.readouterr().err == ""
    assert sweeper.cap_workers(10_000, "sweep") == cores
    assert capsys.readouterr().err == f"bearings sweep: --workers 10000 capped at {cores} (the cores this process " \
                                      "may use)\n"
    monkeypatch.setattr(sweeper, "_available_memory", lambda: sweeper.WORKER_BYTES // 2)
    assert sweeper.cap_workers(10_000, "eval") == 1
    assert "capped at 1 (the free memory, 0.1 GiB)" in capsys.readouterr().err


WRITER = """\
sense: [Perceive]
tree:
  LearnRoute: {path: route.ltmap, child: Stop}
"""


def test_each_run_of_a_sweep_writes_its_files_in_a_folder_of_its_own(tmp_path):
    mission = tmp_path / "writer.yaml"
    mission.write_text(WRITER)
    assert main(["sweep", str(mission), "--seeds", "0-1", "--workers", "1", "-o", str(tmp_path / "out")]) == 0
    rows = read_rows(tmp_path / "out" / "results.jsonl")
    assert [row["status"] for row in rows] == ["SUCCESS", "SUCCESS"]
    for row in rows:
        assert (tmp_path / "out" / "outputs" / row["id"] / "route.ltmap").is_file()
    assert not (tmp_path / "route.ltmap").exists()
