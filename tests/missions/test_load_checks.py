"""A target name is checked against the roadmap file at load time, when the file exists."""

from __future__ import annotations

import pytest

from maps.roadmap import Roadmap
from maps.store import InputError
from missions.cli import main
from missions.loader import load_mission
from perception.geometry import Pose2D


@pytest.fixture
def roadmap(tmp_path):
    path = tmp_path / "lab.roadmap"
    Roadmap().with_target("door", Pose2D(), "door.png").with_target("window", Pose2D(1.0, 0.0)).save(path)
    return path


def test_an_unknown_target_is_refused_at_load_with_a_did_you_mean(roadmap):
    with pytest.raises(InputError, match=r"no target named 'dor' in the roadmap; did you mean 'door'\? "
                                         r"\(it has: door, window\)"):
        load_mission("goto_target", overrides={"roadmap": str(roadmap), "target": "dor"}, require_inputs=True)
    assert load_mission("goto_target", overrides={"roadmap": str(roadmap), "target": "window"}).tree is not None


def test_without_the_file_yet_the_target_is_left_to_the_run(tmp_path):
    later = tmp_path / "written-later.roadmap"  # learn_targets may write it earlier in the same mission
    assert load_mission("goto_target", overrides={"roadmap": str(later), "target": "door"}).tree is not None


def test_bearings_run_exits_2_before_anything_moves(roadmap, tmp_path, capsys):
    report = tmp_path / "r.json"
    code = main(["run", "goto_target", "--sim", "lab", "--quiet", "--report", str(report),
                 "--set", f"roadmap={roadmap}", "--set", "target=kitchen"])
    assert code == 2 and not report.exists()
    assert "no target named 'kitchen' in the roadmap" in capsys.readouterr().err
