"""The end-of-run line: collisions, clearance and safety stops always; each capability's declared headline."""

from __future__ import annotations

from behaviours.telemetry import Figure, Sections, section
from missions.cli import main
from missions.summary import declared_headline, figure_text, summary_line


def test_headline_figures_are_declared_next_to_the_figures():
    gathered = Sections()
    gathered.add(section("ltmap", {"viewframes": 12, "bytes": 900, "map_file": "/x/route.ltmap"},
                         headline=("viewframes", "map_file")))
    gathered.add([Figure("ltmap", "switches", 11, headline=True), Figure("ltmap", "switches", 12, headline=True)])
    assert gathered.headline == ["ltmap.viewframes", "ltmap.map_file", "ltmap.switches"]

    class Observer:
        HEADLINE = ("ground_truth.goal_error_m",)

    assert declared_headline([Observer(), object()], gathered.headline)[0] == "ground_truth.goal_error_m"


def test_the_line_always_shows_collisions_clearance_and_safety_stops_when_the_report_has_them():
    report = {"ground_truth": {"collisions": 2, "min_clearance_m": 0.0512, "goal_error_m": 0.2104,
                               "trajectory_length_m": 5.0},
              "safety": {"safety_stops": 3}, "exploration": {"explored_area_m2": 34.2, "done": True},
              "headline": ["ground_truth.goal_error_m", "exploration.explored_area_m2", "exploration.done",
                           "ltmap.missing"]}
    assert summary_line(report) == ("ground truth: collisions 2, min clearance 0.051 m, goal error 0.210 m; "
                                    "safety: safety stops 3; exploration: explored area 34.200 m^2, done yes")
    assert summary_line({"status": "SUCCESS"}) == ""


def test_figure_text_reads_units_from_the_name():
    assert figure_text("stalled_time_s", 1.5) == "stalled time 1.500 s"
    assert figure_text("repeat.switches", 4) == "repeat switches 4"


def test_a_run_prints_its_collisions_and_the_report_lists_the_headline(tmp_path, capsys):
    report = tmp_path / "r.json"
    assert main(["run", "square", "--sim", "lab", "--quiet", "--set", "side=0.5", "--report", str(report)]) == 0
    out = capsys.readouterr().out
    assert "ground truth: collisions 0, min clearance " in out and ", goal error " in out
    import json

    headline = json.loads(report.read_text())["headline"]
    assert headline[:2] == ["ground_truth.goal_error_m", "ground_truth.path_error_m"]
