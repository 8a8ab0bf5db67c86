"""WatchInterestEdges alone: hand-set map and pose, manual clock, commands read back."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.control import Parallel
from behaviours.exploration.follow_path import FollowPath
from behaviours.exploration.gaze import WatchInterestEdges
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from drivers.interfaces import PanTiltLimits, PanTiltState
from maps.exploration.gaze import camera_lift, speed_limit
from maps.exploration.goal import Goal, Mode
from maps.exploration.grid import Cell, ExplorationMap, GridFrame
from maps.exploration.head import StereoHead
from maps.exploration.interest import Interest
from perception.geometry import Pose2D

HEAD = StereoHead()  # the defaults of the ports: the simulator's stereo pair on the PTU-D46
PTU, LIMIT, GAZE = "/ptu/command", "/robot/speed_limit", "/map/gaze"
STEP = math.radians(185.1428 / 3600)  # a PTU-D46's position
D46 = PanTiltLimits((-3090 * STEP, 3090 * STEP), (-907 * STEP, 604 * STEP), STEP, STEP, 2902 * STEP, 57 * STEP)


def edge_map(*edges: tuple[list[float], list[float], Interest]) -> ExplorationMap:
    points = np.array([p for a, b, _ in edges for p in (a, b)], dtype=np.float64)
    pairs = np.arange(len(points)).reshape(-1, 2)
    states = np.array([s for _, _, s in edges], dtype=np.uint8)
    return ExplorationMap(GridFrame(0.0, 0.0, 0.1, 2, 2), np.zeros((2, 2), np.float32), points, pairs, states)


LEFT = ([2.1, 1.0, 0.6], [4.0, 2.0, 0.6], Interest.WATCH_NOW)  # bearing atan(1/2) from the pan axis at (0.1, 0)
RIGHT = ([3.1, -1.5, 0.5], [6.0, -3.0, 0.5], Interest.WATCH_NOW)


def watch(**ports) -> WatchInterestEdges:
    return WatchInterestEdges(**{"tilt_step": 0.0, **ports})


def test_pans_to_the_closer_point_and_lifts_the_cameras_by_eq5():
    harness = BehaviourHarness(watch(), blackboard={"/map/exploration": edge_map(LEFT), "/robot/odometry": Pose2D()})
    assert harness.tick() == Status.RUNNING
    cmd = harness.read(PTU)
    assert cmd.pan == pytest.approx(math.atan2(1.0, 2.0))  # eq. 3
    rho = math.hypot(2.0, 1.0)
    assert cmd.tilt == pytest.approx(camera_lift(0.6, HEAD.lens_height, rho, HEAD.vertical_fov))  # eq. 5
    assert cmd.speed == pytest.approx(math.radians(300.0))
    assert harness.read(GAZE).target == 0
    assert harness.read(LIMIT) == pytest.approx(1.2)  # the PTU-D46 keeps up: no limit below the top speed


def test_tilt_is_rounded_to_its_step():
    harness = BehaviourHarness(watch(tilt_step=5.0),
                               blackboard={"/map/exploration": edge_map(LEFT), "/robot/odometry": Pose2D()})
    harness.tick()
    tilt = math.degrees(harness.read(PTU).tilt)
    assert tilt == pytest.approx(round(tilt / 5.0) * 5.0)


def test_a_slow_unit_limits_the_speed_by_eq4():
    harness = BehaviourHarness(watch(pan_rate=5.0), blackboard={"/map/exploration": edge_map(LEFT),
                                                              "/robot/odometry": Pose2D()})
    harness.tick()
    gamma, rho = math.atan2(1.0, 2.0), math.hypot(2.0, 1.0)
    assert harness.read(LIMIT) == pytest.approx(speed_limit(rho, gamma, math.radians(5.0) * 0.8))  # eq. 4
    assert harness.read(LIMIT) < 0.4
    assert report_sections(harness.behaviour)["exploration"]["gaze_speed_limited_fraction"] == 1.0


def test_the_turn_rate_enters_eq4():
    blackboard = {"/map/exploration": edge_map(LEFT), "/robot/odometry": Pose2D(), "/robot/turn": -0.1}
    harness = BehaviourHarness(watch(pan_rate=10.0, turn_rate="{/robot/turn}"), blackboard=blackboard)
    harness.tick()
    gamma, rho = math.atan2(1.0, 2.0), math.hypot(2.0, 1.0)
    assert harness.read(LIMIT) == pytest.approx(speed_limit(rho, gamma, math.radians(10.0) * 0.8, -0.1))


def test_alternates_sides_after_the_dwell_remembering_pa():
    harness = BehaviourHarness(watch(dwell=1.0),
                               blackboard={"/map/exploration": edge_map(LEFT, RIGHT), "/robot/odometry": Pose2D()})
    harness.tick()
    assert harness.read(PTU).pan > 0 and harness.read(GAZE).remembered == 1
    harness.clock.advance(1.1)
    harness.tick()
    assert harness.read(PTU).pan < 0 and (harness.read(GAZE).target, harness.read(GAZE).remembered) == (1, 0)


def test_turns_back_by_eq4_when_the_point_leaves_the_view():
    harness = BehaviourHarness(watch(home_tilt=-35.0),
                               blackboard={"/map/exploration": edge_map(LEFT), "/robot/odometry": Pose2D()})
    harness.tick()
    harness.write("/robot/odometry", Pose2D(3.0, 0.0, 0.0))  # the point is behind, 132 degrees off: out of the image
    harness.tick()
    cmd = harness.read(PTU)
    # eq. 4: phi/2 - atan(robot_radius / keep_ahead) = 31.3633 - atan(0.26 / 1.0) = 31.3633 - 14.5742 deg, left
    assert (math.degrees(cmd.pan), math.degrees(cmd.tilt)) == pytest.approx((16.7891, -35.0), abs=1e-3)
    assert harness.read(GAZE).watched == frozenset({0})


def test_turns_back_to_the_front_with_the_earlier_rule():
    harness = BehaviourHarness(watch(home_tilt=-35.0, turn_back="front", leave="pan_limit"),
                               blackboard={"/map/exploration": edge_map(LEFT), "/robot/odometry": Pose2D()})
    harness.tick()
    harness.write("/robot/odometry", Pose2D(2.1, 0.0, 0.0))  # 95 degrees off: past max_pan, still in the image
    harness.tick()
    cmd = harness.read(PTU)
    assert (cmd.pan, cmd.tilt) == pytest.approx((0.0, math.radians(-35.0)))
    assert harness.read(GAZE).watched == frozenset({0})


def test_the_command_keeps_within_what_the_unit_reports():
    """A PTU-D46 reports +-158.91 deg and 149 deg/s: unseen floor behind on the left is looked at from its
    pan limit, rounded to its 185.1428 arc-second steps, at its top speed."""
    unit = PanTiltState(0.0, 0.0, False, 0.0, D46)
    blackboard = {"/robot/odometry": Pose2D(), "/robot/unseen": Pose2D(-2.0, 0.2), "/ptu/state": unit}
    harness = BehaviourHarness(watch(unseen_ahead="{/robot/unseen}"), blackboard=blackboard)
    harness.tick()
    cmd = harness.read(PTU)
    assert math.degrees(cmd.pan) == pytest.approx(3090 * 185.1428 / 3600)  # 158.91, not 174
    assert cmd.speed == pytest.approx(D46.max_speed)
    assert harness.behaviour.params.pan_rate == pytest.approx(D46.max_speed)  # what the speed limit plans with


def test_fixed_mode_looks_ahead_whatever_the_edges():
    harness = BehaviourHarness(watch(mode="fixed", home_tilt=-30.0),
                               blackboard={"/map/exploration": edge_map(LEFT), "/robot/odometry": Pose2D()})
    harness.tick()
    cmd = harness.read(PTU)
    assert (cmd.pan, cmd.tilt) == pytest.approx((0.0, math.radians(-30.0)))
    assert harness.read(LIMIT) == pytest.approx(1.2)


def test_unseen_floor_ahead_comes_first():
    blackboard = {"/map/exploration": edge_map(LEFT), "/robot/odometry": Pose2D(), "/robot/unseen": Pose2D(1.1, -1.0)}
    harness = BehaviourHarness(watch(unseen_ahead="{/robot/unseen}"), blackboard=blackboard)
    harness.tick()
    cmd = harness.read(PTU)
    assert cmd.pan == pytest.approx(-math.pi / 4)  # from the pan axis at (0.1, 0)
    assert cmd.tilt == pytest.approx(math.atan2(-HEAD.lens_height, math.sqrt(2.0)))
    assert harness.read(GAZE).target == 0  # the edge state carries on
    harness.write("/robot/unseen", None)
    harness.tick()
    assert harness.read(PTU).pan == pytest.approx(math.atan2(1.0, 2.0))


def test_without_a_map_it_looks_ahead():
    harness = BehaviourHarness(watch(), blackboard={"/robot/odometry": Pose2D()})
    assert harness.tick() == Status.RUNNING
    assert harness.read(PTU).pan == 0.0


def free_corridor() -> ExplorationMap:
    cells = np.full((40, 80), Cell.FREE, dtype=np.uint8)
    return ExplorationMap.from_cells(GridFrame(-1.0, -1.0, 0.05, 40, 80), cells)


def test_the_speed_limit_reaches_the_drive():
    """WatchInterestEdges before FollowPath in one parallel: the drive's speed obeys eq. 4."""
    m = free_corridor()
    edges = edge_map(([1.0, 0.6, 1.0], [2.5, 1.5, 1.0], Interest.WATCH_NOW))
    watched = ExplorationMap(m.frame, m.evidence, edges.points, edges.edges, edges.interest)
    path = np.column_stack((np.arange(0.0, 2.5, 0.05), np.zeros(50)))
    goal = Goal(Mode.FRONTIER, (2.45, 0.0), None, 0.0, 2.45, math.nan, path)
    tree = Parallel("drive and watch", [
        watch(pan_rate=5.0, tilt_step=0.0),
        FollowPath(speed=0.8, speed_limit="{/robot/speed_limit}", robot_radius=0.2),
    ], policy="one")
    harness = BehaviourHarness(tree, blackboard={"/map/exploration": watched, "/robot/odometry": Pose2D(),
                                                 "/map/exploration_goal": goal, "/robot/stalled": False})
    harness.tick()
    limit = harness.read(LIMIT)
    gamma, rho = math.atan2(0.6, 0.9), math.hypot(0.9, 0.6)
    assert limit == pytest.approx(speed_limit(rho, gamma, math.radians(5.0) * 0.8))
    assert 0.0 < harness.read("/robot/command").v <= limit < 0.8


def test_the_gaze_report_keeps_its_shape():
    harness = BehaviourHarness(watch(), blackboard={"/map/exploration": edge_map(LEFT), "/robot/odometry": Pose2D()})
    harness.tick()
    harness.write("/robot/odometry", Pose2D(3.0, 0.0, 0.0))  # the point leaves the view
    harness.tick()
    assert report_sections(harness.behaviour) == {"exploration": {
        "gaze_mode": "edges", "gaze_watching_fraction": 0.5, "gaze_edges_watched": 1, "gaze_switches": 0,
        "gaze_speed_limited_fraction": 0.0, "gaze_look_ahead_fraction": 0.0}}


def test_where_the_cameras_look_is_drawn_every_tick():
    harness = BehaviourHarness(watch(), blackboard={"/map/exploration": edge_map(LEFT), "/robot/odometry": Pose2D()})
    node = harness.behaviour
    assert list(node.drawings()) == []  # nothing commanded yet
    harness.tick()
    ray, watched = node.drawings()
    assert ray.entity == "odometry_frame/exploration/gaze" and ray.origins.tolist() == [[0.1, 0.0]]  # the pan axis
    reach = 1.5 * math.cos(harness.read(PTU).tilt)
    assert ray.vectors[0] == pytest.approx(reach * np.array([2.0, 1.0]) / math.sqrt(5.0))  # towards the edge
    assert watched.entity == "odometry_frame/exploration/watched" and watched.positions.tolist() == [[2.1, 1.0]]
    assert [d.entity for d in node.drawings()] == [ray.entity, watched.entity]  # again: it is every tick
    harness.write("/robot/odometry", Pose2D(3.0, 0.0, 0.0))
    harness.tick()
    assert next(d for d in node.drawings() if d.entity.endswith("watched")).positions.shape == (0, 2)
