"""A required input (no default) is checked by type when a mission is only checked, and stops a run at load."""

from __future__ import annotations

import pytest

from maps.store import InputError
from missions.cli import main
from missions.inputs import Unbound
from missions.loader import load_mission

MISSION = "mission: m\ninputs:\n  d: {type: float, unit: m}\ntree:\n  Drive: {distance: '${d}', name: 'drive ${d}'}\n"


def test_checking_a_mission_leaves_a_required_input_unbound(write_mission):
    mission = load_mission(write_mission(MISSION))
    assert mission.values["d"] == Unbound("d", float)
    assert mission.tree.name == "drive ${d}" and mission.tree.inputs["distance"] == Unbound("d", float)


def test_an_unbound_input_of_the_wrong_type_is_still_a_problem(write_mission):
    with pytest.raises(InputError, match=r"Drive.distance takes float, but input \$\{d\} is str"):
        load_mission(write_mission(MISSION.replace("type: float", "type: str")))


def test_a_mission_to_run_needs_every_required_input(write_mission):
    path = write_mission(MISSION)
    with pytest.raises(InputError, match=r"input 'd' is required: give it with --set d=VALUE"):
        load_mission(path, require_inputs=True)
    assert load_mission(path, overrides={"d": "0.2"}, require_inputs=True).tree.inputs["distance"] == 0.2


def test_validate_passes_and_run_exits_2_before_anything_moves(write_mission, tmp_path, capsys):
    path = write_mission(MISSION)
    assert main(["validate", str(path)]) == 0
    report = tmp_path / "r.json"
    assert main(["run", str(path), "--quiet", "--report", str(report)]) == 2
    assert not report.exists()
    assert "input 'd' is required" in capsys.readouterr().err


def test_a_misspelt_shipped_mission_gets_a_did_you_mean(capsys):
    assert main(["run", "sqare", "--quiet"]) == 2
    assert "sqare: no such file, and no shipped mission of that name; did you mean 'square'?" in capsys.readouterr().err


def test_bearings_missions_lists_the_shipped_missions_with_their_required_inputs(capsys):
    assert main(["missions"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("explore: Explore with the stereo pair") and "square: Drive a square" in out
    assert "inputs: target (required), roadmap, seed" in out


def test_top_level_input_and_data_flow_problems_come_together(write_mission):
    guard = "Guard: {key: /map/nothing, op: '==', value: 1, child: {Drive: {distance: '${d}'}}}"
    path = write_mission(f"mission: m\nrate: -1\ninputs: {{d: 1.0}}\ntree:\n  {guard}\n")
    with pytest.raises(InputError) as info:
        load_mission(path, overrides={"d": "far"})
    said = str(info.value)
    assert "rate" in said and "input 'd' expects a number" in said
    assert "reads /map/nothing, which nothing writes" in said
