"""``bearings sweep``: the grid, determinism across worker counts, resume, torn rows, bad input,
summaries and plots, and the sweep benchmark. Episodes are tiny squares (seconds in total)."""

from __future__ import annotations

import io
import json
import sys
import warnings

import pytest

from experiments.sweep import (
    Episode,
    SweepInputError,
    comparable,
    grid,
    load_table,
    local_executor,
    parse_seeds,
    parse_sets,
    run_sweep,
    summarise,
)
from experiments.sweep.summary import format_summary
from experiments.sweep.sweeper import Progress
from experiments.sweep.table import Journal, TornLineWarning, make_row, read_rows
from experiments.sweep.worker import EpisodeResult
from missions.cli import main

SQUARE = ["square", "--max-time", "30"]


def sweep(*args: str) -> int:
    return main(["sweep", *args])


def rows_of(folder) -> list[dict]:
    return [json.loads(line) for line in (folder / "results.jsonl").read_text().splitlines()]


# --------------------------------------------------------------------------------------------
# Values: episodes, ids, grids, specs, rows


def test_episode_id_depends_on_the_parameters_only():
    a = Episode("square", "lab", 3, {"side": 0.2, "speed": "0.3"})
    same = Episode("square", "lab", 3, {"speed": 0.3, "side": "0.2"})  # order and spelling of values
    assert a.id == same.id and a.id.startswith("square_lab_side=0.2_speed=0.3_s0003_")
    assert Episode("square", "lab", 4, a.inputs).id != a.id
    assert Episode("square", "lab", 3, a.inputs, max_time_s=5).id != a.id
    assert Episode("/x/my mission.yaml", "/w/lab.yaml").id.startswith("my-mission_lab_s0000_")
    assert a.run_arguments("r.json") == ["run", "square", "--sim", "lab", "--seed", "3", "--report", "r.json",
                                         "--quiet", "--set", "side=0.2", "--set", "speed=0.3"]


def test_grid_is_every_combination_sorted_by_id():
    episodes = grid("square", ["lab", "corridor"], [0, 1, 2], {"side": ["0.2", "0.3"], "speed": ["1"]})
    assert len(episodes) == 12 and len({e.id for e in episodes}) == 12
    assert [e.id for e in episodes] == sorted(e.id for e in episodes)
    assert {(e.world, e.inputs["side"], e.seed) for e in episodes} == {
        (w, s, n) for w in ("lab", "corridor") for s in ("0.2", "0.3") for n in (0, 1, 2)}


def test_seed_and_set_specs():
    assert parse_seeds("0-3,7,2") == [0, 1, 2, 3, 7]
    assert parse_sets(["speed=0.2,0.4", "path=[[0,1],[2,3]],[]"]) == {"speed": ["0.2", "0.4"],
                                                                     "path": ["[[0,1],[2,3]]", "[]"]}
    for bad in ("5-2", "a", "-1", "1-", "4294967290-4294967296"):
        with pytest.raises(SweepInputError):
            parse_seeds(bad)
    for bad in (["x="], ["=1"], ["x"], ["x=1,,2"], ["x=1", "x=2"], ["x=1,1"]):
        with pytest.raises(SweepInputError):
            parse_sets(bad)


def test_row_flattens_the_report_and_failed_episodes_have_a_reason():
    episode = Episode("square", "lab", 1, {"side": "0.2"})
    report = {"mission": "square", "status": "FAILURE", "reason": "Drive failed", "ticks": 5, "sim_time_s": 0.4,
              "wall_time_s": 0.01, "inputs": {"side": 0.2, "speed": 0.3},
              "ground_truth": {"goal_error_m": 0.5, "final_pose": {"x": 1.0}, "trajectory": [[0, 0]]},
              "ltmap": {"viewframes": 7, "memory_bytes": float("nan")}}
    row = make_row(episode, EpisodeResult(episode.id, 1, json.dumps(report), None, "", 0.5))
    assert row["inputs.side"] == 0.2 and row["status"] == "FAILURE" and row["reason"] == "Drive failed"
    assert row["ground_truth.goal_error_m"] == 0.5 and row["ground_truth.final_pose.x"] == 1.0
    assert row["ltmap.viewframes"] == 7 and row["ltmap.memory_bytes"] is None
    assert not any(k.endswith("trajectory") or k.startswith("inputs.speed") for k in row)
    assert "wall_time_s" not in comparable(row) and "elapsed_s" not in comparable(row)
    lost = make_row(episode, EpisodeResult(episode.id, -9, None, "killed", "killed by SIGKILL", 0.5))
    assert lost["status"] == "ERROR" and lost["reason"] == "killed by SIGKILL" and lost["error"] == "killed"


def test_summary_per_combination():
    rows = [{"id": f"e{i}", "mission": "m", "world": w, "seed": i, "max_time_s": None, "inputs.speed": v,
             "status": "SUCCESS" if i % 2 else "FAILURE", "sim_time_s": float(i), "ground_truth.goal_error_m": 0.1 * i}
            for i, (w, v) in enumerate([("lab", 0.2), ("lab", 0.2), ("lab", 0.4), ("lab", 0.4)])]
    rows.append({"id": "e9", "mission": "m", "world": "lab", "seed": 9, "max_time_s": None, "inputs.speed": 0.4,
                 "status": "ERROR", "reason": "killed by SIGKILL"})
    summary = summarise(rows)
    assert [s["inputs.speed"] for s in summary] == [0.2, 0.4]
    slow, fast = summary
    assert (slow["episodes"], slow["success"], slow["failure"], slow["error"]) == (2, 1, 1, 0)
    assert (fast["episodes"], fast["success_rate"], fast["error"]) == (3, 1 / 3, 1)
    assert slow["figures"]["sim_time_s"] == pytest.approx({"n": 2, "mean": 0.5, "std": 0.70710678, "min": 0, "max": 1})
    table = format_summary(summary)
    assert table.splitlines()[0].split()[:2] == ["speed", "runs"] and "33%" in table and "goal_error_m" in table


def test_the_summary_says_why_runs_did_not_succeed_commonest_first():
    stalled = "Drive failed: stalled"
    reasons = [stalled, stalled, "time limit of 60 s reached", None, stalled]
    rows = [{"id": f"e{i}", "mission": "m", "world": "corridor", "seed": i, "max_time_s": None, "inputs.side": 2,
             "status": "FAILURE", "reason": reason} for i, reason in enumerate(reasons)]
    rows.append({"id": "ok", "mission": "m", "world": "lab", "seed": 0, "max_time_s": None, "inputs.side": 2,
                 "status": "SUCCESS", "reason": "mission tree succeeded"})
    corridor, lab = summarise(rows)
    assert corridor["reasons"] == [{"reason": "Drive failed: stalled", "count": 3},
                                   {"reason": "time limit of 60 s reached", "count": 1},
                                   {"reason": "no reason", "count": 1}]
    assert lab["reasons"] == []
    table = format_summary([corridor, lab])
    assert table.splitlines()[-1] == ("  world=corridor: 3 x Drive failed: stalled; 1 x time limit of 60 s reached; "
                                      "1 x no reason")


def test_a_success_that_collided_is_not_a_success():
    rows = [{"id": f"e{i}", "mission": "m", "world": "lab", "seed": i, "max_time_s": None, "status": "SUCCESS",
             "ground_truth.collisions": collisions, "safety.safety_stops": stops, "ground_truth.min_clearance_m": gap}
            for i, (collisions, stops, gap) in enumerate([(0, 1, 0.12), (2, 0, 0.0), (0, 3, 0.08)])]
    (entry,) = summarise(rows)
    assert (entry["success"], entry["collided"], entry["success_rate"]) == (2, 1, 2 / 3)
    assert entry["figures"]["safety.safety_stops"]["mean"] == pytest.approx(4 / 3)
    assert entry["figures"]["ground_truth.min_clearance_m"]["min"] == 0.0
    header = format_summary([entry]).splitlines()[0].split()
    assert {"collided", "safety_stops", "min_clearance_m"} <= set(header)
    assert entry["reasons"] == [{"reason": "the mission succeeded but the robot collided", "count": 1}]


# --------------------------------------------------------------------------------------------
# Sweeps


def test_sweep_gives_the_same_table_with_one_or_two_workers(tmp_path, capsys):
    common = [*SQUARE, "--sim", "lab,corridor", "--seeds", "0-1", "--set", "side=0.1,0.2"]
    assert sweep(*common, "--workers", "2", "-o", str(tmp_path / "two")) == 0
    out = capsys.readouterr().out
    assert sweep(*common, "--workers", "1", "-o", str(tmp_path / "one")) == 0
    one, two = rows_of(tmp_path / "one"), rows_of(tmp_path / "two")
    assert len(one) == 8 and [r["id"] for r in one] == sorted(r["id"] for r in one)  # sorted by id, not by finish
    assert [comparable(r) for r in one] == [comparable(r) for r in two]
    assert all(r["status"] == "SUCCESS" and r["ground_truth.trajectory_length_m"] > 0.3 for r in one)
    assert len({r["ground_truth.final_pose.x"] for r in one if r["world"] == "lab"}) == 4  # seeds differ
    report = json.loads((tmp_path / "one" / "reports" / f"{one[0]['id']}.json").read_text())
    assert report["status"] == "SUCCESS" and report["seed"] == one[0]["seed"] and "trajectory" in report["ground_truth"]
    summary = json.loads((tmp_path / "one" / "summary.json").read_text())
    assert [(s["world"], s["inputs.side"], s["episodes"]) for s in summary] == [
        ("corridor", 0.1, 2), ("corridor", 0.2, 2), ("lab", 0.1, 2), ("lab", 0.2, 2)]
    assert "side" in out and "100%" in out and "8 runs" in out


def test_resume_skips_recorded_episodes_and_a_torn_row_is_ignored(tmp_path, capsys):
    folder = tmp_path / "out"
    args = [*SQUARE, "--seeds", "0-2", "--set", "side=0.1", "--workers", "1", "-o", str(folder)]
    assert sweep(*SQUARE, "--seeds", "0", "--set", "side=0.1", "--workers", "1", "-o", str(folder)) == 0
    first = rows_of(folder)
    assert len(first) == 1
    with open(folder / "results.jsonl", "ab") as table:  # a writer killed in the middle of a row
        table.write(b'{"id":"square_empty_side=0.1_s0001_')
    with pytest.warns(TornLineWarning):
        assert len(load_table(folder)) == 1
    assert sweep(*args) == 2  # results there, and no --resume
    assert "already holds 1 results: add --resume" in capsys.readouterr().err
    assert sweep(*args, "--resume") == 0
    err = capsys.readouterr().err
    assert "bearings sweep: warning: " in err and "ignoring a torn last line" in err
    rows = rows_of(folder)
    assert [r["seed"] for r in rows] == [0, 1, 2]
    assert rows[0] == first[0]  # not run again: its row, wall times included, is the one recorded first
    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("error", TornLineWarning)  # the table was rewritten whole and sorted
        assert sweep("--summary", str(folder)) == 0
    assert capsys.readouterr().out.splitlines()[1].split()[:3] == ["square", "empty", "3"]


def test_the_table_ends_with_one_row_per_episode_the_last_written_sorted(tmp_path):
    folder = tmp_path / "out"
    episodes = grid("square", ["empty"], [0, 1], {"side": [0.1]}, max_time_s=30)
    first = run_sweep(episodes[1:], results_dir=folder)
    table = folder / "results.jsonl"
    stale = json.dumps({**first[0], "status": "ERROR", "reason": "an earlier try"})
    table.write_text(stale + "\n" + table.read_text())  # the same episode, an older row before it
    rows = run_sweep(episodes, results_dir=folder, resume=True)
    assert [r["seed"] for r in rows] == [0, 1] and rows[1] == first[0]
    assert rows_of(folder) == json.loads(json.dumps(rows, default=str))


def test_journal_writes_whole_lines_and_cuts_a_torn_tail(tmp_path):
    path = tmp_path / "results.jsonl"
    path.write_bytes(b'{"id":"a","x":1}\n{"id":"b","x"')
    with pytest.warns(TornLineWarning, match="torn last line"), Journal(path) as journal:
        journal.append({"id": "c", "x": 3})
    assert [r["id"] for r in read_rows(path)] == ["a", "c"]
    assert path.read_bytes().endswith(b'{"id":"c","x":3}\n')


@pytest.mark.parametrize(("args", "message"), [
    (["--seeds", "5-2"], "--seeds 5-2: the range 5-2 is empty"),
    (["--set", "x="], "--set x=: empty value"),
    (["--sim", "lab,nowhere"], "nowhere: no such world file or shipped world"),
    (["--set", "side=abc"], "input 'side' expects a number"),
    (["--set", "colour=red"], "unknown input 'colour'"),
    (["--timeout", "0"], "--timeout must be a finite number of seconds above 0, got 0"),
    (["--max-time", "inf"], "--max-time expects a finite number in s, got inf"),
    (["--seeds", "1-" + "9" * 5000], "--seeds: seeds go from 0 to 4294967295"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, args, message):
    assert sweep(*SQUARE, *args, "--workers", "1", "-o", str(tmp_path / "out")) == 2
    err = capsys.readouterr().err
    assert err.startswith("bearings sweep: ") and message in err and err.count("\n") == 1
    assert not (tmp_path / "out" / "results.jsonl").exists()


def test_unknown_mission_and_missing_output(tmp_path, capsys):
    assert sweep("no_such_mission", "--workers", "1", "-o", str(tmp_path)) == 2
    assert "no_such_mission: no such file" in capsys.readouterr().err
    assert sweep("square") == 2
    assert "-o RESULTS_DIR" in capsys.readouterr().err


def test_cluster_without_distributed_says_how_to_install(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    assert sweep(*SQUARE, "--cluster", "tcp://127.0.0.1:8786", "-o", str(tmp_path)) == 2
    assert "pip install 'bearings[cluster]'" in capsys.readouterr().err


def _fake_results(folder):
    folder.mkdir()
    rows = [{"id": f"e{w}{v}{s}", "mission": "m", "world": w, "seed": s, "max_time_s": None, "inputs.speed": v,
             "status": "SUCCESS", "sim_time_s": 10 + s, "ground_truth.goal_error_m": v * (1 + s) / 10}
            for w in ("lab", "corridor") for v in (0.2, 0.4) for s in range(3)]
    (folder / "results.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))


def test_summary_and_plot_of_earlier_results(tmp_path, capsys):
    _fake_results(tmp_path / "res")
    assert sweep("--summary", str(tmp_path / "res"), "--plot", "goal_error_m", "--against", "speed") == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].split()[:3] == ["world", "speed", "runs"]
    png = tmp_path / "res" / "ground_truth.goal_error_m-vs-inputs.speed.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f"plot: {png}" in out
    assert sweep("--summary", str(tmp_path / "res"), "--plot", "nope", "--against", "speed") == 2
    assert "no figure 'nope'" in capsys.readouterr().err


def test_plot_without_matplotlib_says_how_to_install(tmp_path, capsys, monkeypatch):
    _fake_results(tmp_path / "res")
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    assert sweep("--summary", str(tmp_path / "res"), "--plot", "goal_error_m", "--against", "speed") == 2
    assert "pip install 'bearings[plot]'" in capsys.readouterr().err


def test_api_runs_without_a_results_folder_and_forked_or_spawned_episodes_agree():
    episodes = grid("square", ["lab"], [0, 1], {"side": [0.1]}, max_time_s=30)
    seen = []
    forked = run_sweep(episodes, on_row=seen.append)
    assert [r["seed"] for r in forked] == [0, 1] and sorted(r["id"] for r in seen) == [r["id"] for r in forked]
    with local_executor(1) as executor:
        spawned = run_sweep(episodes[:1], executor=executor, start_method="spawn")
    assert comparable(spawned[0]) == comparable(forked[0])


def test_progress_line_counts_failures_and_estimates_the_rest():
    stream = io.StringIO()
    progress = Progress(total=10, resumed=2, stream=stream)
    progress.add({"status": "SUCCESS"})
    progress.add({"status": "ERROR"})
    lines = stream.getvalue().splitlines()
    assert lines[0].startswith("sweep: 3/10 done (2 resumed), 0 failed, elapsed 0:00, ETA ")
    assert lines[1].startswith("sweep: 4/10 done (2 resumed), 1 failed, elapsed 0:00, ETA 0:00")
    progress.finish()  # not a terminal: no redraw
    assert len(stream.getvalue().splitlines()) == 2


def test_bench_sweep_prints_named_figures(capsys):
    assert main(["bench", "sweep", "--quick", "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["area"] == "sweep" and figures["workers"] >= 1
    for key in ("episodes_per_s_1_worker", "episodes_per_s_n_workers", "scaling_ratio", "isolation_overhead_s"):
        assert figures[key] > 0
    expected = figures["episodes_per_s_n_workers"] / (figures["workers"] * figures["episodes_per_s_1_worker"])
    assert abs(figures["scaling_ratio"] - expected) < 0.01


def test_an_episode_can_start_at_a_chosen_pose():
    from experiments.sweep import Episode

    plain, placed = Episode("square", "lab", 1), Episode("square", "lab", 1, start="4.2,3.2,90deg")
    assert plain.id != placed.id and "start" not in plain.parameters
    assert placed.run_arguments("r.json")[-1] == "--start=4.2,3.2,90deg"
