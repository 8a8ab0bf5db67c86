"""Hostile input, from the reliability audit: each reproduction ends in a located error and exit 2,
never a traceback, a hang or a file damaged."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from drivers.sim.world import load_world
from maps.store import MAX_FILE_BYTES, InputError
from missions.cli import main
from missions.loader import load_mission


def _messages(path: Path, **kwargs) -> list[str]:
    with pytest.raises(InputError) as info:
        load_mission(path, **kwargs)
    return [str(d) for d in info.value.diagnostics]


@pytest.mark.parametrize(("value", "expected"), [
    ("!!int ten", "'ten' cannot be read as int"), ("!!float ten", "'ten' cannot be read as float"),
    ("!!timestamp 2020-99-99", "'2020-99-99' cannot be read as timestamp"),
])
def test_explicit_tags_with_bad_values(write_mission, value, expected):
    [message] = _messages(write_mission(f"rate: {value}\ntree: Stop\n"))
    assert message.endswith(f":1:7: malformed YAML: {expected} (ValueError)")


def test_an_include_bomb_is_stopped_quickly(write_mission):
    for level in range(30):
        write_mission(f"tree:\n  Sequence:\n    children:\n      - include: b{level + 1}.yaml\n"
                      f"      - include: b{level + 1}.yaml\n", name=f"b{level}.yaml")
    write_mission("tree: Stop\n", name="b30.yaml")
    started = time.monotonic()
    messages = _messages(write_mission("tree: {include: b0.yaml}\n", name="top.yaml"))
    assert time.monotonic() - started < 10
    assert any("expands to more than 10000 nodes" in m for m in messages)


def test_files_have_a_size_limit(tmp_path, capsys):
    big = tmp_path / "big.yaml"
    big.write_bytes(b"tree: Stop\n#" + b"x" * MAX_FILE_BYTES)
    assert any("larger than 16 MB" in m for m in _messages(big))
    assert main(["validate", "/dev/zero"]) == 2
    assert "/dev/zero: is a device or socket, not a regular file" in capsys.readouterr().err


def test_a_typo_inside_a_longer_text_is_refused(write_mission):
    messages = _messages(write_mission("inputs: {side: 1.0}\ntree:\n  Sequence:\n    name: 'square of ${sidee} m'\n"
                                       "    children: [Stop]\n"))
    assert any(":4:11: unknown input ${sidee}; did you mean 'side'?" in m for m in messages)


def test_numbers_are_checked_however_they_arrive(write_mission, capsys):
    path = write_mission("inputs: {side: {type: float, default: 1.0}}\ntree: {Drive: {distance: '${side}'}}\n")
    assert load_mission(path, overrides={"side": "1e-3"}).tree.inputs["distance"] == pytest.approx(0.001)
    for args, expected in ((["--max-time", "nan"], "command line: --max-time expects a finite number"),
                           (["--seed", "-1"], "command line: --seed must be >= 0, got -1"),
                           (["--rate", "0"], "command line: --rate must be >= 0.1 Hz, got 0.0"),
                           (["--set", "side=.inf"], "--set: input 'side' expects a finite number, got inf")):
        assert main(["run", str(path), "--quiet", *args]) == 2, args
        assert expected in capsys.readouterr().err, args


def test_outputs_are_checked_before_anything_runs(write_mission, tmp_path, capsys):
    path = write_mission("tree: {Wait: {duration: 100000}}\n")  # would run for a long time
    started = time.monotonic()
    assert main(["run", str(path), "--quiet", "--report", str(tmp_path)]) == 2
    assert main(["run", str(path), "--quiet", "--save", "/dev/full"]) == 2
    assert main(["run", str(path), "--quiet", "--report", str(tmp_path / "no" / "such" / "r.json")]) == 2
    assert time.monotonic() - started < 10
    err = capsys.readouterr().err
    assert f"--report {tmp_path}: is a directory" in err
    assert "--save /dev/full: is not a regular file" in err
    assert "does not exist" in err and "recording:" not in err


PLUGIN = """
from py_trees.common import Status
from behaviours.base import BearingsBehaviour
from behaviours.registry import register

@register
class {name}(BearingsBehaviour):
    '''A test plugin.'''
    def update(self):
        return Status.SUCCESS
"""


def test_plugins_come_only_from_the_missions_folder_or_named_modules(tmp_path):
    outside = tmp_path / "outside.py"
    outside.write_text(PLUGIN.format(name="Outside"))
    folder = tmp_path / "mission"
    folder.mkdir()
    for spec in ("../outside.py", str(outside)):
        path = folder / "m.yaml"
        path.write_text(f"plugins: ['{spec}']\ntree: Stop\n")
        assert any("is outside the mission's folder" in m for m in _messages(path)), spec


def test_a_plugin_that_exits_while_importing_is_a_located_error(write_mission, tmp_path):
    (tmp_path / "leaves.py").write_text("import sys\nsys.exit(5)\n")
    [message] = _messages(write_mission("plugins: [leaves.py]\ntree: Stop\n"))
    assert message.endswith(":1:11: plugin 'leaves.py' exited while being imported (exit code 5)")


def test_two_plugin_files_with_one_name_in_two_folders_do_not_clash(tmp_path):
    missions = []
    for name in ("Alpha", "Beta"):
        folder = tmp_path / name.lower()
        folder.mkdir()
        (folder / "nodes.py").write_text(PLUGIN.format(name=name))
        (folder / "m.yaml").write_text(f"plugins: [nodes.py]\ntree: {name}\n")
        missions.append(load_mission(folder / "m.yaml"))
    assert [m.tree.type for m in missions] == ["Alpha", "Beta"]


def test_includes_stay_in_the_missions_folder_unless_a_search_path_allows_more(tmp_path):
    folder = tmp_path / "mission"
    folder.mkdir()
    (tmp_path / "shared.yaml").write_text("tree: Stop\n")
    for target in ("/etc/passwd", "../shared.yaml"):
        path = folder / "m.yaml"
        path.write_text(f"tree: {{include: '{target}'}}\n")
        assert any("cannot find included mission" in m for m in _messages(path)), target
    path.write_text("tree: {include: shared.yaml}\n")
    assert load_mission(path, search_path=[tmp_path]).tree.type == "Stop"


@pytest.mark.parametrize(("text", "expected"), [
    ("walls: [{points: [[0, 5], [5, 5]], height: 1.0e+5}]\n", "walls[0].height must be <= 100 m, got 100000.0"),
    ("walls: [{points: [[0, 5], [1.0e+308, 5]], height: 2}]\n", "walls[0].points[1][0] must be <= 10000 m"),
    ("seed: -5\n", "seed must be >= 0, got -5"),
    ("pillars: [{center: [5, 5], radius: 1.0e+4, height: 2}]\n", "pillars[0].radius must be <= 100 m"),
    ("pillars: [{center: [5, 5], radius: 90, height: 2}]\n", "its texture would be 33929 texels long"),
    ("walls: [{points: [[-1, 0.1], [1, 0.1]], height: 2}]\n", "the robot's start (0, 0) is not in free space"),
])
def test_world_quantities_are_bounded(world_file, text, expected):
    with pytest.raises(InputError) as info:
        load_world(world_file(text))
    assert any(expected in d.message for d in info.value.diagnostics), info.value


def test_many_landmarks_are_fine_and_too_many_are_refused_clearly(world_file):
    rows = "".join(f"  - {{position: [{i % 100}, {i // 100 + 2}, 1]}}\n" for i in range(60_000))
    assert len(load_world(world_file("landmarks:\n" + rows)).landmarks) == 60_000


def test_a_bad_world_is_invalid_input_for_run_and_snapshot(world_file, capsys):
    path = world_file("walls: [{points: [[0, 5], [5, 5]], height: 1.0e+5}]\n")
    assert main(["run", "square", "--sim", str(path), "--quiet"]) == 2
    assert main(["sim", "snapshot", "--world", str(path), "--pose", "1,1,0", "-o", "/tmp/never.png"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("walls[0].height must be <= 100 m") == 2


def test_a_report_records_the_zero_velocity_it_ends_with(tmp_path):
    report = tmp_path / "r.json"
    assert main(["run", "square", "--quiet", "--max-time", "3", "--report", str(report)]) == 1
    assert json.loads(report.read_text())["last_command"] == {"v": 0.0, "w": 0.0}


@pytest.mark.parametrize(("args", "expected"), [
    (["--pose", "1e308,1,0"], "--pose: x and y must be within 10000 m"),
    (["--pose", "1,1,0", "--seed", "-4"], "command line: --seed must be >= 0, got -4"),
    (["--pose", "nan,1,0"], "--pose: finite numbers expected"),
    (["--pose", "1,1,0", "--pan", "inf"], "--pan and --tilt must be finite"),
])
def test_snapshot_numbers_are_bounded(tmp_path, capsys, args, expected):
    assert main(["sim", "snapshot", "--world", "lab", *args, "-o", str(tmp_path / "s.png")]) == 2
    err = capsys.readouterr().err
    assert expected in err and "Traceback" not in err


def test_a_foreign_file_is_named_in_one_short_line(capsys):
    assert main(["sim", "snapshot", "--world", "/etc/passwd", "--pose", "1,1", "-o", "/tmp/never.png"]) == 2
    [line, _count] = capsys.readouterr().err.splitlines()
    assert line.startswith("/etc/passwd:1:1: a world file must be a mapping") and len(line) < 160


def test_a_simulated_run_starts_where_told_and_only_in_free_space(tmp_path, capsys):
    report = tmp_path / "r.json"
    assert main(["run", "square", "--sim", "lab", "--start=4.2,3.2,90deg", "--quiet", "--report", str(report),
                 "--max-time", "0.5"]) == 1
    first = json.loads(report.read_text())["ground_truth"]["trajectory"][0]
    assert first[1:3] == pytest.approx([4.2, 3.2]) and first[3] == pytest.approx(1.5708, abs=1e-4)
    for start, expected in (("0.1,0.1,0", "--start: the pose (0.1, 0.1) is not in free space"),
                            ("nowhere", "--start must be x,y,theta or a named pose"),
                            ("1e9,0", "--start: x and y must be within 10000 m"),
                            ("4.2,3.2,-93.6", "theta -93.6 rad is more than a full turn; degrees take a deg suffix "
                                              "(4.2,3.2,-93.6deg)")):
        assert main(["run", "square", "--sim", "lab", f"--start={start}", "--quiet"]) == 2
        assert expected in capsys.readouterr().err, start
