"""The reachable free floor of a world, against areas computed by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drivers.sim.floor import reachable_floor
from drivers.sim.world import load_world

ROOM = """
name: room
start: {x: 0.8, y: 0.8}
robot: {radius: 0.25}
walls:
  - {points: [[0, 0], [4, 0], [4, 3], [0, 3]], closed: true, height: 2}
boxes:
  - {center: [2.5, 1.5], size: [1, 1], height: 0.7}
pillars:
  - {center: [1.0, 2.2], radius: 0.2, height: 2}
"""


def two_rooms(door: float) -> str:
    """Two 3 x 3 m rooms side by side, a door of width ``door`` from y = 1 in the wall between them."""
    return f"""
        name: two
        start: {{x: 1.5, y: 1.5}}
        robot: {{radius: 0.25}}
        walls:
          - {{points: [[0, 0], [6, 0], [6, 3], [0, 3]], closed: true, height: 2}}
          - {{points: [[3, 0], [3, 1]], height: 2}}
          - {{points: [[3, {1 + door}], [3, 3]], height: 2}}
        """


def test_a_room_with_a_box_and_a_pillar_by_hand(world_file):
    floor = reachable_floor(load_world(world_file(ROOM)), resolution=0.02)
    r = 0.25
    centre_room = (4 - 2 * r) * (3 - 2 * r)  # 3.5 x 2.5
    box = 1.0 + 4 * 1.0 * r + math.pi * r**2  # the 1 x 1 box grown by r (rounded corners)
    pillar = math.pi * (0.2 + r) ** 2
    assert floor.bounded
    assert floor.reachable_area == pytest.approx(centre_room - box - pillar, rel=0.02)  # 5.92 m^2
    # the disc sweeps everything but the four room corners it cannot reach into
    swept = 12.0 - 1.0 - math.pi * 0.2**2 - 4 * (1 - math.pi / 4) * r**2
    assert floor.floor_area == pytest.approx(swept, rel=0.02)
    rows, cols, _ = floor.cells_of(np.array([[2.5, 1.5], [0.1, 1.5], [2.0, 0.5]]))
    assert floor.reachable[rows, cols].tolist() == [False, False, True]
    assert floor.free[rows, cols].tolist() == [False, True, True]  # box interiors are solid
    off_grid = [floor.x0 - 1.0, 1.5]
    assert floor.reachable_at(np.array([[2.5, 1.5], [0.1, 1.5], [2.0, 0.5], off_grid])).tolist() == [
        False, False, True, False]


def test_a_door_narrower_than_the_robot_closes_the_next_room(world_file):
    wide = reachable_floor(load_world(world_file(two_rooms(0.9))), resolution=0.02)
    narrow = reachable_floor(load_world(world_file(two_rooms(0.4))), resolution=0.02)
    one_room = 2.5 * 2.5
    # through the door: the 0.5 x 0.9 m band across the wall minus half discs of r around the jambs
    passage = 0.5 * 0.9 - math.pi * 0.25**2
    assert wide.reachable_area == pytest.approx(2 * one_room + passage, rel=0.02)
    assert narrow.reachable_area == pytest.approx(one_room, rel=0.02)


def test_coverage_of_explored_points(world_file):
    floor = reachable_floor(load_world(world_file(two_rooms(0.9))), resolution=0.05)
    xs, ys = np.meshgrid(np.arange(0.025, 3.0, 0.05), np.arange(0.025, 3.0, 0.05))
    left_room = np.column_stack((xs.ravel(), ys.ravel()))
    assert floor.coverage(left_room) == pytest.approx((6.25 + 0.254 / 2) / (12.5 + 0.254), rel=0.03)
    assert floor.coverage(np.concatenate([left_room, left_room + (3.0, 0.0)])) > 0.98


def test_open_worlds_are_unbounded_and_a_blocked_start_is_refused(world_file):
    text = "start: {x: 1.5, y: 1.0}\nwalls: [{points: [[0, 0], [3, 0]], height: 2}]\n"
    open_world = reachable_floor(load_world(world_file(text)))
    assert not open_world.bounded
    with pytest.raises(ValueError, match="start pose"):
        reachable_floor(load_world(world_file(ROOM.replace("{x: 0.8, y: 0.8}", "{x: 2.5, y: 1.5}"))))


def test_the_rooms_world_is_four_rooms_joined_by_doors():
    world = load_world("rooms")
    floor = reachable_floor(world, resolution=0.05)
    assert floor.bounded and world.ceiling == pytest.approx(2.6)
    centres = np.array([[p.x, p.y] for name, p in world.poses.items() if name.startswith(("room_", "door_"))])
    assert len(centres) == 7
    rows, cols, inside = floor.cells_of(centres)
    assert inside.all() and floor.reachable[rows, cols].all()
    assert 50.0 < floor.reachable_area < 62.0  # of 96 m^2 inside the outer walls


def test_a_window_rasterises_only_the_floor_around_the_start(world_file):
    world = load_world(world_file(ROOM))
    whole = reachable_floor(world, resolution=0.02)
    part = reachable_floor(world, resolution=0.02, window=(-0.5, -0.5, 2.0, 3.5))  # the room's left half
    assert part.reachable.shape == (200, 125)
    assert part.reachable_area == pytest.approx(1.75 * 2.5 - math.pi * 0.45**2, rel=0.03)  # walls and pillar
    assert part.reachable_area < whole.reachable_area and not part.bounded  # open at x = 2
    plane = load_world(world_file("start: {x: 100.0, y: -50.0}\n"))  # no walls: only the window bounds it
    around = reachable_floor(plane, resolution=0.1, window=(95.0, -55.0, 105.0, -45.0))
    assert around.reachable.all() and not around.bounded
    with pytest.raises(ValueError, match="does not hold the start"):
        reachable_floor(world, window=(2.0, 0.0, 4.0, 3.0))
