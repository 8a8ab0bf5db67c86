"""``bearings eval roadmap``: random starts, targets placed in the free space, the true reference
frame, the figures from hand-made runs, the option checks, and one whole evaluation in the small
room (the lab's figures are measured by hand: docs/roadmap.md)."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from drivers.sim.cameras import camera_pose
from drivers.sim.scene import Scene
from drivers.sim.world import load_world
from experiments.eval.roadmap import (
    PLACED,
    GotoPlan,
    Settings,
    check_options,
    check_world,
    format_table,
    goto_figures,
    learn_figures,
    placeable,
    placed_names,
    reference_truth,
    seed_targets,
    summarise,
)
from experiments.eval.roadmap_world import (
    PREFERRED_CENTRE,
    START_CLEARANCE,
    TARGET_CLEARANCE,
    FreeFloor,
    away_from_exits,
    best_heading,
    camera_rays,
    camera_view,
    floor_in_view,
    has_room,
    heading_choices,
    learn_start,
    learning_room,
    place_targets,
    random_starts,
    reachable_grid,
    usable_poses,
)
from experiments.sweep import Episode
from experiments.sweep.table import read_report
from missions.cli import main
from perception.geometry import Pose2D
from tests.missions.test_roadmap_missions import SMALL_ROOM

# 6 x 4 m with a 2.4 x 2 m box (a robot would fit inside its outline) and a pillar; poses: two usable,
# one inside the box, one in the pillar's reach
FURNISHED = """
name: furnished
start: {x: 0.9, y: 0.8, theta_deg: 0}
poses:
  p: {x: 1.0, y: 3.0, theta_deg: 0}
  q: {x: 5.0, y: 0.8, theta_deg: 90}
  boxed: {x: 3.2, y: 2.0, theta_deg: 0}
  pillar: {x: 5.0, y: 3.0, theta_deg: 0}
walls: [{points: [[0, 0], [6, 0], [6, 4], [0, 4]], closed: true, height: 2.4}]
boxes: [{center: [3.2, 2.0], size: [2.4, 2.0], height: 0.8}]
pillars: [{center: [5.0, 3.1], radius: 0.2, height: 2.4}]
cameras:
  - {name: front, kind: pinhole, model: {width: 64, height: 48, fx: 50, fy: 50, cx: 31.5, cy: 23.5}}
  - {name: stereo, kind: stereo, model: {width: 64, height: 48, fx: 50, fy: 50, cx: 31.5, cy: 23.5, baseline: 0.12}}
"""
BARE = re.sub(r"poses:\n(  .*\n)+", "", FURNISHED)  # no named poses
# 1.6 x 1.6 m: room to start (0.45 m clear) but not for targets 1.5 m apart facing surfaces 1-5 m away
CUPBOARD = re.sub(r"walls: .*\n", "walls: [{points: [[0, 0], [1.6, 0], [1.6, 1.6], [0, 1.6]], closed: true, "
                  "height: 2.4}]\n", BARE)
CUPBOARD = re.sub(r"(boxes|pillars): .*\n", "", CUPBOARD)
# 2.2 x 2.2 m: room for the learning's dodecagon (a disc 1.49 m across round (1.1, 1.1)), not for 4 targets
CLOSET = re.sub(r"walls: .*\n", "walls: [{points: [[0, 0], [2.2, 0], [2.2, 2.2], [0, 2.2]], closed: true, "
                "height: 2.4}]\n", CUPBOARD).replace("{x: 0.9, y: 0.8,", "{x: 1.225, y: 0.634,")
# 8 x 1.2 m: nowhere 0.7 m clear, but room for targets 0.45 m clear looking along it
GALLERY = re.sub(r"walls: .*\n", "walls: [{points: [[0, 0], [8, 0], [8, 1.2], [0, 1.2]], closed: true, "
                 "height: 2.4}]\n", BARE)
GALLERY = re.sub(r"(boxes|pillars): .*\n", "", GALLERY).replace("{x: 0.9, y: 0.8,", "{x: 0.9, y: 0.6,")
# 6 x 6 m, empty: the floor in view has a closed form
EMPTY = re.sub(r"walls: .*\n", "walls: [{points: [[0, 0], [6, 0], [6, 6], [0, 6]], closed: true, height: 2.4}]\n",
               BARE)
EMPTY = re.sub(r"(boxes|pillars): .*\n", "", EMPTY)


def test_random_starts_are_clear_reachable_and_drawn_from_the_seed_alone(world_file):
    world = load_world(world_file(FURNISHED))
    starts = random_starts(world, 200, seed=3)
    assert starts == random_starts(world, 200, seed=3)
    assert random_starts(world, 5, seed=3) == starts[:5]  # the first ones do not depend on how many
    assert random_starts(world, 5, seed=4) != starts[:5]
    scene, grid = Scene(world), reachable_grid(world)
    for pose in starts:
        assert scene.clearance(pose.x, pose.y) >= START_CLEARANCE
        assert not (2.0 < pose.x < 4.4 and 1.0 < pose.y < 3.0)  # never inside the box (1 m clear of its faces there)
        row, col, _ = grid.cells_of([pose.x, pose.y])
        assert grid.reachable[row[0], col[0]]
    headings = [p.theta for p in starts]
    assert min(headings) < -2.5 and max(headings) > 2.5  # any heading
    assert min(p.x for p in starts) < 1.0 and max(p.x for p in starts) > 5.0  # the whole room
    cupboard = load_world(world_file("start: {x: 0.4, y: 0.4}\nwalls: [{points: [[0, 0], [0.8, 0], [0.8, 0.8], "
                                     "[0, 0.8]], closed: true, height: 2}]\n", "cupboard.yaml"))
    with pytest.raises(ValueError, match="no reachable place 0.45 m clear"):
        random_starts(cupboard, 1, seed=0)


def _centre_ray(world, scene: Scene, pose: Pose2D) -> float:
    """Distance along the front camera's optical axis to the nearest surface above the camera,
    cast here with the scene's own ray casting (not through the code under test)."""
    where = camera_pose(world.camera("front"), world.ptu, pose)
    distance, index = scene.cast_columns(where.eye, np.array([where.psi]))
    return float(np.min(np.where(scene.heights[index] > where.eye[2], distance[0], np.inf)))


@pytest.mark.parametrize("name", ["bare", "lab"])
def test_placed_targets_are_free_reachable_apart_and_face_surfaces_in_range(world_file, name):
    world = load_world(str(world_file(BARE)) if name == "bare" else "lab")
    targets = place_targets(world, 4, seed=3)
    assert list(targets) == ["t1", "t2", "t3", "t4"]
    assert targets == place_targets(world, 4, seed=3)  # from the seed alone
    assert place_targets(world, 2, seed=3) == dict(list(targets.items())[:2])  # the first ones do not depend on N
    assert place_targets(world, 4, seed=4) != targets
    scene, grid, rays = Scene(world), reachable_grid(world), camera_rays(world)
    # room around a target: the lab has it for all; in the furnished 6 x 4 m room the first ones take it
    assert scene.clearance(targets["t1"].x, targets["t1"].y) >= TARGET_CLEARANCE
    for pose in targets.values():
        assert scene.clearance(pose.x, pose.y) >= (TARGET_CLEARANCE if name == "lab" else START_CLEARANCE)
        row, col, _ = grid.cells_of([pose.x, pose.y])
        assert grid.reachable[row[0], col[0]]
        assert 1.0 <= _centre_ray(world, scene, pose) <= 5.0
        view = camera_view(scene, world, pose, rays)
        assert view.within(1.0, 5.0) and len(set(view.surfaces)) >= 2  # never one flat wall alone
    poses = list(targets.values())
    assert min(a.distance_to(b) for i, a in enumerate(poses) for b in poses[i + 1:]) >= 1.5
    # across seeds the targets spread over the room (not one favourite spot)
    spread = [p for seed in range(5) for p in place_targets(world, 4, seed).values()]
    xmin, _, xmax, _ = world.bounds()
    span = xmax - xmin
    assert min(p.x for p in spread) < xmin + 0.4 * span and max(p.x for p in spread) > xmax - 0.4 * span


@pytest.mark.parametrize("name", ["bare", "lab"])
def test_placed_targets_look_across_the_most_floor_the_robot_can_stand_on(world_file, name):
    """The heading chosen at a target is the one whose view is seen from the largest reachable area
    (among those whose optical axis meets its surface 2-4 m away, when any does), and the placed
    targets' views hold far more floor than the worst qualifying heading at their positions."""
    world = load_world(str(world_file(BARE)) if name == "bare" else "lab")
    free, rays = FreeFloor.of(world, START_CLEARANCE), camera_rays(world)
    chosen_floor, worst_floor = [], []
    for seed in range(3):
        for pose in place_targets(world, 4, seed).values():
            choices = heading_choices(free, pose.x, pose.y, rays)
            chosen = [c for c in choices if abs(math.remainder(c.theta - pose.theta, 2 * math.pi)) < 1e-9]
            assert len(chosen) == 1  # a qualifying heading
            preferred = [c for c in choices if PREFERRED_CENTRE[0] <= c.view.centre <= PREFERRED_CENTRE[1]]
            assert chosen[0].floor == max(c.floor for c in (preferred or choices))
            assert best_heading(free, pose.x, pose.y, rays) == chosen[0]
            chosen_floor.append(chosen[0].floor)
            worst_floor.append(min(c.floor for c in choices))
    assert sum(chosen_floor) > 1.5 * sum(worst_floor)
    assert min(chosen_floor) >= 1.0  # m^2: never a view of a nook seen from a few cells


def test_floor_in_view_is_the_reachable_floor_between_the_camera_and_the_wall(world_file):
    world = load_world(str(world_file(EMPTY)))
    free, rays = FreeFloor.of(world, START_CLEARANCE), camera_rays(world)
    pose = Pose2D(1.0, 3.0, 0.0)  # facing the east wall, 5 m ahead
    where = camera_pose(world.camera("front"), world.ptu, pose)
    view = camera_view(free.scene, world, pose, rays)
    floor = floor_in_view(free.cells, free.grid.resolution**2, where.eye, where.psi, rays, view)
    # a triangle from the eye to where the robot's centre can go (the robot's radius short of the wall)
    depth = 6.0 - world.robot_radius - where.eye[0]
    expected = 0.5 * depth**2 * (math.tan(rays.max()) + math.tan(-rays.min()))
    assert floor == pytest.approx(expected, rel=0.05)
    nearer = Pose2D(4.0, 3.0, 0.0)  # 2 m from the wall: the same view seen from less floor
    there = camera_pose(world.camera("front"), world.ptu, nearer)
    close = floor_in_view(free.cells, free.grid.resolution**2, there.eye, there.psi, rays,
                          camera_view(free.scene, world, nearer, rays))
    assert close == pytest.approx(0.5 * (6.0 - world.robot_radius - there.eye[0]) ** 2
                                  * (math.tan(rays.max()) + math.tan(-rays.min())), rel=0.1)
    assert close < 0.25 * floor


def test_targets_fall_back_to_the_start_clearance_without_room(world_file):
    world = load_world(str(world_file(GALLERY, "gallery.yaml")))
    assert not has_room(reachable_grid(world), TARGET_CLEARANCE)
    targets = place_targets(world, 2, seed=0)
    scene = Scene(world)
    assert all(START_CLEARANCE <= scene.clearance(p.x, p.y) < TARGET_CLEARANCE for p in targets.values())
    assert has_room(reachable_grid(load_world("lab")), TARGET_CLEARANCE)


def test_no_room_for_targets_is_said(world_file):
    cupboard = load_world(str(world_file(CUPBOARD, "cupboard.yaml")))
    random_starts(cupboard, 1, seed=0)  # room to start from...
    with pytest.raises(ValueError, match="room for [01] target\\(s\\), not 2: reachable, 0.45 m clear, 1.5 m apart"):
        place_targets(cupboard, 2, seed=0)  # ...but not for two targets


def test_placed_targets_go_into_a_copy_of_the_world(world_file, tmp_path):
    path = str(world_file(BARE))
    loaded = load_world(path)
    settings = check_options(path, {})
    targets = seed_targets(path, loaded, settings, 2, tmp_path / "eval")
    assert targets.world == str(tmp_path / "eval" / "seeds" / "world_s0002" / "world.yaml")
    assert targets.poses == place_targets(loaded, 4, 2)
    copy = load_world(targets.world)
    assert copy.name == "furnished" and copy.walls == loaded.walls and copy.start == loaded.start
    for name, pose in targets.poses.items():  # named poses of the copy: bearings sim snapshot --pose t1
        assert (copy.poses[name].x, copy.poses[name].y) == pytest.approx((pose.x, pose.y))
        assert math.degrees(copy.poses[name].theta) == pytest.approx(math.degrees(pose.theta))
    named = str(world_file(FURNISHED, "furnished.yaml"))
    assert seed_targets(named, load_world(named), check_options(named, {}), 2, tmp_path / "eval").world == named


def _learn_report(reference: Pose2D, estimates: dict[str, Pose2D], **section) -> dict:
    """A learn_targets report whose robot stood at ``reference`` (world frame) when it took the
    reference image at t = 10 s, with ``estimates`` (reference frame) as its targets."""
    targets = {n: {"x": p.x, "y": p.y, "theta_deg": math.degrees(p.theta), "image": f"{n}.png"}
               for n, p in estimates.items()}
    ground_truth = {"trajectory": [[0.0, 0.0, 0.0, 0.0], [20.0, 5.0, 5.0, 1.0]],
                    "stops": [[9.5, 10.5, reference.x, reference.y, reference.theta]],
                    "final_pose": {"x": 5.0, "y": 5.0, "theta": 1.0}}
    return {"status": "SUCCESS", "reason": "", "sim_time_s": 700.0, "wall_time_s": 120.0,
            "ground_truth": ground_truth,
            "roadmap": {"room": {"reference_stamp": 10.0}, "targets": targets, **section}}


def test_targets_are_compared_with_the_truth_in_the_true_reference_frame():
    reference = Pose2D(2.0, 1.0, math.radians(90))  # the true reference pose: not the world's origin
    truth = {"a": Pose2D(2.0, 3.0, math.radians(90)), "b": Pose2D(0.0, 1.0, math.radians(180)),
             "c": Pose2D(4.0, 1.0, 0.0)}
    # in the reference frame: a is 2 m straight ahead, b 2 m to the left facing left
    estimates = {"a": Pose2D(2.05, 0.0, math.radians(1.0)), "b": Pose2D(0.0, 2.2, math.radians(90))}
    report = _learn_report(reference, estimates, connected=True, edges=[{"from": "a", "to": "b"}])
    assert reference_truth(report) == Pose2D(2.0, 1.0, math.radians(90), stamp=10.0)
    figures = learn_figures(0, report, None, truth)
    assert figures["target_errors"]["a"] == pytest.approx({"position_m": 0.05, "heading_deg": 1.0})
    assert figures["target_errors"]["b"] == pytest.approx({"position_m": 0.2, "heading_deg": 0.0})
    assert figures["found"] == 2 and figures["targets"] == 3 and figures["within"] == 1  # b is 0.2 m off
    assert figures["connected"] and figures["edges"] == 1 and figures["sim_time_s"] == 700.0
    # the same estimates compared in the WORLD frame would be metres off: the frame is what matters
    assert learn_figures(0, _learn_report(Pose2D(), estimates), None, truth)["within"] == 0
    # no reference image (the room estimate failed): nothing to compare
    report["roadmap"]["room"] = {}
    assert learn_figures(0, report, None, truth)["found"] == 0
    crashed = learn_figures(1, None, {"status": "ERROR", "reason": "timed out after 60 s wall time",
                                      "elapsed_s": 60.2}, truth)
    assert (crashed["status"], crashed["reason"], crashed["found"]) == ("ERROR", "timed out after 60 s wall time", 0)


def _goto(status: str, final: Pose2D | None, goal: str = "a", number: int = 0) -> tuple[GotoPlan, dict | None, None]:
    """A navigation's plan and report (None: it gave none), and no sweep row."""
    plan = GotoPlan(Episode("goto_target", "w", 0, {"target": goal, "seed": number}, None, "1,1,0"),
                    Pose2D(1.0, 1.0, 0.0), goal)
    if final is None:
        return plan, None, None
    final_pose = {"x": final.x, "y": final.y, "theta": final.theta}
    return plan, {"status": status, "reason": "" if status == "SUCCESS" else "no target matched",
                  "sim_time_s": 90.0, "ground_truth": {"final_pose": final_pose},
                  "roadmap": {"navigation": {"visited": ["b", "a"], "random_moves": 1}}}, None


def test_a_navigation_is_reached_when_it_succeeds_within_the_thresholds():
    goal = Pose2D(2.0, 3.0, math.radians(90))
    close = goto_figures(*_goto("SUCCESS", Pose2D(2.0, 3.1, math.radians(93))), goal)
    assert close["reached"] and close["error_m"] == pytest.approx(0.1) and close["error_deg"] == pytest.approx(3.0)
    assert not goto_figures(*_goto("SUCCESS", Pose2D(2.0, 3.1, math.radians(96))), goal)["reached"]  # 6 deg
    assert not goto_figures(*_goto("SUCCESS", Pose2D(2.2, 3.0, math.radians(90))), goal)["reached"]  # 0.2 m
    assert not goto_figures(*_goto("FAILURE", goal), goal)["reached"]  # there by chance, the mission failed
    plan, report, row = _goto("SUCCESS", Pose2D(2.0, 3.1, math.radians(93)))
    report["ground_truth"]["collisions"] = 2  # it touched a desk twice on the way and printed SUCCESS
    touched = goto_figures(plan, report, row, goal)
    assert not touched["reached"] and touched["collisions"] == 2
    plan, _, _ = _goto("ERROR", None)
    killed = goto_figures(plan, None, {"status": "ERROR", "reason": "killed by SIGKILL", "elapsed_s": 3.0}, goal)
    assert killed["status"] == "ERROR" and killed["error_m"] is None and not killed["reached"]


def test_the_summary_from_hand_made_runs():
    settings = Settings(("a", "b"), 2)
    learns = [
        {"episode": "learn", "seed": 0, "status": "SUCCESS", "reason": "", "targets": 2, "found": 2, "within": 2,
         "target_errors": {"a": {"position_m": 0.05, "heading_deg": 1.0}, "b": {"position_m": 0.1, "heading_deg": 3.0}},
         "connected": True, "edges": 1, "sim_time_s": 600.0, "wall_time_s": 100.0},
        {"episode": "learn", "seed": 1, "status": "FAILURE", "reason": "search rounds used up", "targets": 2,
         "found": 1, "within": 0, "target_errors": {"a": {"position_m": 0.3, "heading_deg": 2.0}},
         "connected": False, "edges": 0, "sim_time_s": 1000.0, "wall_time_s": 200.0},
    ]
    gotos = [
        {"episode": "goto", "seed": 0, "number": 0, "goal": "a", "status": "SUCCESS", "reason": "", "reached": True,
         "error_m": 0.01, "error_deg": 1.0, "sim_time_s": 80.0, "wall_time_s": 10.0},
        {"episode": "goto", "seed": 0, "number": 1, "goal": "b", "status": "ERROR", "reason": "killed by SIGKILL",
         "reached": False, "error_m": None, "error_deg": None, "sim_time_s": None, "wall_time_s": 3.0},
        {"episode": "goto", "seed": 1, "number": 0, "goal": "a", "status": "FAILURE", "reason": "lost",
         "reached": False, "error_m": 1.5, "error_deg": 40.0, "sim_time_s": 300.0, "wall_time_s": 30.0},
    ]
    figures = summarise("w", settings, learns, gotos, {0: {"a": Pose2D(1, 2, math.radians(90))}})
    assert figures["targets.source"] == "named poses" and figures["targets.poses"] == {"0": {"a": [1, 2, 90]}}
    assert figures["targets.found"] == 3 and figures["targets.total"] == 4 and figures["targets.within"] == 2
    assert figures["targets.position_error_worst_m"] == 0.3
    assert figures["targets.position_error_mean_m"] == pytest.approx(0.15)
    assert figures["targets.heading_error_worst_deg"] == 3.0
    assert figures["graph.connected_rate"] == 0.5 and figures["graph.edges_mean"] == 0.5
    assert (figures["goto.planned"], figures["goto.run"], figures["goto.reached"]) == (4, 3, 1)
    assert figures["goto.reached_rate"] == pytest.approx(1 / 3)
    assert figures["goto.error_worst_m"] == 1.5 and figures["goto.error_mean_m"] == pytest.approx(0.755)
    assert figures["learn.succeeded"] == 1 and figures["learn.sim_time_s"] == 800.0
    assert (figures["goto.collisions"], figures["goto.safety_stops"], figures["goto.min_clearance_m"]) == (0, 0, None)
    bumped = summarise("w", settings, [{**learns[0], "collisions": 1, "safety_stops": 3, "min_clearance_m": 0.0}], [])
    assert bumped["learn.succeeded"] == 0 and bumped["learn.collisions"] == 1 and bumped["learn.safety_stops"] == 3
    assert "1 coll, 3 stops, clear 0.00" in format_table(bumped)
    assert [f["episode"] for f in figures["failures"]] == ["learn", "goto 1 to b", "goto 0 to a"]
    assert figures["failures"][1]["reason"] == "killed by SIGKILL" and len(figures["runs"]) == 5
    table = format_table(figures)
    assert "targets found 3 of 4" in table and "goto reached 1 of 3 run (4 planned" in table
    assert "rate 0.33, 95 % 0.06-0.79)" in table  # 1 of 3 says little: the Wilson interval beside it
    assert "seed 0 goto 1 to b: ERROR: killed by SIGKILL" in table
    placed = format_table(summarise("w", Settings(("t1", "t2"), 0, PLACED), learns, [],
                                    {1: {"t1": Pose2D(1.5, 2.25, 0.0), "t2": Pose2D(4.0, 1.0, math.pi)}}))
    assert "targets t1, t2 (placed)" in placed
    assert "seed 1 placed targets: t1 (1.5, 2.25, 0 deg), t2 (4, 1, 180 deg)" in placed
    empty = summarise("w", settings, learns[1:], [])
    assert empty["goto.reached_rate"] is None and empty["goto.error_worst_m"] is None
    assert "goto reached 0 of 0 run" in format_table(empty) and "rate -, -)" in format_table(empty)
    hidden = format_table({**figures, "targets.out_of_sight": {"0": ["b"], "1": []}})
    assert "seed 0: b out of sight of where the learning starts, behind a wall" in hidden
    assert not any(line.startswith("seed 1: ") for line in hidden.splitlines())  # every target in sight: nothing


def test_targets_and_options_are_checked_against_the_world(world_file):
    path = str(world_file(FURNISHED))
    assert sorted(usable_poses(load_world(path))) == ["p", "q"]  # not inside the box, not at the pillar
    assert check_options(path, {}) == Settings(("p", "q"), 5)
    assert check_options(path, {"targets": "q, p", "starts": "0"}) == Settings(("q", "p"), 0)
    for extra, message in [({"targets": "p,door"}, "no named pose 'door' .*named poses: boxed, p, pillar, q"),
                           ({"targets": "p,boxed"}, "'boxed' .* not where the robot can stand"),
                           ({"targets": "p"}, "at least 2"),
                           ({"targets": "p,p"}, "listed twice"),
                           ({"targets": "p,,q"}, "expected NAME,NAME"),
                           ({"starts": "many"}, "an integer"),
                           ({"starts": "-1"}, "0 to 1000")]:
        with pytest.raises(ValueError, match=message):
            check_options(path, extra)
    assert check_options(path, {"targets": "3"}) == Settings(("t1", "t2", "t3"), 5, PLACED)  # a count: placed
    check_world(path)
    with pytest.raises(ValueError, match="no stereo \\(stereo\\) camera"):
        check_world(str(world_file(FURNISHED.replace("name: stereo", "name: left"), "other.yaml")))


def test_a_world_without_named_poses_gets_placed_targets(world_file):
    bare = str(world_file(BARE, "bare.yaml"))
    assert check_world(bare).poses == {}  # accepted: not refused any more
    assert check_options(bare, {}) == Settings(("t1", "t2", "t3", "t4"), 5, PLACED)
    assert check_options(bare, {"targets": "5", "starts": "0"}) == Settings(("t1", "t2", "t3", "t4", "t5"), 0, PLACED)
    twelve = tuple(f"t{k}" for k in range(1, 13))  # a count places targets in a world with named poses too
    assert check_options("lab", {"targets": "12"}) == Settings(twelve, 5, PLACED)
    # a world with one usable named pose: placed too (one target is no roadmap)
    single = str(world_file(FURNISHED.replace("  q: {x: 5.0, y: 0.8, theta_deg: 90}\n", ""), "single.yaml"))
    assert check_options(single, {}).source == PLACED


@pytest.mark.parametrize(("option", "message"), [
    ("targets=1", "targets: a count must be 2 to 12, got 1"),
    ("targets=13", "targets: a count must be 2 to 12, got 13"),
    ("targets=abc", "targets: world 'furnished' has no named pose 'abc' (its named poses: none)"),
    ("targets=p,nowhere", "no named pose 'nowhere'"),
])
def test_bad_targets_exit_2_with_one_line(world_file, capsys, option, message):
    world = world_file(FURNISHED if "nowhere" in option else BARE)
    assert main(["eval", "roadmap", "--world", str(world), "--option", option]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err and "Traceback" not in err


@pytest.mark.parametrize(("option", "count"), [([], 2), (["--option", "targets=4"], 4)])
def test_a_world_without_room_for_targets_exits_2(world_file, capsys, option, count):
    """The default asks for 4 and settles for as many as the room holds, down to 2; a count given is kept."""
    assert main(["eval", "roadmap", "--world", str(world_file(CLOSET, "closet.yaml")), *option]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "has room for 1 target(s)" in err and f"not {count}:" in err


def test_targets_are_drawn_in_the_room_the_learning_starts_in():
    """The clinic's learning starts in a small room that none of its named poses is in: 4 placed
    targets do not fit there (1.5 m apart, facing surfaces 1-5 m away), 3 do, and the navigations
    start there too."""
    clinic = load_world("clinic")
    grid = reachable_grid(clinic)
    room = learning_room(clinic, grid, learn_start(clinic, grid))
    assert usable_poses(clinic, room) == {} and len(usable_poses(clinic, grid)) == 5
    assert check_options("clinic", {}) == Settings(("t1", "t2", "t3"), 5, PLACED)
    targets = place_targets(clinic, 3, 0, grid=room)
    starts = random_starts(clinic, 5, 0, grid=room)
    assert room.reachable_at(np.array([[p.x, p.y] for p in [*targets.values(), *starts]])).all()
    assert check_options("lab", {}) == Settings(("centre", "corner", "door", "window"), 5)  # one room: as before


def test_a_world_without_room_for_the_dodecagon_exits_2_before_any_placement(world_file, capsys):
    assert main(["eval", "roadmap", "--world", str(world_file(CUPBOARD, "cupboard.yaml"))]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "the room estimation's dodecagon" in err and "has room for" not in err


def test_an_open_world_exits_2_before_any_placement(capsys):
    assert main(["eval", "roadmap", "--world", "outdoor"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "is open" in err and "enclosed room" in err


def test_the_evaluation_in_the_small_room(world_file, tmp_path, capsys):
    """Target images, a learn run and a navigation from a random start, all through the sweep runner."""
    world, out = str(world_file(SMALL_ROOM, "small.yaml")), tmp_path / "eval"
    args = ["eval", "roadmap", "--world", world, "--seeds", "1", "--workers", "2", "-o", str(out),
            "--option", "starts=1"]
    assert main([*args, "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["area"] == "roadmap" and figures["world"] == "small" and figures["targets"] == ["a", "b"]
    assert figures["failures"] == [] and figures["learn.succeeded"] == 1
    assert figures["targets.found"] == figures["targets.total"] == figures["targets.within"] == 2
    assert figures["targets.position_error_worst_m"] < 0.15 and figures["graph.connected_rate"] == 1.0
    assert figures["goto.run"] == figures["goto.reached"] == 1 and figures["goto.error_worst_m"] < 0.05
    learn, goto = figures["runs"]
    assert goto["goal"] in ("a", "b") and goto["start"] == [round(v, 3) for v in goto["start"]]
    assert sorted(p.name for p in (out / "seeds" / "small_s0000" / "targets").iterdir()) == ["a.png", "b.png"]
    assert len((out / "results.jsonl").read_text().splitlines()) == 2  # one learn, one goto
    assert learn["sim_time_s"] > 100 and learn["wall_time_s"] > 0


def test_a_torn_report_is_a_run_without_one(tmp_path):
    episode = Episode("learn_targets", "lab", 0, {"targets": "t", "roadmap": "r"})
    (tmp_path / "reports").mkdir()
    (tmp_path / "reports" / f"{episode.id}.json").write_text('{"status": "SUCC')  # a writer killed mid-write
    assert read_report(tmp_path, episode.id) is None
    row = {"status": "ERROR", "reason": "killed by SIGKILL"}
    assert learn_figures(0, read_report(tmp_path, episode.id), row, {})["reason"] == "killed by SIGKILL"


def test_the_default_count_of_placed_targets_is_what_every_seed_places():
    """`flat`'s bedroom holds 3 placed targets for seed 0 and only 2 for seed 1: the default (4,
    fewer when they do not fit) settles on what every seed of the run places; a count given is kept,
    and refused when a seed cannot place it."""
    flat = load_world("flat")
    grid = reachable_grid(flat)
    start = learn_start(flat, grid)
    inner = away_from_exits(learning_room(flat, grid, start), grid)
    assert placeable(flat, placed_names(4), inner, fewer=True)[0] == placed_names(3)
    names, placed = placeable(flat, placed_names(3), inner, fewer=True, seeds=[0, 1])
    assert names == placed_names(2) and sorted(placed) == [0, 1]
    assert placed[1] == place_targets(flat, 2, 1, grid=inner)  # the poses each seed's episodes use
    with pytest.raises(ValueError, match="has room for 2 target\\(s\\), not 3"):
        placeable(flat, placed_names(3), inner, fewer=False, seeds=[0, 1])
    settings = check_options("flat", {})
    assert settings.targets == placed_names(3) and settings.fewer
    assert not check_options("flat", {"targets": "3"}).fewer
