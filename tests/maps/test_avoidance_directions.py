"""The free direction closest to the wish, and the command that takes it, against hand-worked cases.

The footprint is a 0.4 m square grown by the 0.1 m clearance to a 0.6 m square (half-width 0.3).
Seven directions every 30 degrees from -90 to 90; the detour needs 0.5 m free.
A wall of three points 0.6 m ahead, y = -0.2, 0, 0.2: straight ahead the grown front edge meets it
after 0.3 m. Facing 60 degrees left the points lie at y' = -0.6 sin 60 + y cos 60 = -0.52 + y / 2,
all beyond -0.3: nothing in the way; likewise 60 degrees right, and 90 either way.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.avoidance.directions import angles, choose, steer, wished_direction
from maps.avoidance.sweep import AvoidSettings, DetourLine, Surroundings
from perception.geometry import Pose2D
from perception.polygons import rectangle

SEVEN = AvoidSettings(rectangle(0.2, 0.2, 0.2), clearance=0.1, speed=0.2, spread=math.radians(90.0), directions=7,
                      turn_first=math.radians(30.0), turn_rate=math.radians(45.0), steer_time=1.0, max_stray=1.5)
WALL = np.array([[0.6, -0.2], [0.6, 0.0], [0.6, 0.2]])
DEG = math.radians(1.0)


def around(points: np.ndarray) -> Surroundings:
    return Surroundings.of(points, SEVEN)


def test_the_wish_is_where_the_command_heads_within_the_spread():
    # eq. 4: the turn rate times steer_time; a turn on the spot wishes for the edge of the histogram
    assert wished_direction(0.3, 0.2, SEVEN) == pytest.approx(0.2)
    assert wished_direction(0.3, 3.0, SEVEN) == pytest.approx(math.pi / 2)
    assert wished_direction(0.0, -0.5, SEVEN) == pytest.approx(-math.pi / 2)
    assert wished_direction(0.0, 0.0, SEVEN) == 0.0
    assert np.degrees(angles(SEVEN)) == pytest.approx([-90, -60, -30, 0, 30, 60, 90])


def test_a_wall_ahead_sends_the_robot_sixty_degrees_to_one_side():
    choice = choose(around(WALL), 0.0, SEVEN, reach=0.5)
    free = [d.free for d in choice.directions]
    assert free[3] == pytest.approx(0.3)  # straight ahead: blocked
    assert free[0] == free[1] == free[5] == free[6] == math.inf
    assert [d.will_do(0.5) for d in choice.directions] == [True, True, False, False, False, True, True]
    assert choice.chosen in (1, 5)  # equally close to the wish, equal room: one of the two
    # a wish a little to the left, or a detour that took the left, goes left; and the other way
    assert choose(around(WALL), 5 * DEG, SEVEN, reach=0.5).chosen == 5
    assert choose(around(WALL), 0.0, SEVEN, reach=0.5, side=1).chosen == 5
    assert choose(around(WALL), 0.0, SEVEN, reach=0.5, side=-1).chosen == 1
    assert choose(around(WALL), 0.0, SEVEN, reach=0.5, side=1).side == 1


def test_the_detours_side_is_left_only_when_nothing_there_will_do():
    # (0, 0.45) on the left: facing 60 degrees left it lies at (0.39, 0.225), in the grown square's way
    # after 0.09 m; facing 90 degrees left at (0.45, 0), after 0.15 m
    both = np.vstack((WALL, [[0.0, 0.45]]))
    choice = choose(around(both), 0.0, SEVEN, reach=0.5, side=1)
    assert choice.directions[5].free == pytest.approx(0.09, abs=1e-3)
    assert choice.directions[6].free == pytest.approx(0.15)
    assert choice.chosen == 1


def test_a_detour_stays_within_max_stray_of_its_line():
    # 1.4 m left of the line, heading along it: 0.5 m at 60 deg left ends 1.833 m from it, at 90 deg 1.9;
    # at 60 deg right 0.967 m, coming back
    line, aside = DetourLine(0.0, 0.0, 0.0), Pose2D(0.0, 1.4, 0.0)
    choice = choose(around(WALL), 0.0, SEVEN, reach=0.5, side=1, pose=aside, line=line)
    assert [d.strays for d in choice.directions] == [False, False, False, False, True, True, True]
    assert choice.chosen == 1 and not choice.only_straying
    # with the right blocked too ((0, -0.45), mirrored from the case above), only the bound holds the robot
    held = choose(around(np.vstack((WALL, [[0.0, -0.45]]))), 0.0, SEVEN, reach=0.5, pose=aside, line=line)
    assert held.chosen is None and held.only_straying


def test_a_direction_far_off_the_heading_is_turned_to_on_the_spot_first():
    # eq. 6: 60 degrees is beyond turn_first (30): turn left on the spot at 45 deg/s
    wall = around(WALL)
    assert steer(choose(wall, 0.0, SEVEN, reach=0.5, side=1), wall, SEVEN) == pytest.approx((0.0, math.radians(45)))
    # 30 degrees off, with its arc free: 0.2 m/s, turning 30 degrees over steer_time (1 s)
    clear = around(np.array([[2.0, -1.0]]))
    choice = choose(clear, 30 * DEG, SEVEN, reach=0.5)
    assert choice.chosen == 4 and steer(choice, clear, SEVEN) == pytest.approx((0.2, math.radians(30)))
    # none chosen: stop
    boxed = around(np.array([[0.35 * math.cos(a), 0.35 * math.sin(a)] for a in np.linspace(-2, 2, 21)]))
    assert steer(choose(boxed, 0.0, SEVEN, reach=0.5), boxed, SEVEN) == (0.0, 0.0)


def test_the_choice_is_mirror_symmetric():
    fan = AvoidSettings(rectangle(0.2, 0.2, 0.2), clearance=0.1, speed=0.2, directions=25)
    points = np.array([[0.7, -0.1], [0.75, 0.05], [0.5, -0.4]])
    choice = choose(Surroundings.of(points, fan), 0.3, fan, reach=0.5)
    mirrored = choose(Surroundings.of(points * [1.0, -1.0], fan), -0.3, fan, reach=0.5)
    assert choice.chosen is not None and mirrored.chosen == len(choice.directions) - 1 - choice.chosen
