"""``bearings bench tree``: one JSON object of named figures on a 30-node tree (no timing asserts)."""

from __future__ import annotations

import json

from missions.cli import main


def test_bench_tree_prints_named_figures(capsys):
    assert main(["bench", "tree", "--quick", "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["area"] == "tree" and figures["task_tree_nodes"] == 30 and figures["ticks"] == 300
    for key in ("py_trees_tick_us", "runner_tick_us", "runner_tick_with_sim_us", "runner_overhead_ratio",
                "monitor_check_us", "monitor_check_ratio"):
        assert figures[key] > 0
    ratio = figures["runner_tick_us"] / figures["py_trees_tick_us"]
    assert abs(figures["runner_overhead_ratio"] - ratio) < 0.01  # the ratio is of the figures reported
