"""FollowPath alone: hand-set map, goal and pose; commands and safety decisions read back."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.exploration.follow_path import FollowPath, approach_speed
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from drivers.interfaces import STOP
from maps.exploration.goal import Goal, Mode
from maps.exploration.grid import Cell, ExplorationMap, GridFrame
from perception.geometry import Pose2D
from perception.ranges import RangeScan, RangeSensor

FRAME = GridFrame(-1.0, -1.0, 0.05, 40, 100)  # x -1..4, y -1..1


def room(*, unknown_from: float | None = None, wall_at: float | None = None) -> ExplorationMap:
    """Free floor; optionally unknown from x = ``unknown_from`` on, or a wall across at x = ``wall_at``."""
    cells = np.full(FRAME.shape, Cell.FREE, dtype=np.uint8)
    xs = FRAME.centre_of(np.zeros(FRAME.cols, dtype=int), np.arange(FRAME.cols))[:, 0]
    if unknown_from is not None:
        cells[:, xs >= unknown_from] = Cell.UNKNOWN
    if wall_at is not None:
        cells[:, np.abs(xs - wall_at) < 0.03] = Cell.OBSTACLE
    return ExplorationMap.from_cells(FRAME, cells)


def goal_to(x: float, y: float = 0.0) -> Goal:
    n = int(round(x / 0.05)) + 1
    path = np.column_stack((np.linspace(0.0, x, n), np.linspace(0.0, y, n)))
    return Goal(Mode.FRONTIER, (x, y), None, 0.0, x, math.nan, path)


def follow(m: ExplorationMap, goal: Goal | None, pose: Pose2D | None = None, **ports) -> BehaviourHarness:
    node = FollowPath(**{"speed": 0.4, "robot_radius": 0.25, **ports})
    return BehaviourHarness(node, blackboard={"/map/exploration": m, "/map/exploration_goal": goal,
                                              "/robot/odometry": pose or Pose2D(), "/robot/stalled": False})


def drive(harness: BehaviourHarness, dt: float = 0.2) -> None:
    pose, cmd = harness.read("/robot/odometry"), harness.read("/robot/command") or STOP
    harness.write("/robot/odometry", Pose2D(pose.x + cmd.v * dt * math.cos(pose.theta),
                                            pose.y + cmd.v * dt * math.sin(pose.theta), pose.theta + cmd.w * dt))


def test_drives_along_the_path_and_stops_at_the_goal():
    harness = follow(room(), goal_to(3.0))
    assert harness.tick() == Status.RUNNING
    assert harness.read("/robot/command").v > 0.0
    for _ in range(200):
        harness.tick()
        drive(harness)
        harness.clock.advance(0.2)
    assert harness.read("/robot/odometry").x == pytest.approx(2.7, abs=0.05)  # tolerance 0.3
    assert harness.tick() == Status.RUNNING and harness.read("/robot/command") == STOP
    assert harness.behaviour.feedback_message == "at the goal"


def test_turns_on_the_spot_towards_a_path_behind():
    harness = follow(room(), goal_to(3.0), Pose2D(0.0, 0.0, math.pi))
    harness.tick()
    cmd = harness.read("/robot/command")
    assert cmd.v == 0.0 and cmd.w != 0.0


def test_the_speed_limit_caps_the_speed():
    harness = follow(room(), goal_to(3.0), speed_limit="{/robot/speed_limit}")
    harness.write("/robot/speed_limit", 0.1)
    harness.tick()
    assert harness.read("/robot/command").v == pytest.approx(0.1)


def test_no_goal_no_motion():
    harness = follow(room(), None)
    assert harness.tick() == Status.RUNNING and harness.read("/robot/command") == STOP


def test_stops_before_unseen_floor_and_says_where_it_is():
    harness = follow(room(unknown_from=1.5), goal_to(3.0), guard=2.0)
    harness.tick()
    unseen = harness.read("/robot/unseen_ahead")
    assert unseen is not None and 1.5 < unseen.x < 1.6 and unseen.y == pytest.approx(0.0, abs=0.03)  # the cells
    for _ in range(100):
        harness.tick()
        drive(harness)
        harness.clock.advance(0.2)
    x = harness.read("/robot/odometry").x
    assert 1.2 < x <= 1.525 - 0.25  # it crawls on from unseen_margin before, and the disc never covers it
    assert harness.behaviour.blind_stops > 0


def test_crawls_within_the_margin_of_unseen_floor():
    harness = follow(room(unknown_from=1.5), goal_to(3.0), pose=Pose2D(1.1, 0.0, 0.0), crawl=0.1, unseen_margin=0.3)
    harness.tick()
    assert harness.read("/robot/command").v == pytest.approx(0.1)


def test_unseen_floor_beside_the_path_does_not_hold_the_robot():
    m = room()
    cells = m.cells.copy()
    ys = FRAME.centre_of(np.arange(FRAME.rows), np.zeros(FRAME.rows, dtype=int))[:, 1]
    cells[ys > 0.2, :] = Cell.UNKNOWN  # unknown from 0.2 m left of the path: within the disc's reach
    harness = follow(ExplorationMap.from_cells(FRAME, cells), goal_to(3.0))
    harness.tick()
    assert harness.read("/robot/unseen_ahead") is None and harness.read("/robot/command").v > 0.3


def test_gives_up_after_no_progress():
    harness = follow(room(unknown_from=1.5), goal_to(3.0), stuck_time=4.0)
    status = harness.tick_until(between=drive, dt=0.2, max_ticks=200)
    assert status == Status.FAILURE and "no progress" in harness.behaviour.feedback_message
    assert harness.read("/robot/command") == STOP


def test_a_wall_across_the_path_fails_the_goal():
    harness = follow(room(wall_at=1.0), goal_to(3.0))
    assert harness.tick() == Status.FAILURE
    assert harness.behaviour.feedback_message == "the goal cannot be reached any more"
    assert harness.behaviour.replans == 1


def test_a_way_back_along_its_own_trail_is_not_blocked_by_what_the_map_saw_beside_it_since():
    """The robot drove into a slot along y = 0 (its trail); the map has since put obstacle cells 0.2 m
    either side (stereo noise, a low bed's edge): within its 0.25 m radius. The path back out along the
    trail is followed, not given up (in `flat` every goal was given up there for 690 s)."""
    cells = room().cells.copy()
    xs = FRAME.centre_of(np.zeros(FRAME.cols, dtype=int), np.arange(FRAME.cols))[:, 0]
    ys = FRAME.centre_of(np.arange(FRAME.rows), np.zeros(FRAME.rows, dtype=int))[:, 1]
    beside = np.abs(np.abs(ys) - 0.2) < 0.03
    cells[np.ix_(beside, xs < 3.0)] = Cell.OBSTACLE
    visited = np.zeros(FRAME.shape, dtype=bool)
    visited[np.ix_(np.abs(ys) < 0.03, (xs > -0.5) & (xs < 3.0))] = True
    m = ExplorationMap.from_cells(FRAME, cells, visited=visited)
    harness = follow(m, goal_to(2.5))
    assert harness.tick() == Status.RUNNING and harness.behaviour.replans == 0
    assert harness.read("/robot/command").v > 0.0
    blind = follow(ExplorationMap.from_cells(FRAME, cells), goal_to(2.5))  # no trail: the same cells block
    assert blind.tick() == Status.FAILURE


def test_waits_for_someone_who_stepped_onto_the_path_then_drives_on():
    harness = follow(room(), goal_to(3.0), wait=6.0)
    assert harness.tick() == Status.RUNNING  # the way is clear: this map is the one to compare with
    harness.write("/map/exploration", room(wall_at=1.0))  # a person across the corridor, on free floor
    harness.clock.advance(0.2)
    assert harness.tick() == Status.RUNNING and harness.read("/robot/command") == STOP
    assert "waiting for it to clear" in harness.behaviour.feedback_message and harness.behaviour.waits == 1
    harness.clock.advance(5.7)  # 5.9 s: still waiting
    assert harness.tick() == Status.RUNNING and harness.read("/robot/command") == STOP
    harness.write("/map/exploration", room())  # they walked on: the floor seen past them
    harness.clock.advance(0.2)
    assert harness.tick() == Status.RUNNING and harness.read("/robot/command").v > 0.0
    assert report_sections(harness.behaviour)["exploration"]["waits"] == 1


def test_gives_the_goal_up_when_the_way_stays_blocked_for_the_wait():
    harness = follow(room(), goal_to(3.0), wait=6.0)
    harness.tick()
    harness.write("/map/exploration", room(wall_at=1.0))
    harness.tick()
    harness.clock.advance(6.0)
    assert harness.tick() == Status.FAILURE and "stayed blocked for 6 s" in harness.behaviour.feedback_message
    assert harness.read("/robot/command") == STOP


def test_a_wall_seen_where_the_floor_was_unknown_fails_at_once():
    harness = follow(room(unknown_from=0.95), goal_to(3.0), wait=6.0, guard=0.0)
    harness.tick()
    harness.write("/map/exploration", room(wall_at=1.0))  # the wall is where nothing was seen before
    harness.clock.advance(0.2)
    assert harness.tick() == Status.FAILURE
    assert harness.behaviour.feedback_message == "the goal cannot be reached any more"


def test_an_obstacle_on_the_path_is_driven_around():
    m = room()
    cells = m.cells.copy()
    rows, cols = FRAME.cell_of(np.array([[1.0, 0.0]]))
    cells[rows[0] - 2 : rows[0] + 3, cols[0] - 2 : cols[0] + 3] = Cell.OBSTACLE  # a post on the path
    harness = follow(ExplorationMap.from_cells(FRAME, cells), goal_to(3.0))
    assert harness.tick() == Status.RUNNING
    assert harness.behaviour.replans == 1
    assert np.min(np.hypot(*(harness.behaviour.path - [1.0, 0.0]).T)) > 0.25


def test_a_stall_backs_away_then_gives_up():
    harness = follow(room(), goal_to(3.0), max_stalls=2, backoff=0.5)
    harness.write("/robot/stalled", True)
    assert harness.tick() == Status.RUNNING and harness.read("/robot/command").v < 0.0
    harness.clock.advance(0.6)
    assert harness.tick() == Status.RUNNING  # the second stall
    harness.clock.advance(0.6)
    assert harness.tick() == Status.FAILURE
    assert report_sections(harness.behaviour)["exploration"]["stalls"] == 3


def with_obstacles(*xy: tuple[float, float]) -> ExplorationMap:
    cells = room().cells.copy()
    for x, y in xy:
        rows, cols = FRAME.cell_of(np.array([[x, y]]))
        cells[rows[0], cols[0]] = Cell.OBSTACLE
    return ExplorationMap.from_cells(FRAME, cells)


def test_slows_to_stop_before_an_obstacle_the_arc_would_touch():
    # a post 0.32 m beside the path at x = 0.6: the path is clear (radius 0.25), the robot with 0.1 m more is not
    harness = follow(with_obstacles((0.6, 0.32)), goal_to(3.0), check_distance=0.0, clearance=0.1)
    post = np.array([0.625, 0.325])  # its cell's centre
    closest = math.inf
    for _ in range(60):
        harness.tick()
        drive(harness)
        harness.clock.advance(0.2)
        pose = harness.read("/robot/odometry")
        closest = min(closest, float(np.hypot(pose.x - post[0], pose.y - post[1])))
    assert closest >= 0.35 - 0.01 and harness.behaviour.safety_stops > 0


def test_where_cutting_the_corner_to_the_carrot_would_come_too_near_it_follows_the_path_itself():
    """A wall 0.275 m to the right (within the 0.30 m room, outside the 0.25 m disc), the robot heading
    25 degrees towards it, its path stepping 5 cm left and then running along the wall. The carrot
    0.4 m on lies 32 degrees left: not enough to turn on the spot, and the arc to it closes on the wall
    at once (held, for ever: in `flat`'s kitchen beside the dining table the robot stood so until its
    goals were given up one after the other). The path's next point 0.1 m away lies 52 degrees left:
    it turns towards that first, then drives along the path."""
    path = np.vstack(([[0.0, 0.0]], np.column_stack((np.arange(0.0, 3.01, 0.05), np.full(61, 0.05)))))
    goal = Goal(Mode.FRONTIER, (3.0, 0.05), None, 0.0, 3.0, math.nan, path)
    harness = follow(with_obstacles(*[(x, -0.275) for x in np.arange(-0.5, 3.0, 0.05)]), goal,
                     Pose2D(0.0, 0.0, math.radians(-25.0)), check_distance=0.0)
    assert harness.tick() == Status.RUNNING
    turn = harness.read("/robot/command")
    assert turn.v == 0.0 and turn.w > 0.0 and harness.behaviour.feedback_message == "turning towards the path (+52 deg)"
    for _ in range(40):
        harness.tick()
        drive(harness)
        harness.clock.advance(0.2)
    pose = harness.read("/robot/odometry")
    assert pose.x > 1.0 and pose.y > -0.02  # along the path, never nearer the wall than it started


def test_a_wall_alongside_does_not_slow_the_robot():
    harness = follow(with_obstacles(*[(x, 0.32) for x in np.arange(-0.5, 3.0, 0.05)]), goal_to(3.0),
                     check_distance=0.0, clearance=0.1)
    harness.tick()
    assert harness.read("/robot/command").v == pytest.approx(0.4)


def test_a_path_with_just_enough_clearance_is_not_blocked():
    """Through a doorway: obstacle cells 0.26 m either side of the path, the robot's radius 0.25."""
    m = room()
    cells = m.cells.copy()
    rows, cols = FRAME.cell_of(np.array([[1.0, 0.3], [1.0, -0.3]]))
    cells[rows, cols] = Cell.OBSTACLE  # the jambs: cell centres (1.025, +-0.325) and the path at y 0.025
    harness = follow(ExplorationMap.from_cells(FRAME, cells), goal_to(3.0))
    assert harness.tick() == Status.RUNNING and harness.behaviour.replans == 0


def test_the_report_keeps_its_shape_and_the_path_is_drawn_when_it_changes():
    m = room()
    cells = m.cells.copy()
    rows, cols = FRAME.cell_of(np.array([[1.0, 0.0]]))
    cells[rows[0] - 2 : rows[0] + 3, cols[0] - 2 : cols[0] + 3] = Cell.OBSTACLE  # a post on the path
    harness = follow(room(), goal_to(3.0))
    node = harness.behaviour
    harness.tick()
    (followed,) = node.drawings()
    assert followed.entity == "odometry_frame/exploration/followed" and followed.strips[0] is node.path
    assert followed.colours == (255, 255, 255) and followed.radius == pytest.approx(0.015)
    harness.tick()
    assert list(node.drawings()) == []  # the same path
    harness.write("/map/exploration", ExplorationMap.from_cells(FRAME, cells))
    harness.tick()  # re-planned round the post
    assert node.replans == 1 and [d.entity for d in node.drawings()] == ["odometry_frame/exploration/followed"]
    assert report_sections(node) == {"exploration": {"stalls": 0, "replans": 1, "stuck": 0, "waits": 0,
                                                     "safety_stops": 0, "blind_stops": 0}}


def test_approach_speed_stops_in_time_for_someone_walking_towards_the_robot():
    # hand: gap 1 m, 1 m/s, 0.25 m/s^2, 0.2 s, 0.05 m: room 0.75, b = 4.2, v = 0.25 (sqrt(4.2^2 + 6) - 4.2)
    v = approach_speed(1.0, 1.0, 0.25, 0.2, 0.05)
    assert v == pytest.approx(0.25 * (math.sqrt(23.64) - 4.2))
    assert v * v / 0.5 + (v + 1.0) * 0.2 + v / 0.25 == pytest.approx(0.95)  # eq. A with equality
    assert approach_speed(1.0, 0.0, 0.25, 0.0, 0.0) == pytest.approx(math.sqrt(2 * 0.25 * 1.0))  # still: braking only
    assert approach_speed(0.2, 1.0, 0.25, 0.2, 0.05) == 0.0  # too late to move on at all
    assert approach_speed(3.0, 1.0, 0.25, 0.2, 0.05) > 0.4


def sonar(front: float, side: float = math.inf) -> RangeScan:
    """A sonar looking straight ahead and one at 60 degrees to the left (readings in m; inf: no echo)."""
    sensors = (RangeSensor(0.1, 0.0, 0.0), RangeSensor(0.1, 0.1, math.radians(60.0)))
    return RangeScan(sensors, np.array([front, side]), 0.0)


def test_an_echo_straight_ahead_caps_the_speed_one_beside_it_does_not():
    harness = follow(room(), goal_to(3.0))
    harness.write("/robot/ranges", sonar(front=1.35))  # the echo at x 1.45: 1.2 m from the disc (radius 0.25)
    harness.tick()
    assert harness.read("/robot/command").v == pytest.approx(approach_speed(1.2, 1.0, 0.25, 0.2, 0.05))
    harness.write("/robot/ranges", sonar(front=math.inf, side=0.8))  # a wall beside: its cone misses the heading
    harness.tick()
    assert harness.read("/robot/command").v == pytest.approx(0.4)
    harness = follow(room(), goal_to(3.0), approach=0.0)
    harness.write("/robot/ranges", sonar(front=1.35))
    harness.tick()
    assert harness.read("/robot/command").v == pytest.approx(0.4)
