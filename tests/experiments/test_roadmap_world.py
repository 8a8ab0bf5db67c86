"""Where the roadmap evaluation starts a learning (where the room estimation's dodecagon fits) and the room it
learns (the floor in sight of it, cut at the doors)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from drivers.sim.scene import Scene
from drivers.sim.world import load_world
from experiments.eval.roadmap_world import away_from_exits, learn_start, learning_room, out_of_sight, reachable_grid
from perception.geometry import Pose2D

CIRCLE = 0.25 / (2.0 * math.sin(math.pi / 12))  # 0.4830 m: the corners' circle of a 0.25 m side
# A 1.4 m hallway (y 0-1.4) from x = 0 to 6, opening at its east end into a 4 x 4 m room (x 6-10).
HALLWAY = {
    "name": "hall", "start": {"x": 0.8, "y": 0.7, "theta_deg": 0},
    "walls": [{"points": [[0, 0], [6, 0], [6, -1.3], [10, -1.3], [10, 2.7], [6, 2.7], [6, 1.4], [0, 1.4]],
               "closed": True, "height": 2.5}],
}


def world_file(tmp_path, data):
    path = tmp_path / f"{data['name']}.yaml"
    path.write_text(yaml.safe_dump({"format": 1, **data}))
    return load_world(path)


def test_a_start_with_room_for_the_dodecagon_is_kept():
    lab = load_world("lab")  # its start has 0.02 m to spare round the robot's disc: kept as it is
    start = learn_start(lab, reachable_grid(lab))
    assert (start.x, start.y, start.theta) == (lab.start.x, lab.start.y, lab.start.theta)


def test_a_start_in_a_hallway_moves_to_the_nearest_pose_where_the_dodecagon_fits_with_a_margin(tmp_path):
    world = world_file(tmp_path, HALLWAY)
    start = learn_start(world, reachable_grid(world))
    bearing = start.theta + math.radians(105.0)  # the corners' centre: 90 + 15 deg round from the heading
    centre = (start.x + CIRCLE * math.cos(bearing), start.y + CIRCLE * math.sin(bearing))
    # the corners' circle, the robot's 0.26 m disc and the monitor's 0.35 m slow-down margin: 1.093 m
    assert Scene(world).clearance(*centre) >= CIRCLE + 0.26 + 0.35
    assert 6.0 < centre[0] < 10.0  # in the room: the hallway's 0.7 m to each wall is too little
    assert start.x < 7.5  # the nearest such pose: near the room's entrance, not its far side


def test_a_world_with_no_room_anywhere_says_so(tmp_path):
    narrow = {**HALLWAY, "name": "narrow",
              "walls": [{"points": [[0, 0], [6, 0], [6, 1.4], [0, 1.4]], "closed": True, "height": 2.5}]}
    world = world_file(tmp_path, narrow)
    with pytest.raises(ValueError, match="no reachable place where the room estimation's dodecagon"):
        learn_start(world, reachable_grid(world))


# Two rooms, 4 x 4 m each, side by side: the wall between them at x = 4 has a door at y 2.8-4.
# A pillar (0.1 m) in the west room on the line from the start to one target, a cabinet (1.9 m)
# lower than the line of sight (2 m) in front of another.
TWO_ROOMS = {
    "name": "two_rooms", "start": {"x": 0.8, "y": 2.0, "theta_deg": 0},
    "walls": [{"points": [[0, 0], [8, 0], [8, 4], [0, 4]], "closed": True, "height": 2.4},
              {"points": [[4, 0], [4, 2.8]], "height": 2.4}],
    "pillars": [{"center": [2.0, 2.0], "radius": 0.1, "height": 2.4}],
    "boxes": [{"center": [2.0, 3.2], "size": [0.6, 0.4], "height": 1.9}],
}


def test_targets_behind_a_wall_are_out_of_sight_of_the_learning_start(tmp_path):
    """Worked by hand from the start (0.8, 2.0): to (6, 1) the line crosses x = 4 at y = 1.38, and
    the lines to 0.3 m each side of it at 1.2-1.6, all below the door (2.8): hidden. To (6, 3.4) the
    middle line crosses at 2.86, through the door: in sight. The pillar hides the line to (3.2, 2.0)
    but not those 0.3 m to each side (0.15 m from its centre at x = 2); the cabinet is below the line.
    From (6, 1) in the east room the lines to the pillar's target cross x = 4 at 1.50-1.95, those to
    the cabinet's at 2.13-2.48: both hidden."""
    world = world_file(tmp_path, TWO_ROOMS)
    targets = {"next_room": Pose2D(6.0, 1.0, 0.0), "through_door": Pose2D(6.0, 3.4, 0.0),
               "behind_pillar": Pose2D(3.2, 2.0, 0.0), "behind_cabinet": Pose2D(2.0, 3.6, 0.0)}
    assert out_of_sight(world, world.start, targets) == ("next_room",)
    assert out_of_sight(world, Pose2D(6.0, 1.0, 0.0), targets) == ("behind_cabinet", "behind_pillar")


def test_the_learning_room_is_the_floor_in_sight_cut_at_the_door_and_not_at_a_desk(tmp_path):
    """Worked by hand in TWO_ROOMS with a desk (x 2.5-3.0, y 1.0-4.0) leaving a 1.0 m gap at the
    south wall: the robot's centre passes it in a 0.48 m strip (1.0 - 2 x 0.26), narrower than the
    opening's 0.8 m. Low (0.75 m), the desk is looked over and does not part the room: (3.5, 3.0)
    east of it is in the room. As tall as the walls it hides that strip (the line from the start
    (0.8, 2.0) to (3.5, 3.0) crosses x = 2.5-3.0 at y = 2.63-2.81, and the lines 0.3 m to its sides
    too) and it is out. (6.0, 3.4) is in sight through the 1.2 m door (the line crosses x = 4 at
    y = 2.86), but the door's reachable floor is 0.68 m wide: the next room. (6.0, 1.0): behind
    the wall."""
    points = np.array([[1.0, 1.0], [3.5, 3.0], [6.0, 3.4], [6.0, 1.0]])
    inside = {}
    for height in (0.75, 2.4):
        desk = {"center": [2.75, 2.5], "size": [0.5, 3.0], "height": height}
        world = world_file(tmp_path, {**TWO_ROOMS, "name": f"desk{height:g}", "boxes": [*TWO_ROOMS["boxes"], desk]})
        grid = reachable_grid(world)
        assert grid.reachable_at(points).all()  # every point is floor the robot can reach from the start
        inside[height] = learning_room(world, grid, world.start).reachable_at(points).tolist()
    assert inside == {0.75: [True, True, False, False], 2.4: [True, False, False, False]}


def test_a_one_room_world_keeps_its_floor_and_its_named_poses():
    lab = load_world("lab")
    grid = reachable_grid(lab)
    room = learning_room(lab, grid, learn_start(lab, grid))
    assert np.count_nonzero(room.reachable) >= 0.99 * np.count_nonzero(grid.reachable)
    assert room.reachable_at(np.array([[p.x, p.y] for p in lab.poses.values()])).all()


def test_placed_targets_keep_away_from_the_rooms_exits(tmp_path):
    """In TWO_ROOMS the west room's floor reaches into the door (x 4, y 2.8-4): (3.6, 3.4) is in the
    room, 0.4 m from the door's line, and the reachable floor beyond the room is nearer than 0.45 m
    (the room's floor ends in the doorway): not where a target goes. (1.0, 1.0), far from the door,
    and (3.6, 1.0), by the wall between the rooms (the floor beyond it 0.52 m and more away), are."""
    world = world_file(tmp_path, TWO_ROOMS)
    grid = reachable_grid(world)
    points = np.array([[1.0, 1.0], [3.6, 1.0], [3.6, 3.4]])
    room = learning_room(world, grid, world.start)
    assert room.reachable_at(points).tolist() == [True, True, True]
    assert away_from_exits(room, grid).reachable_at(points).tolist() == [True, True, False]
