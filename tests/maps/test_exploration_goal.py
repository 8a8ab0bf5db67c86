"""Goal selection: attractive power (eq. 1) by hand, frontier mode switching, done."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration.goal import (
    GoalParams,
    Mode,
    ModeSwitch,
    attractive_power,
    candidates,
    select_goal,
    verification_goal,
)
from maps.exploration.grid import Cell, ExplorationMap, GridFrame
from maps.exploration.travel import traversable

NO_RADIUS = GoalParams(eta=0.25, k=1.0, robot_radius=0.0, min_frontier=0.1)
ROBOT = (0.25, 0.55)  # the centre of cell (row 5, col 2)


def explored_strip(points: list[list[float]], *, walled: bool = False) -> ExplorationMap:
    """Explored free floor [0, 2] x [0, 1] in 0.1 m cells (grid rows 1-10, columns 1-20) amid
    unknown cells; ``walled``: a ring of obstacle cells around it."""
    cells = np.zeros((31, 41), dtype=np.uint8)
    cells[1:11, 1:21] = Cell.FREE
    if walled:
        cells[[0, 11], 0:22] = Cell.OBSTACLE
        cells[0:12, [0, 21]] = Cell.OBSTACLE
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return ExplorationMap.from_cells(GridFrame(-0.1, -0.1, 0.1, 31, 41), cells, points=pts)


P1 = [4.0, 0.55, 0.5]  # east: nearest border (1.95, 0.55), d = 2.05, G = 17 cells = 1.7
P2 = [0.25, 2.5, 0.5]  # north: nearest border (0.25, 0.95), d = 1.55, G = 4 cells = 0.4


def test_eq1_attractive_power():
    assert attractive_power(3.0, 4.0, 0.5) == pytest.approx(1.0)
    assert attractive_power(np.array([2.05, 1.55]), np.array([1.7, 0.4]), 0.25) == pytest.approx([1.625, 1.45])


def test_eta_outside_the_papers_range_is_refused():
    with pytest.raises(ValueError, match="eta"):
        GoalParams(eta=0.6)


def test_candidates_by_hand():
    found = candidates(explored_strip([P1, P2]), ROBOT, NO_RADIUS)
    assert found.distance == pytest.approx([2.05, 1.55])
    assert found.border[found.nearest] == pytest.approx(np.array([[1.95, 0.55], [0.25, 0.95]]))
    assert found.border_cost[found.nearest] == pytest.approx([1.7, 0.4])
    assert found.power == pytest.approx([2.05 - 0.25 * 1.7, 1.55 - 0.25 * 0.4])


def test_the_highest_attractive_power_wins_and_eta_trades_distance_for_travel():
    switch, goal = select_goal(ModeSwitch(), explored_strip([P1, P2]), ROBOT, NO_RADIUS)
    assert switch.mode is Mode.ATTRACTION and goal is not None
    assert goal.point == 0 and goal.target == pytest.approx((1.95, 0.55))
    assert (goal.distance, goal.cost, goal.power) == pytest.approx((2.05, 1.7, 1.625))
    assert goal.path[0] == pytest.approx(ROBOT) and goal.path[-1] == pytest.approx(goal.target)
    # eta = 0.5: P1 2.05 - 0.85 = 1.2 < P2 1.55 - 0.2 = 1.35
    _, goal = select_goal(ModeSwitch(), explored_strip([P1, P2]), ROBOT, GoalParams(0.5, 1.0, 0.0, 0.1))
    assert goal is not None and goal.point == 1 and goal.target == pytest.approx((0.25, 0.95))


def test_nearby_lets_only_points_of_borders_about_as_close_as_the_closest_compete():
    m = explored_strip([P1, P2])  # the closest border: (0.05, 0.55), G = 2 cells = 0.2
    # nearby 1: P1's border costs 1.7 > 0.2 + 1.0, out (power -inf); P2's 0.4 <= 1.2 competes and wins,
    # although eq. 1 over both prefers P1 (1.625 > 1.45)
    near = GoalParams(eta=0.25, k=1.0, robot_radius=0.0, min_frontier=0.1, nearby=1.0)
    found = candidates(m, ROBOT, near)
    assert found.power == pytest.approx([-math.inf, 1.55 - 0.25 * 0.4])
    switch, goal = select_goal(ModeSwitch(), m, ROBOT, near)
    assert switch.mode is Mode.ATTRACTION and goal is not None and goal.point == 1
    # nearby 0.1: 0.4 > 0.2 + 0.1, no point attracts: frontier mode, the closest border
    switch, goal = select_goal(ModeSwitch(), m, ROBOT, GoalParams(0.25, 1.0, 0.0, 0.1, nearby=0.1))
    assert switch.mode is Mode.FRONTIER and goal is not None and goal.cost == pytest.approx(0.2)
    with pytest.raises(ValueError, match="nearby"):
        GoalParams(nearby=-1.0)


def test_points_inside_the_explored_area_do_not_attract():
    switch, goal = select_goal(ModeSwitch(), explored_strip([[1.0, 0.5, 0.3], [1.5, 1.5, 0.3]]), ROBOT, NO_RADIUS)
    # the first is on explored floor (d = 0), the second 0.55 m beyond the border (< K)
    assert switch.mode is Mode.FRONTIER and goal is not None and goal.point is None
    assert goal.target == pytest.approx((0.05, 0.55)) and goal.cost == pytest.approx(0.2)  # the closest border
    assert math.isnan(goal.power)


def test_frontier_mode_and_back():
    switch, _ = select_goal(ModeSwitch(), explored_strip([]), ROBOT, NO_RADIUS)
    assert switch.mode is Mode.FRONTIER
    switch, goal = select_goal(switch, explored_strip([P2]), ROBOT, NO_RADIUS)
    assert switch.mode is Mode.ATTRACTION and goal is not None and goal.point == 0


def test_a_spent_point_no_longer_attracts():
    m = explored_strip([P1, P2])
    switch = ModeSwitch().spend(0)
    switch, goal = select_goal(switch, m, ROBOT, NO_RADIUS)
    assert goal is not None and goal.point == 1
    switch, goal = select_goal(switch.spend(1), m, ROBOT, NO_RADIUS)
    assert switch.mode is Mode.FRONTIER and goal is not None


def test_done_when_no_border_is_reachable_and_done_stays():
    switch, goal = select_goal(ModeSwitch(), explored_strip([P1], walled=True), ROBOT, NO_RADIUS)
    assert switch.mode is Mode.DONE and goal is None
    switch, goal = select_goal(switch, explored_strip([P1, P2]), ROBOT, NO_RADIUS)
    assert switch.mode is Mode.DONE and goal is None


def test_borders_beyond_a_gap_the_robot_cannot_pass_do_not_count():
    m = explored_strip([P1], walled=True)
    cells = m.cells.copy()
    cells[6, 21:23] = Cell.FREE  # a 0.1 m slot in the east wall at y = 0.55, explored floor behind it
    m = ExplorationMap.from_cells(m.frame, cells, points=m.points)
    switch, goal = select_goal(ModeSwitch(), m, ROBOT, NO_RADIUS)  # a point robot fits through
    assert switch.mode is Mode.ATTRACTION and goal is not None and goal.target == pytest.approx((2.15, 0.55))
    wide = GoalParams(eta=0.25, k=1.0, robot_radius=0.1, min_frontier=0.1)
    assert select_goal(ModeSwitch(), m, ROBOT, wide)[0].mode is Mode.DONE


def test_mode_switch_transitions():
    a, f, d = ModeSwitch(Mode.ATTRACTION), ModeSwitch(Mode.FRONTIER), ModeSwitch(Mode.DONE)
    assert a.next(point_beyond_k=False, border_reachable=True).mode is Mode.FRONTIER
    assert a.next(point_beyond_k=True, border_reachable=True).mode is Mode.ATTRACTION
    assert f.next(point_beyond_k=True, border_reachable=True).mode is Mode.ATTRACTION
    assert f.next(point_beyond_k=False, border_reachable=True).mode is Mode.FRONTIER
    for s in (a, f, d):
        assert s.next(point_beyond_k=True, border_reachable=False).mode is Mode.DONE
    assert d.next(point_beyond_k=True, border_reachable=True).mode is Mode.DONE
    # patience: DONE only after that many selections in a row without a reachable border
    once = f.next(point_beyond_k=False, border_reachable=False, patience=2)
    assert (once.mode, once.strikes) == (Mode.FRONTIER, 1)
    assert once.next(point_beyond_k=False, border_reachable=True, patience=2).strikes == 0
    assert once.next(point_beyond_k=False, border_reachable=False, patience=2).mode is Mode.DONE


def test_patience_gives_no_goal_before_done():
    walled = explored_strip([P1], walled=True)
    params = GoalParams(eta=0.25, k=1.0, robot_radius=0.0, min_frontier=0.1, patience=2)
    switch, goal = select_goal(ModeSwitch(), walled, ROBOT, params)
    assert switch.mode is Mode.ATTRACTION and goal is None  # look around, then ask again
    switch, goal = select_goal(switch, walled, ROBOT, params)
    assert switch.mode is Mode.DONE and goal is None


def test_selection_needs_the_robots_footprint_first():
    with pytest.raises(ValueError, match="footprint"):
        select_goal(ModeSwitch(), ExplorationMap.empty(resolution=0.1, half_size=1.0), (0.0, 0.0))


def test_points_seen_once_do_not_attract_with_min_sightings():
    m = explored_strip([P1, P2])
    m = ExplorationMap(m.frame, m.evidence, m.points, visited=m.visited, sightings=np.array([1, 3], dtype=np.int32))
    params = GoalParams(eta=0.25, k=1.0, robot_radius=0.0, min_frontier=0.1, min_sightings=2)
    found = candidates(m, ROBOT, params)
    assert found.distance == pytest.approx([0.0, 1.55])
    _, goal = select_goal(ModeSwitch(), m, ROBOT, params)
    assert goal is not None and goal.point == 1


def test_the_current_goal_is_kept_within_the_hysteresis():
    m = explored_strip([P1, P2])  # A_P: P1 1.625, P2 1.45
    _, best = select_goal(ModeSwitch(), m, ROBOT, NO_RADIUS)
    assert best is not None and best.point == 0
    _, current = select_goal(ModeSwitch().spend(0), m, ROBOT, NO_RADIUS)
    assert current is not None and current.point == 1
    keep = GoalParams(eta=0.25, k=1.0, robot_radius=0.0, min_frontier=0.1, hysteresis=0.2)
    _, goal = select_goal(ModeSwitch(), m, ROBOT, keep, current=current)
    assert goal is not None and goal.point == 1  # 1.45 is within 0.2 of 1.625
    tight = GoalParams(eta=0.25, k=1.0, robot_radius=0.0, min_frontier=0.1, hysteresis=0.1)
    _, goal = select_goal(ModeSwitch(), m, ROBOT, tight, current=current)
    assert goal is not None and goal.point == 0


def test_avoided_targets_are_no_candidates_and_the_baseline_ignores_points():
    m = explored_strip([P1, P2])
    found = candidates(m, ROBOT, NO_RADIUS, avoid=np.array([[1.95, 0.55]]))
    assert np.min(np.hypot(*(found.border - [1.95, 0.55]).T)) > NO_RADIUS.avoid_radius
    baseline = GoalParams(eta=0.25, k=1.0, robot_radius=0.0, min_frontier=0.1, closest_frontier=True)
    switch, goal = select_goal(ModeSwitch(), m, ROBOT, baseline)
    assert switch.mode is Mode.FRONTIER and goal is not None and goal.cost == pytest.approx(0.2)


def test_points_next_to_obstacles_do_not_attract_with_a_point_clearance():
    m = explored_strip([[2.15, 0.25, 2.0], [4.0, 0.85, 0.5]], walled=True)  # atop the east wall; farther east
    cells = m.cells.copy()
    cells[7:11, 21] = Cell.UNKNOWN  # a gap in the east wall (y 0.6 - 1.0): the strip has a border there
    m = ExplorationMap.from_cells(m.frame, cells, points=m.points)
    params = GoalParams(eta=0.25, k=1.0, robot_radius=0.0, min_frontier=0.1, point_clearance=0.3)
    found = candidates(m, ROBOT, params)
    assert found.distance[0] == 0.0 and found.distance[1] > 1.0


def doorway(speckle: bool, points: bool = True) -> ExplorationMap:
    """A walled room [0, 3] x [0, 2] (0.1 m cells) with a 0.8 m door in its east wall at y 0.6-1.4
    and a walled passage beyond, explored for 0.4 m (x 3.1-3.5), unknown after; ``speckle``: a 2 x 2
    obstacle clump in the passage at (3.2-3.4, 0.9-1.1), which leaves gaps of 0.3 m either side;
    ``points``: a point seen 1.15 m beyond the border (something to explore there)."""
    cells = np.zeros((23, 51), dtype=np.uint8)  # frame x0 = y0 = -0.1: cell (r, c) centre (c/10 - 0.05, r/10 - 0.05)
    cells[1:21, 1:31] = Cell.FREE  # the room
    cells[[0, 21], 0:32] = Cell.OBSTACLE
    cells[0:22, [0, 31]] = Cell.OBSTACLE
    cells[7:15, 31] = Cell.FREE  # the door, y 0.6-1.4
    cells[7:15, 32:36] = Cell.FREE  # explored beyond it
    cells[[6, 15], 32:36] = Cell.OBSTACLE  # the passage's walls
    if speckle:
        cells[10:12, 33:35] = Cell.OBSTACLE
    beyond = np.array([[4.6, 1.05, 0.5]])  # a point seen through the door, 1.15 m beyond the border
    return ExplorationMap.from_cells(GridFrame(-0.1, -0.1, 0.1, 23, 51), cells,
                                     points=beyond if points else np.zeros((0, 3)))


VERIFY = GoalParams(robot_radius=0.26, min_frontier=0.1, verify_radius=0.1, look_back=1.0)


def test_a_border_closed_by_a_clump_is_looked_at_again_from_look_back_before_it():
    m, robot = doorway(speckle=True), (0.55, 1.05)
    switch, goal = select_goal(ModeSwitch(), m, robot, VERIFY)
    assert goal is None and switch.strikes == 1  # the robot's disc passes no gap: no border is reachable
    goal = verification_goal(m, robot, VERIFY)
    assert goal is not None and goal.mode is Mode.VERIFY and goal.blocked is not None
    # the first cell of the narrow path the robot's disc cannot pass is at the door (within 0.26 of
    # the clump or a jamb); the goal lies 1 m of path before it, inside the room
    assert 2.9 <= goal.blocked[0] <= 3.1
    passable = traversable(m, 0.26)
    rows, cols = m.frame.cell_of(np.array([goal.target]))
    assert passable[rows[0], cols[0]]
    assert 1.7 <= goal.target[0] <= 2.2 and goal.path[-1] == pytest.approx(goal.target)


def test_nothing_to_verify_without_the_clump_or_once_verified_or_when_off():
    robot = (0.55, 1.05)
    clear = doorway(speckle=False)
    _, goal = select_goal(ModeSwitch(), clear, robot, VERIFY)
    assert goal is not None and goal.mode is Mode.ATTRACTION  # the door itself is passable
    m = doorway(speckle=True)
    blocked = verification_goal(m, robot, VERIFY)
    assert blocked is not None and blocked.blocked is not None
    assert verification_goal(m, robot, VERIFY, verified=np.array([blocked.blocked])) is None
    assert verification_goal(m, robot, VERIFY, avoid=np.array([[3.45, y] for y in (0.75, 1.05, 1.35)])) is None
    assert verification_goal(m, robot, GoalParams(robot_radius=0.26, min_frontier=0.1)) is None
    assert verification_goal(doorway(speckle=True, points=False), robot, VERIFY) is None  # nothing seen beyond


def closed_doorway() -> ExplorationMap:
    """:func:`doorway` with a blob across the whole passage (x 3.2-3.4): no gap for any disc."""
    m = doorway(speckle=False)
    cells = m.cells.copy()
    cells[7:15, 33:35] = Cell.OBSTACLE
    return ExplorationMap.from_cells(m.frame, cells, points=m.points)


def test_a_border_closed_with_no_gap_is_looked_at_from_the_nearest_place_the_robot_reaches():
    m, robot = closed_doorway(), (0.55, 1.05)
    assert select_goal(ModeSwitch(), m, robot, VERIFY)[1] is None
    goal = verification_goal(m, robot, VERIFY)
    assert goal is not None and goal.mode is Mode.VERIFY and goal.blocked is not None
    assert 2.7 <= goal.blocked[0] <= 3.1  # where the robot's disc first stops fitting: the door
    rows, cols = m.frame.cell_of(np.array([goal.target]))
    assert traversable(m, 0.26)[rows[0], cols[0]]
    assert 1.6 <= goal.target[0] <= 2.2 and abs(goal.target[1] - 1.05) <= 0.3  # 1 m of path before, facing it
    # looked at once and still there: nothing else closes a border, nothing left to verify
    assert verification_goal(m, robot, VERIFY, verified=np.array([goal.blocked])) is None
