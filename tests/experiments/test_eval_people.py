"""``--option people=N`` of every ``bearings eval`` area: people drawn from the seed, on or across
the way the robot goes, in a copy of the world file the episodes run in; people=0 changes nothing."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from drivers.sim.floor import reachable_floor
from drivers.sim.world import load_world
from experiments.eval import exploration, ltmap, roadmap
from experiments.eval.people import (
    KEEP_CLEAR_M,
    RADIUS,
    SPACING,
    WAIT_S,
    Crowd,
    Walker,
    _Placer,
    in_rooms,
    on_ways,
    parse_people,
    parse_rest,
    table_line,
    world_with_people,
)
from experiments.sweep import Episode
from missions.cli import main

HALL = """
name: hall
start: {x: 1.0, y: 2.0, theta_deg: 0}
walls: [{points: [[0, 0], [10, 0], [10, 4], [0, 4]], closed: true, height: 2.5}]
boxes: [{center: [5.0, 3.5], size: [1.0, 1.0], height: 0.8}]
people: [{path: [[9, 3.5]]}]
"""
ROUTE = np.array([[1.0, 2.0], [5.0, 2.0], [8.0, 1.0]])
BOX = str(Path(__file__).resolve().parents[1] / "data" / "worlds" / "box.yaml")


def distance_to(way: np.ndarray, point: np.ndarray) -> float:
    a, b = way[:-1], way[1:]
    t = np.clip(np.sum((point - a) * (b - a), axis=1) / np.sum((b - a) ** 2, axis=1), 0.0, 1.0)
    return float(np.min(np.hypot(*(point - (a + t[:, None] * (b - a))).T)))


def gap(person: Walker, point: np.ndarray) -> float:
    """How near a person's path (a point or a segment) comes to ``point``."""
    path = np.asarray(person.path)
    return float(np.hypot(*(path[0] - point))) if len(path) == 1 else distance_to(path, point)


def crosses(way: np.ndarray, walker: Walker) -> bool:
    """Whether a walker's segment meets the polyline (sampled every 1/200 of it); a standing one: no."""
    if len(walker.path) == 1:
        return False
    a, b = np.asarray(walker.path)
    samples = a + np.linspace(0.0, 1.0, 201)[:, None] * (b - a)
    return min(distance_to(way, p) for p in samples) < 0.03


@pytest.mark.parametrize(("parse", "text", "value"), [
    (parse_people, None, 0), (parse_people, "0", 0), (parse_people, "4", 4), (parse_people, "20", 20),  # a count
    (parse_rest, None, 2.0), (parse_rest, "0", 0.0), (parse_rest, "10", 10.0), (parse_rest, "60", 60.0),  # seconds
])
def test_the_options_read_a_count_of_people_and_seconds_of_rest(parse, text, value):
    assert parse(text) == value


@pytest.mark.parametrize(("parse", "text", "message"), [
    (parse_people, "-1", "0 to 20"), (parse_people, "21", "0 to 20"), (parse_people, "two", "an integer"),
    (parse_rest, "-1", "0 to 60"), (parse_rest, "61", "0 to 60"), (parse_rest, "long", "a number of seconds"),
])
def test_a_bad_option_is_refused(parse, text, message):
    with pytest.raises(ValueError, match=message):
        parse(text)


def test_a_longer_rest_changes_the_rests_alone(world_file):
    """The same seed's people, places and speeds with any rest: each rest drawn up to it is the same
    fraction of it (0-2 s by default, 0-10 s with rest=10)."""
    world = load_world(world_file(HALL))
    short, long = (on_ways(world, [ROUTE], 6, seed=3, keep_clear=[ROUTE[0]], rest=r) for r in (2.0, 10.0))
    assert [(p.path, p.speed) for p in short] == [(p.path, p.speed) for p in long]
    walkers = [(a, b) for a, b in zip(short, long, strict=True) if len(a.path) == 2]
    assert walkers and all(b.wait_s == pytest.approx(5.0 * a.wait_s) and b.wait_s <= 10.0 for a, b in walkers)
    floor = reachable_floor(world)
    start = [(world.start.x, world.start.y)]
    rooms = [in_rooms(world, floor, 5, seed=0, keep_clear=start, rest=r) for r in (2.0, 10.0)]
    assert [p.path for p in rooms[0]] == [p.path for p in rooms[1]]


@pytest.mark.parametrize("area", [ltmap, roadmap, exploration])
def test_every_area_takes_the_rest(area):
    assert area.check_options("lab", {"people": "3", "rest": "10"}).people == Crowd(3, 10.0)
    assert area.check_options("lab", {"people": "3"}).people == Crowd(3, 2.0)
    with pytest.raises(ValueError, match="rest must be 0 to 60"):
        area.check_options("lab", {"rest": "90"})


def test_people_stand_on_the_way_or_walk_across_it_clear_of_its_ends(world_file):
    world = load_world(world_file(HALL))
    people = on_ways(world, [ROUTE], 6, seed=3, keep_clear=[ROUTE[0], ROUTE[-1]])
    assert len(people) == 6
    assert {len(p.path) for p in people} == {1, 2}  # some stand, some walk (this seed: both)
    for person in people:
        path = np.asarray(person.path)
        if len(path) == 1:
            assert distance_to(ROUTE, path[0]) < 1e-9
        else:
            assert crosses(ROUTE, person) and 0.5 <= person.speed <= 1.2 and 0.0 <= person.wait_s <= 2.0
        for end in (ROUTE[0], ROUTE[-1]):  # 1 m from the route's start and end, all along their paths
            assert gap(person, end) >= KEEP_CLEAR_M - 1e-9
    centres = np.array([p.path[0] for p in people if len(p.path) == 1])
    gaps = np.hypot(*(centres[:, None] - centres[None]).transpose(2, 0, 1))
    assert np.all(gaps[np.triu_indices(len(centres), 1)] >= SPACING - 1e-9)


def test_the_same_seed_draws_the_same_people_and_another_seed_others(world_file):
    world = load_world(world_file(HALL))
    draw = [on_ways(world, [ROUTE], 4, seed=s, keep_clear=[ROUTE[0]]) for s in (1, 1, 2)]
    assert draw[0] == draw[1] and draw[0] != draw[2]


def test_people_in_rooms_are_on_the_floor_the_robot_reaches(world_file):
    world = load_world(world_file(HALL))
    floor = reachable_floor(world)
    people = in_rooms(world, floor, 5, seed=0, keep_clear=[(world.start.x, world.start.y)])
    assert len(people) == 5
    points = np.array([q for p in people for q in p.path])
    assert floor.reachable_at(points).all()
    assert np.all(np.hypot(*(points - [world.start.x, world.start.y]).T) >= KEEP_CLEAR_M)


TWO_ROOMS = """
name: two_rooms
start: {x: 1.0, y: 2.0, theta_deg: 0}
walls:
  - {points: [[0, 0], [10, 0], [10, 4], [0, 4]], closed: true, height: 2.5}
  - {points: [[5, 0], [5, 1.5]], height: 2.5}
  - {points: [[5, 2.5], [5, 4]], height: 2.5}
"""


def test_nobody_stands_where_they_cut_a_room_off(world_file):
    # the door is 1 m wide (y 1.5-2.5): a person (0.25 m) in it leaves 0.375 m on each side, and the
    # robot's disc grown by the clearance it keeps needs 0.72 m: the east room would be cut off
    world = load_world(world_file(TWO_ROOMS))
    floor = reachable_floor(world)
    placer = _Placer(world, keep_clear=[])
    assert not placer.keeps_floor(floor, np.array([5.0, 2.0]))  # in the door
    assert not placer.keeps_floor(floor, np.array([5.4, 2.0]))  # just inside the east room, in front of it
    assert placer.keeps_floor(floor, np.array([7.5, 2.0]))  # in the middle of the east room
    assert placer.keeps_floor(floor, np.array([2.5, 3.0]))  # beside the west room's wall: a way round
    people = [w for seed in range(10) for w in in_rooms(world, floor, 4, seed=seed, keep_clear=[(1.0, 2.0)])]
    standing = np.array([w.path[0] for w in people if len(w.path) == 1])
    assert len(standing) and not np.any(np.hypot(*(standing - [5.0, 2.0]).T) < 0.9)  # none near the door


def test_a_world_with_no_room_gets_fewer_people(world_file):
    world = load_world(world_file(HALL))
    assert on_ways(world, [np.array([[1.0, 2.0], [2.5, 2.0]])], 3, seed=0, keep_clear=[[1.0, 2.0], [2.5, 2.0]]) == []


def corridor(width: float) -> str:
    return f"""
name: corridor
start: {{x: 0.5, y: {width / 2}, theta_deg: 0}}
walls: [{{points: [[0, 0], [10, 0], [10, {width}], [0, {width}]], closed: true, height: 2.5}}]
"""


def test_nobody_stands_where_the_robot_cannot_get_past_them(world_file):
    # the robot's disc (0.26 m) grown by the avoidance's clearance (0.10 m) beside a person (0.25 m)
    # needs 0.25 + 2 * 0.36 = 0.97 m from the person's centre to one wall: a 1.4 m corridor has 0.7
    way = np.array([[1.0, 0.7], [9.0, 0.7]])
    narrow = load_world(world_file(corridor(1.4)))
    assert not any(len(w.path) == 1 for s in range(5) for w in on_ways(narrow, [way], 3, seed=s,
                                                                       keep_clear=[way[0], way[-1]]))
    wide = load_world(world_file(corridor(2.4), "wide.yaml"))  # 1.2 m to each wall
    clear = [[1.0, 1.2], [9.0, 1.2]]
    placed = [w for s in range(5) for w in on_ways(wide, [way + [0.0, 0.5]], 3, seed=s, keep_clear=clear)]
    assert any(len(w.path) == 1 for w in placed)


def test_a_corridor_too_narrow_for_a_body_each_side_gets_short_crossings_that_leave_a_way(world_file):
    """A 1.4 m corridor: from its middle a person reaches 0.45 m to a wall (their radius off it), less
    than a body (0.5 m), so no crossing of the usual kind fits and before nobody was placed. Short
    crossings go at least half a body (0.25 m) to each side; paused at an end (centre 0.25 m from a
    wall), the person's edge is 0.5 m from it, leaving 0.90 m to the other wall, more than the 0.72 m
    the robot's disc grown by its clearance needs."""
    way = np.array([[1.0, 0.7], [9.0, 0.7]])
    world = load_world(world_file(corridor(1.4)))
    placer = _Placer(world, keep_clear=[])
    people = [w for s in range(5) for w in on_ways(world, [way], 3, seed=s, keep_clear=[way[0], way[-1]])]
    assert len(people) >= 5 and all(len(w.path) == 2 and crosses(way, w) for w in people)
    for walker in people:
        for end in np.asarray(walker.path):
            assert RADIUS - 1e-9 <= distance_to(way, end) < 2 * RADIUS  # short: between half and one body
            on_way = np.array([end[0], 0.7])
            assert placer.leaves_a_way(end, on_way - [1.5, 0.0], on_way + [1.5, 0.0])


def test_a_person_beside_the_first_closes_one_side_and_a_third_the_last_way_past(world_file):
    placer = _Placer(load_world(world_file(corridor(2.4))), keep_clear=[])
    first, before, after = np.array([5.0, 1.2]), np.array([3.5, 1.2]), np.array([6.5, 1.2])
    assert placer.leaves_a_way(first, before, after)  # 0.95 m on each side, 0.72 needed
    placer.placed.append(Walker(((5.0, 1.2),)))
    placer.standing.append((first, before, after))
    north = Walker(((5.35, 1.85),))  # 0.3 m from the north wall, 0.24 m from the first: closed
    assert placer.keeps_ways(north)  # the south side is still open
    placer.placed.append(north)
    assert not placer.keeps_ways(Walker(((5.35, 0.55),)))  # and now the south one closes it
    assert placer.keeps_ways(Walker(((5.35, 0.55), (5.35, 1.0))))  # a walker moves on: not counted


def test_the_copy_of_the_world_keeps_its_own_people_and_adds_the_drawn_ones(world_file, tmp_path):
    source = world_file(HALL)
    drawn = [Walker(((3.0, 2.0),)), Walker(((6.0, 1.0), (6.0, 3.0)), 0.8, 1.5)]
    copy = load_world(world_with_people(str(source), tmp_path / "s0" / "hall.yaml", drawn))
    original = load_world(source)
    assert copy.name == "hall" and copy.walls == original.walls and copy.start == original.start
    assert [p.path for p in copy.people] == [((9.0, 3.5),), ((3.0, 2.0),), ((6.0, 1.0), (6.0, 3.0))]
    assert copy.people[2].speed == 0.8 and copy.people[2].wait == 1.5 and copy.people[1].radius == RADIUS


def test_ltmap_repeats_run_with_people_on_the_route_and_the_teach_without(world_file, tmp_path):
    path = str(world_file(HALL))
    loaded = load_world(path)
    settings = ltmap.check_options(path, {"people": "3"})
    assert settings.people.count == 3 and settings.people.rest == WAIT_S
    worlds, people = ltmap.repeat_worlds(path, loaded, settings, [0, 1], tmp_path)
    assert worlds[0] == str(tmp_path / "people" / "s0000" / "world.yaml") and worlds[0] != worlds[1]
    assert len(load_world(worlds[0]).people) == 1 + len(people[0]) and people[0] != people[1]
    route = settings.route.world_xy
    assert all(distance_to(route, np.asarray(p.path[0])) < 1e-9 or crosses(route, p) for p in people[0])
    teach = ltmap.teach_episode(path, 0, settings, tmp_path, None)
    assert teach.world == path  # taught in the world as it is
    report = {"ground_truth": {"final_pose": {"x": 5.0, "y": 2.0, "theta": 0.0}}, "sim_time_s": 30.0}
    repeat = ltmap.follow_episode(teach, report, ltmap.Level(0, 3, 9, 90, 1000, 1.0), 5, None, world=worlds[0])
    assert repeat.world == worlds[0]
    none = ltmap.check_options(path, {})
    assert not none.people and ltmap.repeat_worlds(path, loaded, none, [0], tmp_path) == ({0: path}, {})


def test_roadmap_navigations_run_with_people_between_the_targets(world_file, tmp_path):
    path = str(world_file(HALL.replace("people: [{path: [[9, 3.5]]}]\n", "") + """
poses:
  a: {x: 2.0, y: 1.0, theta_deg: 0}
  b: {x: 8.0, y: 1.0, theta_deg: 90}
  c: {x: 8.0, y: 3.0, theta_deg: 180}
"""))
    loaded = load_world(path)
    settings = roadmap.Settings(("a", "b", "c"), 2, roadmap.NAMED, Crowd(4))
    targets = {seed: roadmap.seed_targets(path, loaded, settings, seed, tmp_path) for seed in (0, 1)}
    worlds, people = roadmap.navigation_worlds(loaded, settings, targets, tmp_path, None)
    assert worlds[0] == str(tmp_path / "seeds" / "world_s0000" / "people" / "world.yaml")
    spots = [np.array([p.x, p.y]) for p in targets[0].poses.values()]
    ways = [np.array([a, b]) for i, a in enumerate(spots) for b in spots[i + 1:]]
    for person in people[0]:
        assert any(distance_to(w, np.asarray(person.path[0])) < 1e-9 or crosses(w, person) for w in ways)
        assert all(gap(person, s) >= KEEP_CLEAR_M - 1e-9 for s in spots)
    learn = roadmap.learn_episode(targets[0].world, 0, tmp_path, None)
    plans = roadmap.goto_plans(learn, loaded, ["a", "b"], 2, None, run_in=worlds[0])
    assert learn.world == path and {p.episode.world for p in plans} == {worlds[0]}
    for plan in plans:  # nobody stands on a navigation's start
        assert all(np.hypot(plan.start.x - q[0], plan.start.y - q[1]) >= KEEP_CLEAR_M - 1e-9
                   for p in people[0] if len(p.path) == 1 for q in p.path)


def test_people_zero_leaves_every_episode_as_it_was():
    assert exploration.seed_worlds("lab", Crowd(), [0, 1], reachable_floor(load_world("lab")), Path("/nowhere")) == (
        {0: "lab", 1: "lab"}, {})
    assert [e.id for e in exploration.episodes({0: "lab"}, [0])] == [e.id for e in exploration.episodes("lab", [0])]
    teach = Episode("teach_route", "lab", 0, {"map": "m.ltmap", "camera": "landmarks"})
    report = {"ground_truth": {"final_pose": {"x": 1.0, "y": 1.0, "theta": 0.0}}, "sim_time_s": 10.0}
    level = ltmap.Level(0, 3, 9, 90, 1000, 1.0)
    assert ltmap.follow_episode(teach, report, level, 5, None).id == ltmap.follow_episode(
        teach, report, level, 5, None, world="lab").id


def test_exploration_with_people_runs_every_variant_in_the_seeds_world(tmp_path, capsys):
    code = main(["eval", "exploration", "--world", BOX, "--seeds", "1", "--workers", "2", "--max-time", "2",
                 "--option", "people=2", "-o", str(tmp_path / "out"), "--json"])
    assert code == 0, capsys.readouterr().err
    figures = json.loads(capsys.readouterr().out)
    assert figures["people"] == 2 and figures["people.placed"] == {"0": 2} and figures["episodes"] == 4
    rows = [json.loads(line) for line in (tmp_path / "out" / "results.jsonl").read_text().splitlines()]
    assert {row["world"] for row in rows} == {str(tmp_path / "out" / "people" / "s0000" / "box.yaml")}
    assert len(load_world(rows[0]["world"]).people) == 2


def test_a_bad_people_option_exits_2_before_any_episode(capsys):
    assert main(["eval", "exploration", "--world", BOX, "--seeds", "1", "--option", "people=many"]) == 2
    assert "people: an integer expected" in capsys.readouterr().err


def test_the_tables_say_how_many_people_were_placed():
    figures = {"people": 3, "people.placed": {"0": 3, "1": 2}}
    assert table_line(figures) == ["people: 3 asked per seed, standing on or walking across the way (seed 0: 3, "
                                   "seed 1: 2 placed)"]
    assert table_line({"people": 0}) == [] and table_line({}) == []
    assert table_line({**figures, "people.rest": 10.0}) == [
        "people: 3 asked per seed, standing on or walking across the way, resting up to 10 s at each end (seed 0: "
        "3, seed 1: 2 placed)"]


def test_a_crowd_records_its_people_and_nothing_when_it_asked_for_none():
    walker = Walker(((1.0, 2.0), (1.0, 3.0)), 0.8, 4.5)
    assert Crowd(2, 5.0).figures({1: [walker], 0: []}) == {
        "people": 2, "people.rest": 5.0, "people.placed": {"0": 0, "1": 1},
        "people.paths": {"0": [], "1": [{"path": [[1.0, 2.0], [1.0, 3.0]], "speed": 0.8, "wait_s": 4.5}]}}
    assert Crowd().figures({}) == {} and not Crowd() and Crowd(1)
