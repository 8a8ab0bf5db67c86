"""``bearings eval ltmap``: the default route on any world, the Table-I figures, and the whole
evaluation on a small world file written here (ideal bearings sensor, one seed: a fast run; the
rendered-panorama tables of lab and outdoor are measured by hand)."""

from __future__ import annotations

import importlib
import json
import math

import numpy as np
import pytest

from drivers.sim.simulation import path_distances
from drivers.sim.world import load_world
from experiments.eval import AREAS
from experiments.eval.ltmap import (
    Level,
    Run,
    check_options,
    follow_episode,
    format_table,
    goal_tolerance,
    repeat_figures,
    teach_episode,
    viewframe_errors,
)
from experiments.eval.ltmap_route import MARGINS, MIN_END, Floor, default_route, parse_route
from experiments.sweep import Episode
from missions.cli import main
from perception.geometry import frame_to_parent

# A 6 x 4 m room with a box and a pillar, landmarks on the walls and the furniture, the robot
# starting in a corner facing the room's far end.
ROOM = """
name: small_room
start: {x: 1.0, y: 1.0, theta_deg: 20}
walls:
  - {points: [[0, 0], [6, 0], [6, 4], [0, 4]], closed: true, height: 2.5}
boxes:
  - {center: [3.0, 3.6], size: [1.2, 0.6], height: 0.8}
pillars:
  - {center: [3.2, 1.6], radius: 0.15, height: 2.5}
landmarks:
"""
ROOM += "".join(f"  - {{position: [{x}, {y}, {z}]}}\n" for x, y, z in (
    (0, 0.4, 2.0), (0, 1, 1.2), (0, 1.6, 0.6), (0, 2.2, 1.8), (0, 2.8, 2.3), (0, 3.3, 1.0), (0.5, 4, 0.7),
    (1, 4, 1.5), (1.6, 4, 2.3), (2.2, 4, 2.0), (3.3, 4, 1.6), (4, 4, 1.1), (4.7, 4, 2.2), (5.2, 4, 1.7),
    (5.7, 4, 0.9), (6, 3.7, 2.2), (6, 3.2, 1.3), (6, 2.6, 0.7), (6, 2, 2.1), (6, 1.4, 1.6), (6, 0.8, 1.0),
    (6, 0.3, 2.2), (5, 0, 1.6), (4.4, 0, 0.6), (3.8, 0, 1.2), (3.1, 0, 1.8), (2.5, 0, 2.0), (1.8, 0, 0.8),
    (1.2, 0, 1.4), (0.6, 0, 2.2), (3.2, 1.6, 1.5), (3.0, 3.3, 0.8), (2.0, 2.0, 2.5), (4.5, 2.5, 2.5)))
SHORT_ROUTE = "1.5,0,2.5,0.8"  # m, odometry frame: 2.7 m past the pillar

def test_the_default_route_is_a_bent_tour_of_the_free_floor(world_file):
    world = load_world(world_file(ROOM))
    route = default_route(world)
    start = world.start
    assert route.source == "tour" and route.margin_m in MARGINS
    assert route.world_xy[0].tolist() == [start.x, start.y]
    odometry = np.reshape(route.odometry, (-1, 2))
    np.testing.assert_allclose(frame_to_parent(start, odometry), route.world_xy[1:], atol=1e-9)
    floor = Floor.around(world, (-1.0, -1.0, 7.0, 5.0))
    legs = zip(route.world_xy[:-1], route.world_xy[1:], strict=True)
    along = np.concatenate([np.linspace(a, b, 50) for a, b in legs])
    assert floor.grid.reachable_at(along).all()  # never closer than the robot's radius to a wall, box or pillar
    assert math.dist(route.world_xy[0], route.world_xy[-1]) >= MIN_END and route.length_m > 3.0
    assert len(route.world_xy) >= 3  # it turns: not a straight line


def test_the_default_route_on_an_open_plane_and_in_a_cupboard(world_file):
    plane = load_world(world_file("start: {x: 500.0, y: -200.0, theta_deg: 90}\n"))
    route = default_route(plane)  # only the floor around the start is looked at
    end = route.odometry[-2:]
    assert end[0] > 3.5 and abs(end[1]) < 0.5  # straight ahead of the start heading, as far as it goes
    assert 5.0 < route.length_m < 7.0 and route.margin_m == MARGINS[0]
    cupboard = load_world(world_file("start: {x: 0.5, y: 0.5}\nwalls: [{points: [[0, 0], [1.1, 0], [1.1, 1.1], "
                                     "[0, 1.1]], closed: true, height: 2}]\n"))
    with pytest.raises(ValueError, match="no room for a route"):
        default_route(cupboard)


def test_options_are_checked_against_the_world(world_file):
    path = str(world_file(ROOM))
    settings = check_options(path, {"camera": "landmarks", "route": "[1.5, 0, 2.5, 0.8]", "goal_tolerance": "0.3"})
    assert settings.route.source == "given" and settings.route.odometry == [1.5, 0.0, 2.5, 0.8]
    assert settings.goal_tolerance == 0.3 and settings.min_landmarks is None
    for extra, message in [({"camera": "front"}, "not a panorama or bearings camera"),
                           ({"route": "1,2,3"}, "even number"),
                           ({"route": "9,0"}, "waypoint 0 .* not on the floor"),
                           ({"route": "1.521,0.085,3.024,-0.462"}, "leg to waypoint 1 passes"),  # across the pillar
                           ({"min_landmarks": "-1"}, ">= 0"),
                           ({"goal_tolerance": "nan"}, "positive"),
                           ({"rotation": "gyro"}, "zinf, compass"),
                           ({"gap_filling": "yes"}, "on or off"),
                           ({"route": "loop"}, "numbers x0,y0"),
                           ({"cuts": "-1"}, "cuts must be >= 0"),
                           ({"cuts": "all"}, "cuts: an integer")]:
        with pytest.raises(ValueError, match=message):
            check_options(path, extra)
    assert parse_route("1, 2,3,4") == [1.0, 2.0, 3.0, 4.0]
    assert check_options(path, {"camera": "landmarks"}).rotation == "zinf"
    assert check_options(path, {"camera": "landmarks"}).cuts is None
    assert check_options(path, {"camera": "landmarks", "cuts": "0"}).cuts == 0
    assert check_options(path, {"camera": "landmarks", "rotation": "compass"}).rotation == "compass"


def test_the_route_back_retraces_the_tour_and_ends_a_third_of_the_way_out(world_file):
    world = load_world(world_file(ROOM))
    tour, back = default_route(world), check_options(str(world_file(ROOM)), {"route": "back"}).route
    assert back.source == "back" and back.margin_m == tour.margin_m
    assert np.array_equal(back.world_xy[:len(tour.world_xy)], tour.world_xy)  # out along the tour
    returned = back.world_xy[len(tour.world_xy) - 1:]  # and back along its legs, reversed
    along = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(returned, axis=0).T))))
    assert along[-1] == pytest.approx(2.0 / 3.0 * tour.length_m) and back.length_m == pytest.approx(
        5.0 / 3.0 * tour.length_m)
    assert np.all(path_distances(returned, tour.world_xy) < 1e-9)  # every point of the way back on the tour
    np.testing.assert_allclose(frame_to_parent(world.start, np.reshape(back.odometry, (-1, 2))), back.world_xy[1:],
                               atol=1e-9)


def test_gap_filling_off_is_an_input_of_the_teach_and_the_default_keeps_the_ids(world_file, tmp_path):
    path = str(world_file(ROOM))
    on, off = (check_options(path, {"camera": "landmarks", "gap_filling": v}) for v in ("on", "off"))
    assert on.gap_filling and not off.gap_filling
    taught_on, taught_off = (teach_episode(path, 0, s, tmp_path, None) for s in (on, off))
    assert "gap_filling" not in taught_on.inputs and taught_off.inputs["gap_filling"] is False
    assert taught_on.inputs["map"] != taught_off.inputs["map"]  # one results folder can hold both


def test_the_compass_repeat_carries_its_rotation_and_the_default_keeps_the_ids():
    teach = Episode("teach_route", "lab", 0, {"map": "m.ltmap", "camera": "panorama"})
    report = {"ground_truth": {"final_pose": {"x": 1.0, "y": 2.0, "theta": 0.5}}, "sim_time_s": 10.0}
    level = Level(cut=0, height=4, viewframes=10, landmarks=1000, bytes=50_000, fraction=1.0)
    default = follow_episode(teach, report, level, 50, None)
    compass = follow_episode(teach, report, level, 50, None, "compass")
    assert "rotation" not in default.inputs and compass.inputs["rotation"] == "compass"
    assert default.id != compass.id


def _report(rows, **sections):
    return {"status": "SUCCESS", "ground_truth": {"trajectory": rows}, **sections}


def test_viewframes_are_matched_through_times_and_sources():
    # taught along x at 1 m/s: viewframes 0, 1, 2 at x = 0, 1, 2
    teach = _report([[t, float(t), 0.0, 0.0] for t in range(4)],
                    ltmap={"taught": [{"viewframe": i, "time_s": float(i)} for i in range(3)]})
    # repeated back along y = 0.1 from x = 2; the pruned map kept taught viewframes 0 and 2
    repeat = _report([[t, 2.0 - t, 0.1, math.pi] for t in range(3)],
                     ltmap={"viewframes": 2, "viewframe_source": [0, 2],
                            "reached": [{"viewframe": 1, "time_s": 0.0}, {"viewframe": 0, "time_s": 1.5}]})
    taught = Run.of(teach)
    assert viewframe_errors(taught, Run.of(repeat)) == pytest.approx([0.1, math.hypot(0.5, 0.1)])
    assert goal_tolerance(taught, robot_radius=0.26, given=None) == pytest.approx(1.0)  # the viewframes' spacing
    assert goal_tolerance(taught, robot_radius=0.6, given=None) == pytest.approx(1.2)  # the robot's diameter
    assert goal_tolerance(taught, robot_radius=0.26, given=0.3) == 0.3
    level = Level(cut=1, height=1, viewframes=2, landmarks=40, bytes=900, fraction=0.5)
    figures = repeat_figures(taught, repeat, level, tolerance=0.5)
    assert figures["path_error_m"] == pytest.approx(0.1) and figures["goal_error_m"] == pytest.approx(0.1)
    assert figures["reached"] and figures["viewframes_reached"] == 1.0
    assert not repeat_figures(taught, repeat, level, tolerance=0.05)["reached"]
    assert not repeat_figures(taught, {**repeat, "status": "FAILURE"}, level, tolerance=0.5)["reached"]
    assert figures["bytes_per_m"] == pytest.approx(900 / 3.0)  # taught along 3 m
    assert figures["estimates_pct"] is None  # a report without the counts
    counted = repeat_figures(taught, {**repeat, "ltmap": {**repeat["ltmap"], "estimates": {
        "zinf_1deg": 6, "zinf_4deg": 2, "compass": 1, "lost": 1}}}, level, tolerance=0.5)
    assert counted["estimates_pct"] == {"zinf_1deg": 60.0, "zinf_2deg": 0.0, "zinf_4deg": 20.0, "zinf_8deg": 0.0,
                                        "compass": 10.0, "no_rotation": 0.0, "lost": 10.0}
    touched = {**repeat, "ground_truth": {**repeat["ground_truth"], "collisions": 1, "min_clearance_m": 0.0},
               "safety": {"safety_stops": 2}}  # home, but it touched something on the way: not reached
    collided = repeat_figures(taught, touched, level, tolerance=0.5)
    assert not collided["reached"] and (collided["collisions"], collided["safety_stops"]) == (1, 2)
    assert (figures["collisions"], figures["safety_stops"], figures["min_clearance_m"]) == (0, 0, None)
    assert repeat_figures(taught, None, level, tolerance=0.5) | {"reached": False} == {
        "cut": 1, "height": 1, "viewframes": 2, "landmarks": 40, "bytes": 900, "memory_fraction": 0.5,
        "status": "ERROR", "reached": False}


def test_the_evaluation_on_a_small_world_file(world_file, tmp_path, capsys):
    world, out = str(world_file(ROOM)), tmp_path / "eval"
    args = ["eval", "ltmap", "--world", world, "--seeds", "1", "--workers", "2", "-o", str(out),
            "--option", "camera=landmarks", "--option", f"route={SHORT_ROUTE}"]
    assert main([*args, "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["area"] == "ltmap" and figures["world"] == "small_room" and figures["taught"] == 1
    assert figures["route_source"] == "given" and figures["route"] == [1.5, 0.0, 2.5, 0.8]
    rows = figures["rows"]
    assert [r["levels_cut"] for r in rows] == list(range(len(rows))) and len(rows) >= 2
    assert rows[0]["memory_pct"] == 100.0 and rows[0]["viewframes"] == figures["teach.viewframes"]
    assert all(a["memory_pct"] > b["memory_pct"] for a, b in zip(rows[:-1], rows[1:], strict=True))
    assert rows[0]["height"] == figures["teach.height"] and rows[-1]["height"] == 0
    assert figures["full.goal_reached"] == 1 and figures["full.path_error_m"] < 0.2  # the full tree leads home
    assert figures["full.collisions"] == 0 and figures["teach.collisions"] == 0
    assert figures["full.viewframe_error_m"] < 0.6
    shares = rows[0]["estimates_pct"]  # every estimate of the full tree's repeat counted by its rule
    assert shares.keys() == {"zinf_1deg", "zinf_2deg", "zinf_4deg", "zinf_8deg", "compass", "no_rotation", "lost"}
    assert sum(shares.values()) == pytest.approx(100.0)
    assert rows[0]["bytes_per_m"] == pytest.approx(rows[0]["bytes"] / figures["teach.path_length_m"])
    assert all(r["map_as_expected"] for r in figures["runs"]) and "warning" not in figures
    assert len((out / "results.jsonl").read_text().splitlines()) == 1 + len(rows)  # a teach, a repeat per height
    assert list((out / "maps").iterdir())
    # the table again from the same folder: nothing runs again
    assert main([*args, "--resume"]) == 0
    table = capsys.readouterr().out
    assert "small_room" in table and "goal reached by every seed down to" in table
    assert "on the full map 1 of 1, the rate 95 % 0.21-1.00 (Wilson)" in table  # one seed says little
    teaching = next(line for line in table.splitlines() if line.startswith("teaching: "))
    clearance = float(teaching.split("clear ")[1])  # the closest the robot's disc came to anything
    assert teaching.startswith("teaching: 0 coll, 0 stops, clear ") and 0.05 < clearance < 1.0
    assert len(table.splitlines()) == 7 + len(rows)
    assert len((out / "results.jsonl").read_text().splitlines()) == 1 + len(rows)
    assert format_table(figures) == table.rstrip("\n")
    # the full map alone (cuts=0): one row, the same repeat (its results are reused: nothing runs)
    assert main([*args, "--option", "cuts=0", "--resume", "--json"]) == 0
    alone = json.loads(capsys.readouterr().out)
    assert [r["levels_cut"] for r in alone["rows"]] == [0] and alone["rows"][0] == rows[0]
    assert len((out / "results.jsonl").read_text().splitlines()) == 1 + len(rows)


def test_bad_options_exit_2(world_file, capsys):
    world = str(world_file(ROOM))
    for option, message in [("speed=1", "no option 'speed'"), ("camera=stereo", "usable: panorama, landmarks"),
                            ("route=0,9", "not on the floor")]:
        assert main(["eval", "ltmap", "--world", world, "--option", option]) == 2
        assert message in capsys.readouterr().err


def test_a_teach_that_fails_leaves_nothing_to_repeat(world_file, tmp_path, capsys):
    args = ["eval", "ltmap", "--world", str(world_file(ROOM)), "--workers", "1", "--max-time", "1",
            "--option", "camera=landmarks", "--option", f"route={SHORT_ROUTE}", "-o", str(tmp_path / "out")]
    assert main([*args, "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["taught"] == 0 and figures["rows"] == [] and figures["repeats"] == 0
    assert figures["teach_failed"][0]["problem"].startswith("FAILURE")
    assert "seed 0: no map to repeat (FAILURE" in format_table(figures)


def test_the_help_names_every_option_each_area_declares(capsys):
    with pytest.raises(SystemExit):
        main(["eval", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for area, module in AREAS.items():
        options = getattr(importlib.import_module(module), "OPTIONS", {})
        assert area in text and all(name in text for name in options), area
