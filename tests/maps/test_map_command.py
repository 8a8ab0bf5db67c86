"""``bearings map info | prune`` through the command line entry point."""

from __future__ import annotations

import json

import numpy as np
import pytest

from maps.ltmap.file import load_ltmap, save_ltmap
from maps.ltmap.learner import RouteLearner
from missions.cli import main
from missions.commands.map import parse_byte_size
from perception.synthetic_route import make_route_world, observe_route, straight_route


@pytest.fixture(scope="module")
def route_file(tmp_path_factory):
    world, rng, learner = make_route_world(5, length=4.0, n_near=400), np.random.default_rng(6), RouteLearner()
    for pose in straight_route(4.0, 0.05):
        learner.observe(observe_route(world, pose, rng, noise_deg=0.1), pose.theta, (pose.x, pose.y))
    learner.finish()
    path = tmp_path_factory.mktemp("maps") / "route.ltmap"
    save_ltmap(path, learner.tree)
    return path


def test_info_prints_the_tree(route_file, capsys):
    assert main(["map", "info", str(route_file)]) == 0
    text = capsys.readouterr().out
    summary = load_ltmap(route_file).summary()
    for name, value in (("viewframes", summary.viewframes), ("landmarks", summary.landmarks),
                        ("height", summary.height), ("bytes", summary.memory_bytes)):
        assert f"{name:<13}{value}" in text
    assert " ".join(map(str, summary.landmarks_per_level)) in text
    # the first viewframe is made at the second image (0.05 m), the goal at 4 m: 3.95 m along x
    assert "places       taught odometry, 3.9 m from the first viewframe to the last" in text


def test_info_says_when_a_map_has_no_places(tmp_path, capsys):
    world, rng, learner = make_route_world(5, length=1.0, n_near=400), np.random.default_rng(6), RouteLearner()
    for pose in straight_route(1.0, 0.05):
        learner.observe(observe_route(world, pose, rng, noise_deg=0.1), pose.theta)
    learner.finish()
    save_ltmap(tmp_path / "old.ltmap", learner.tree)
    assert main(["map", "info", str(tmp_path / "old.ltmap")]) == 0
    assert "places       none (followed by vision alone" in capsys.readouterr().out
    assert main(["map", "info", str(tmp_path / "old.ltmap"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["places"] is False


def test_info_json(route_file, capsys):
    assert main(["map", "info", str(route_file), "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    summary = load_ltmap(route_file).summary()
    assert figures["bytes"] == summary.memory_bytes and figures["height"] == summary.height
    assert sum(figures["landmarks_per_level"]) == figures["landmarks"] == summary.landmarks
    assert figures["places"] is True


def test_prune_writes_a_map_within_the_budget(route_file, tmp_path, capsys):
    full = load_ltmap(route_file).memory_bytes()
    budget = full // 3
    out = tmp_path / "small.ltmap"
    assert main(["map", "prune", str(route_file), "--budget", f"{budget}B", "-o", str(out)]) == 0
    pruned = load_ltmap(out)
    assert pruned.memory_bytes() <= budget < full and pruned.height < load_ltmap(route_file).height
    assert f"wrote {out}" in capsys.readouterr().out
    assert load_ltmap(route_file).memory_bytes() == full  # the input is left alone


def test_a_budget_the_map_cannot_meet_writes_nothing(route_file, tmp_path, capsys):
    out = tmp_path / "tiny.ltmap"
    assert main(["map", "prune", str(route_file), "--budget", "1KB", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "cannot prune to 1000 bytes" in err and err.count("\n") == 1 and not out.exists()


@pytest.mark.parametrize("text", ["", "KB", "-5KB", "0", "0.5B", "12XB", "1e3KB", "nan", "2TiB", "5 K B"])
def test_bad_budgets_are_one_line_and_exit_2(route_file, tmp_path, capsys, text):
    out = tmp_path / "out.ltmap"
    assert main(["map", "prune", str(route_file), f"--budget={text}", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("bearings map: --budget:") and err.count("\n") == 1 and not out.exists()


@pytest.mark.parametrize(("text", "size"), [("200KB", 200_000), ("200kb", 200_000), ("1.5MiB", 1_572_864),
                                            ("2 KiB", 2048), ("50000", 50_000), ("3MB", 3_000_000), ("1GiB", 2**30),
                                            ("1.9B", 1)])
def test_budget_units(text, size):
    assert parse_byte_size(text) == size


def test_damaged_and_missing_files_are_one_line(route_file, tmp_path, capsys):
    damaged = tmp_path / "damaged.ltmap"
    damaged.write_bytes(route_file.read_bytes()[:-100])
    for path, message in ((damaged, "truncated"), (tmp_path / "none.ltmap", "no such file")):
        assert main(["map", "info", str(path)]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1
    assert main(["map", "prune", str(damaged), "--budget", "1MB", "-o", str(tmp_path / "o.ltmap")]) == 2


def test_help_explains(capsys):
    with pytest.raises(SystemExit) as done:
        main(["map", "prune", "--help"])
    assert done.value.code == 0
    text = capsys.readouterr().out
    assert "KiB" in text and "exit codes" in text and "first and" in text
    assert main(["map"]) == 2  # no subcommand: the help, as invalid input
