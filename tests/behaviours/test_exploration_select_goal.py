"""SelectGoalPoint alone: hand-set map and pose, manual clock."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.exploration.select_goal import SelectGoalPoint
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from maps.exploration.goal import Mode
from maps.exploration.grid import Cell, ExplorationMap, GridFrame
from perception.geometry import Pose2D

MAP, GOAL, POSE = "/map/exploration", "/map/exploration_goal", "/robot/pose"


def explored_room(points: list[list[float]], *, walled: bool = True) -> ExplorationMap:
    """Explored floor [0, 3] x [0, 2] in 0.1 m cells amid unknown; ``walled``: obstacle cells around
    it except for a 0.8 m gap in the east wall (so its only border is the gap)."""
    cells = np.zeros((40, 60), dtype=np.uint8)
    cells[10:30, 10:40] = Cell.FREE
    if walled:
        cells[[9, 30], 9:41] = Cell.OBSTACLE
        cells[9:31, [9, 40]] = Cell.OBSTACLE
        cells[16:24, 40] = Cell.FREE  # the gap: y 0.6 - 1.4
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return ExplorationMap.from_cells(GridFrame(-1.0, -1.0, 0.1, 40, 60), cells, points=pts)


FAR_EAST = [5.0, 1.1, 0.5]  # 1.95 m beyond the gap's border


def select(**ports) -> SelectGoalPoint:
    defaults = dict(robot_radius=0.2, margin=0.0, penalty=0.0, min_frontier=0.1, min_sightings=1,
                    odometry="{/robot/pose}")
    return SelectGoalPoint(**{**defaults, **ports})


def test_a_point_beyond_the_border_makes_the_goal_its_border_point():
    harness = BehaviourHarness(select(), blackboard={MAP: explored_room([FAR_EAST]), POSE: Pose2D(0.5, 1.0)})
    assert harness.tick() == Status.RUNNING
    goal = harness.read(GOAL)
    assert goal.mode is Mode.ATTRACTION and goal.point == 0
    assert goal.target == pytest.approx((3.05, 1.05))  # the gap's border cell nearest the point
    assert goal.power == pytest.approx(goal.distance - 0.25 * goal.cost)  # eq. 1
    assert goal.path[0] == pytest.approx((0.55, 1.05)) and goal.path[-1] == pytest.approx(goal.target)


def test_frontier_mode_without_points_and_back_when_one_appears():
    harness = BehaviourHarness(select(reselect=1.0), blackboard={MAP: explored_room([]), POSE: Pose2D(0.5, 1.0)})
    harness.tick()
    assert harness.read(GOAL).mode is Mode.FRONTIER
    harness.write(MAP, explored_room([FAR_EAST]))
    harness.clock.advance(0.5)
    harness.tick()  # not yet time to choose again
    assert harness.read(GOAL).mode is Mode.FRONTIER
    harness.clock.advance(0.6)
    harness.tick()
    assert harness.read(GOAL).mode is Mode.ATTRACTION
    section = report_sections(harness.behaviour)["exploration"]
    assert section["mode_switches"] == [[0.0, "attraction", "frontier"], [1.1, "frontier", "attraction"]]
    assert section["goal_count"] == 2


def test_the_closest_frontier_strategy_never_follows_points():
    harness = BehaviourHarness(select(strategy="closest_frontier"),
                               blackboard={MAP: explored_room([FAR_EAST]), POSE: Pose2D(0.5, 1.0)})
    harness.tick()
    goal = harness.read(GOAL)
    assert goal.mode is Mode.FRONTIER and goal.point is None


def test_the_strategies_set_the_goal_parameters():
    assert select().params.nearby == 1.0 and not select().params.closest_frontier  # nearby_attraction
    assert select(nearby=2.5).params.nearby == 2.5
    assert select(strategy="attraction", nearby=2.5).params.nearby == math.inf  # eq. 1 over all points
    assert select(strategy="closest_frontier").params.closest_frontier


def test_nearby_attraction_prefers_the_near_border_eq1_over_all_points_the_far_one():
    """Two gaps: one next to the robot with a point 1.5 m beyond, one across the room with a point 4 m
    beyond. Eq. 1 over all points goes across (4 - 0.25 G beats 1.5 - 0.25 G'); nearby_attraction
    stays near: the far gap's border costs more than nearby (1 m) beyond the closest border."""
    m = explored_room([[-1.5, 1.0, 0.5], [7.0, 1.0, 0.5]])
    cells = m.cells.copy()
    cells[16:24, 9] = Cell.FREE  # a gap in the west wall too (y 0.6 - 1.4)
    m = ExplorationMap.from_cells(m.frame, cells, points=m.points)
    blackboard = {MAP: m, POSE: Pose2D(0.5, 1.0)}
    harness = BehaviourHarness(select(strategy="attraction"), blackboard=blackboard)
    harness.tick()
    assert harness.read(GOAL).point == 1 and harness.read(GOAL).target[0] > 2.5
    harness = BehaviourHarness(select(), blackboard=blackboard)
    harness.tick()
    assert harness.read(GOAL).point == 0 and harness.read(GOAL).target[0] < 0.5


def test_reaching_the_goal_spends_its_point_and_chooses_again():
    harness = BehaviourHarness(select(), blackboard={MAP: explored_room([FAR_EAST]), POSE: Pose2D(0.5, 1.0)})
    harness.tick()
    target = harness.read(GOAL).target
    harness.write(POSE, Pose2D(target[0] - 0.3, target[1]))  # within reach (0.6 m)
    assert harness.tick() == Status.RUNNING
    assert 0 in harness.behaviour.switch.spent and harness.behaviour.reached == 1
    # the point is spent, the gap's border avoided; nothing else is left: the gap's second chance
    goal = harness.read(GOAL)
    assert goal.mode is Mode.FRONTIER and harness.behaviour.forgiven == [target]
    harness.clock.advance(0.1)
    assert harness.tick() == Status.FAILURE  # reached again: avoided for good, no border left: look around
    assert harness.read(GOAL) is None and harness.behaviour.reached == 2 and len(harness.behaviour.given_up) == 1


def test_no_reachable_border_fails_until_patience_then_succeeds():
    closed = explored_room([])
    cells = closed.cells.copy()
    cells[16:24, 40] = Cell.OBSTACLE  # the gap closed
    closed = ExplorationMap.from_cells(closed.frame, cells)
    harness = BehaviourHarness(select(patience=2), blackboard={MAP: closed, POSE: Pose2D(0.5, 1.0)})
    assert harness.tick() == Status.FAILURE  # look around, then ask again
    assert "look around" in harness.behaviour.feedback_message
    assert harness.tick() == Status.SUCCESS
    assert report_sections(harness.behaviour)["exploration"]["done"] is True


def test_a_goal_abandoned_by_a_halt_is_avoided():
    harness = BehaviourHarness(select(), blackboard={MAP: explored_room([FAR_EAST]), POSE: Pose2D(0.5, 1.0)})
    harness.tick()
    target = harness.read(GOAL).target
    harness.halt()  # path following failed: the parallel halts the selection
    assert harness.read(GOAL) is None and harness.behaviour.avoid == [target]
    assert harness.behaviour.abandoned == 1


def test_abandoned_border_points_get_a_second_chance_before_done():
    harness = BehaviourHarness(select(patience=1), blackboard={MAP: explored_room([]), POSE: Pose2D(0.5, 1.0)})
    harness.tick()
    first = harness.read(GOAL).target
    harness.halt()  # abandoned: avoided
    assert harness.tick() == Status.RUNNING  # nothing else is left: the gap gets its second chance
    assert harness.read(GOAL).target == pytest.approx(first)
    assert harness.behaviour.forgiven == [first] and harness.behaviour.avoid == []
    harness.halt()  # abandoned again: avoided for good
    assert harness.behaviour.given_up == [first]
    assert harness.tick() == Status.SUCCESS  # patience 1: done


def test_a_goal_whose_path_someone_stepped_onto_is_kept_while_they_stand_there():
    harness = BehaviourHarness(select(reselect=2.0), blackboard={MAP: explored_room([FAR_EAST]),
                                                                 POSE: Pose2D(0.5, 1.0)})
    assert harness.tick() == Status.RUNNING
    goal = harness.read(GOAL)
    cells = harness.read(MAP).cells.copy()
    cells[10:30, 25] = Cell.OBSTACLE  # people across the room at x 1.55, on floor seen free: no way round
    harness.write(MAP, ExplorationMap.from_cells(harness.read(MAP).frame, cells, points=harness.read(MAP).points))
    harness.clock.advance(2.1)
    assert harness.tick() == Status.RUNNING and harness.read(GOAL) is goal  # kept (path following waits)
    assert "moved onto the goal's path" in harness.behaviour.feedback_message
    assert harness.behaviour.switch.strikes == 0


def test_waits_for_the_map():
    harness = BehaviourHarness(select(), blackboard={POSE: Pose2D()})
    assert harness.tick() == Status.RUNNING and harness.read(GOAL) is None



def clumped_gap(clump: bool = True) -> ExplorationMap:
    """The walled room with obstacle cells in the middle of its gap (y 0.9-1.1): two 0.3 m gaps,
    too narrow for a 0.2 m robot, wide enough for a 0.13 m disc."""
    m = explored_room([FAR_EAST])
    cells = m.cells.copy()
    if clump:
        cells[19:21, 40] = Cell.OBSTACLE
    return ExplorationMap.from_cells(m.frame, cells, points=m.points)


def look_at_the_clump(harness: BehaviourHarness) -> tuple[float, float]:
    """Tick until the VERIFY goal for the clump, arrive at it and look: the place looked at."""
    strikes = harness.behaviour.switch.strikes
    assert harness.tick() == Status.RUNNING  # not a strike: look at the clump again
    goal = harness.read(GOAL)
    assert goal.mode is Mode.VERIFY and goal.blocked is not None and goal.blocked[0] > 2.5
    assert goal.path[-1] == pytest.approx(goal.target) and goal.target[0] < goal.blocked[0] - 0.9
    harness.write(POSE, Pose2D(*goal.target))  # arrived: look around from there (a FAILURE, not a strike)
    assert harness.tick() == Status.FAILURE and "look around at it" in harness.behaviour.feedback_message
    assert harness.read(GOAL) is None and harness.behaviour.switch.strikes == strikes
    return goal.blocked


def test_a_border_closed_by_a_clump_is_looked_at_again_before_done():
    harness = BehaviourHarness(select(patience=2), blackboard={MAP: clumped_gap(), POSE: Pose2D(0.5, 1.0)})
    place = look_at_the_clump(harness)
    assert harness.behaviour.verified == [place]
    assert harness.tick() == Status.FAILURE  # the clump is still there; nothing else to look at: a strike
    assert harness.behaviour.switch.strikes == 1
    assert harness.tick() == Status.SUCCESS
    assert report_sections(harness.behaviour)["exploration"]["verifications"] == 1


def test_a_closed_border_seen_from_where_the_robot_stands_is_looked_at_by_the_look_around():
    far = BehaviourHarness(select(patience=2), blackboard={MAP: clumped_gap(), POSE: Pose2D(0.5, 1.0)})
    far.tick()
    look_from, blocked = far.read(GOAL).target, far.read(GOAL).blocked  # 1 m short of the clump
    harness = BehaviourHarness(select(patience=2), blackboard={MAP: clumped_gap(), POSE: Pose2D(look_from[0] - 0.3,
                                                                                                look_from[1])})
    # standing 0.3 m from the look-from point: a goal there would be reached at once, before the cameras
    # turned to the clump; the place is looked at by the look-around the FAILURE starts, not a strike
    assert harness.tick() == Status.FAILURE
    assert harness.read(GOAL) is None and "look around at it again" in harness.behaviour.feedback_message
    (place,) = harness.behaviour.verified  # the clump, reached by a path from here
    assert math.dist(place, blocked) < 0.25 and harness.behaviour.switch.strikes == 0
    assert harness.tick() == Status.FAILURE and harness.behaviour.switch.strikes == 1  # after the look: a strike
    assert report_sections(harness.behaviour)["exploration"]["verifications"] == 1


def test_a_clump_that_clears_when_looked_at_opens_the_border():
    harness = BehaviourHarness(select(reselect=1.0), blackboard={MAP: clumped_gap(), POSE: Pose2D(0.5, 1.0)})
    harness.tick()
    assert harness.read(GOAL).mode is Mode.VERIFY
    harness.write(MAP, clumped_gap(clump=False))  # the floor there was seen free on the way
    harness.clock.advance(1.1)
    assert harness.tick() == Status.RUNNING
    goal = harness.read(GOAL)
    assert goal.mode is Mode.ATTRACTION and goal.target[0] == pytest.approx(3.05)
    assert harness.behaviour.verified == []  # the look was not needed to the end


def test_the_report_keeps_its_shape():
    harness = BehaviourHarness(select(), blackboard={MAP: explored_room([FAR_EAST]), POSE: Pose2D(0.5, 1.0)})
    harness.tick()
    section = report_sections(harness.behaviour)["exploration"]
    assert list(section) == ["mode", "done", "strategy", "selections", "goals_reached", "goals_abandoned",
                             "verifications", "goal_count", "goals", "goal_columns", "mode_switch_count",
                             "mode_switches"]
    goal = harness.read(GOAL)
    assert section["goals"] == [[0.0, "attraction", 3.05, 1.05, 0, round(goal.distance, 3), round(goal.cost, 3),
                                 round(goal.power, 3)]]


def test_a_new_goal_is_drawn_once_with_its_path():
    harness = BehaviourHarness(select(), blackboard={MAP: explored_room([FAR_EAST]), POSE: Pose2D(0.5, 1.0)})
    node = harness.behaviour
    assert list(node.drawings()) == []  # no goal yet
    harness.tick()
    target, path = node.drawings()
    assert target.entity == "odometry_frame/exploration/goal" and target.labels == ("attraction",)
    assert target.positions[0] == pytest.approx((3.05, 1.05)) and target.colours == (255, 80, 80)
    assert path.entity == "odometry_frame/exploration/path" and path.strips[0] is harness.read(GOAL).path
    assert list(node.drawings()) == []  # the same goal: drawn already


def test_the_second_chance_reuses_the_first_selections_travel_cost(monkeypatch):
    """One travel-cost search per tick, however many selections that tick makes from the same place."""
    import maps.exploration.goal as goal_module

    searches = []
    real = goal_module.travel_cost
    monkeypatch.setattr(goal_module, "travel_cost", lambda *a, **k: searches.append(1) or real(*a, **k))
    harness = BehaviourHarness(select(patience=1), blackboard={MAP: explored_room([]), POSE: Pose2D(0.5, 1.0)})
    harness.tick()
    first = harness.read(GOAL).target
    harness.halt()  # abandoned: avoided
    searches.clear()
    assert harness.tick() == Status.RUNNING and harness.behaviour.selections == 3  # none, then the second chance
    assert harness.read(GOAL).target == pytest.approx(first) and len(searches) == 1
