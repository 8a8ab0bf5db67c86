"""MapStereo alone: hand-set pose, pan-tilt state and a rendered stereo pair, manual clock."""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.exploration.map_stereo import MapStereo
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from drivers.sim.simulation import Simulation
from maps.exploration.codec import unpack_cells
from maps.exploration.grid import Cell
from perception.geometry import Pose2D
from perception.ranges import RangeScan, RangeSensor

MAP, POSE = "/map/exploration", "/robot/pose"


@pytest.fixture(scope="module")
def stereo_frame():
    """One stereo pair from the lab, the head tilted down 30 degrees (rendered once)."""
    sim = Simulation.load("lab", seed=0, noise=False)
    sim.ptu.move(0.0, math.radians(-30.0), 10.0)
    sim.step(0.5)
    return sim.robot.cameras["stereo"].grab(), sim.ptu.state()


def test_the_first_tick_marks_the_start_disc_and_nothing_ticks_without_a_pose():
    harness = BehaviourHarness(MapStereo(start_radius=0.6, odometry="{/robot/pose}"))
    assert harness.tick() == Status.RUNNING and harness.read(MAP) is None
    harness.write(POSE, Pose2D(1.0, 2.0, 0.3))
    assert harness.tick() == Status.RUNNING
    m = harness.read(MAP)
    assert m.explored_area == pytest.approx(math.pi * 0.6**2, rel=0.05)
    assert m.cell_state(np.array([[1.0, 2.0], [1.5, 2.0], [1.7, 2.0]])).tolist() == [Cell.FREE, Cell.FREE, Cell.UNKNOWN]


def test_stereo_is_integrated_once_per_new_frame_and_period(stereo_frame):
    frame, ptu = stereo_frame
    harness = BehaviourHarness(MapStereo(period=0.4, odometry="{/robot/pose}"),
                               blackboard={POSE: Pose2D(), "/ptu/state": ptu, "/perception/frames": {"stereo": frame}})
    harness.tick()
    m = harness.read(MAP)
    assert len(m.points) > 500 and m.explored_area > 3.0  # the floor ahead, up to 3 m
    assert len(harness.behaviour.scans) == 1
    later = type(frame)(frame.image, frame.camera, frame.stamp + 0.2, frame.camera_name, frame.right)
    harness.write("/perception/frames", {"stereo": later})
    harness.clock.advance(0.2)
    harness.tick()  # a new frame, but within the period of the last integration
    assert len(harness.behaviour.scans) == 1
    newer = type(frame)(frame.image, frame.camera, frame.stamp + 0.5, frame.camera_name, frame.right)
    harness.write("/perception/frames", {"stereo": newer})
    harness.clock.advance(0.3)
    harness.tick()  # the period is over
    assert len(harness.behaviour.scans) == 2
    harness.clock.advance(0.5)
    harness.tick()  # the same frame again: nothing new
    assert len(harness.behaviour.scans) == 2


def test_the_report_has_the_map_and_the_scans(stereo_frame):
    frame, ptu = stereo_frame
    harness = BehaviourHarness(MapStereo(odometry="{/robot/pose}"),
                               blackboard={POSE: Pose2D(), "/ptu/state": ptu, "/perception/frames": {"stereo": frame}})
    harness.tick()
    section = report_sections(harness.behaviour)["exploration"]
    scan = section["scans"][0]
    assert scan[:3] == [0.0, 0.0, round(ptu.tilt, 4)] and len(scan) == 3 + section["scan"]["bins"]
    assert section["scan"]["bins"] == math.ceil(math.degrees(section["scan"]["horizontal_fov"]))
    m = harness.read(MAP)
    cells = unpack_cells(section["map"]["explored"], m.frame.rows, m.frame.cols)
    assert np.array_equal(cells, m.cells == Cell.FREE)
    assert section["explored_area_m2"] == pytest.approx(m.explored_area)


    assert list(section) == ["explored_area_m2", "obstacle_area_m2", "path_length_m", "points", "edges", "integrations",
                             "area_over_time", "map", "scan", "scans"]  # the shape the evaluation reads
    assert list(section["map"]) == ["x0", "y0", "resolution", "rows", "cols", "explored"]
    assert section["area_over_time"][-1] == [0.0, round(m.explored_area, 3), 0.0]


def test_without_a_pose_the_report_has_no_map():
    node = MapStereo()
    BehaviourHarness(node).tick()
    assert report_sections(node) == {"exploration": {"explored_area_m2": 0.0}}


def test_the_map_is_drawn_on_the_first_integration_and_then_every_tenth(stereo_frame):
    frame, ptu = stereo_frame
    harness = BehaviourHarness(MapStereo(period=0.0, odometry="{/robot/pose}"),
                               blackboard={POSE: Pose2D(), "/ptu/state": ptu, "/perception/frames": {"stereo": frame}})
    node = harness.behaviour
    harness.tick()
    entities = [d.entity for d in node.drawings()]
    assert entities[:3] == ["odometry_frame/exploration/map", "odometry_frame/exploration/map_origin",
                            "odometry_frame/exploration/explored"]
    assert "exploration_3d/points" in entities
    assert list(node.drawings()) == []  # drawn already
    later = type(frame)(frame.image, frame.camera, frame.stamp + 0.5, frame.camera_name, frame.right)
    harness.write("/perception/frames", {"stereo": later})
    harness.clock.advance(0.5)
    harness.tick()
    assert len(node.scans) == 2 and list(node.drawings()) == []  # the second integration: not drawn


def test_range_echoes_clear_obstacle_cells_near_the_robot():
    harness = BehaviourHarness(MapStereo(start_radius=0.3, odometry="{/robot/pose}"))
    harness.write(POSE, Pose2D(0.0, 0.0, math.pi / 2))  # facing +y
    harness.tick()
    m = harness.read(MAP)
    evidence = m.evidence.copy()
    near, far = m.frame.cell_of(np.array([[0.0, 0.8]])), m.frame.cell_of(np.array([[0.0, 2.2]]))
    evidence[near], evidence[far] = 3.5, 3.5  # ahead of the robot: 0.8 m and 2.2 m (beyond ECHO_REACH)
    harness.behaviour.map = m.replaced(evidence=evidence)
    harness.write("/robot/ranges", RangeScan((RangeSensor(0.1, 0.0, 0.0),), np.array([3.0]), 1.0))
    harness.tick()
    m = harness.read(MAP)
    assert m.cell_state(np.array([[0.0, 0.8], [0.0, 2.2]])).tolist() == [Cell.FREE, Cell.OBSTACLE]
