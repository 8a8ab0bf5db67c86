"""Gaze control of the stereo pair: pan (eq. 3), speed limit (eq. 4), lift (eq. 5), alternating sides."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration.gaze import (
    Gaze,
    GazeParams,
    camera_lift,
    next_gaze,
    pan_rate_needed,
    pan_to_point,
    speed_limit,
    survey,
)
from maps.exploration.grid import ExplorationMap, GridFrame
from maps.exploration.head import StereoHead
from maps.exploration.interest import Interest
from perception.geometry import Pose2D

HEAD = StereoHead(ptu=(0.1, 0.0, 1.0), camera=(0.05, 0.0, 0.08))  # lens 1.08 m up
PARAMS = GazeParams(head=HEAD, dwell=1.5)


def test_eq3_pan_is_the_bearing_from_the_pan_axis():
    robot = Pose2D(0.0, 0.0, 0.0)
    axis = HEAD.axis_xy(robot)
    assert axis == pytest.approx([0.1, 0.0])
    pts = np.array([[1.1, 1.0], [0.1, 2.0], [-0.9, 1.0], [1.1, -1.0]])
    assert pan_to_point(robot, axis, pts) == pytest.approx(np.radians([45, 90, 135, -45]))
    turned = Pose2D(0.0, 0.0, math.pi / 2)
    assert pan_to_point(turned, HEAD.axis_xy(turned), np.array([[1.0, 1.1]])) == pytest.approx([-math.pi / 4])


def test_eq3_pan_rate_needed():
    assert pan_rate_needed(1.0, math.pi / 2, v=0.5) == pytest.approx(0.5)
    assert pan_rate_needed(2.0, math.pi / 6, v=1.0, w=0.1) == pytest.approx(0.25 - 0.1)


def test_eq4_speed_limit():
    assert speed_limit(1.0, math.pi / 2, pan_rate=0.5) == pytest.approx(0.5)
    assert speed_limit(1.0, math.pi / 6, pan_rate=0.5) == pytest.approx(1.0)
    assert speed_limit(1.0, math.pi / 2, pan_rate=0.5, w=0.2) == pytest.approx(0.7)  # turning towards it helps
    assert speed_limit(1.0, -math.pi / 2, pan_rate=0.5, w=0.2) == pytest.approx(0.3)  # away from it hurts
    assert speed_limit(1.0, -math.pi / 2, pan_rate=0.5, w=0.6) == 0.0
    assert speed_limit(1.0, 0.0, pan_rate=0.5) == math.inf
    # at the limit, the pan rate needed is exactly the rate available
    v = speed_limit(1.5, math.radians(70), pan_rate=0.8, w=0.1)
    assert pan_rate_needed(1.5, math.radians(70), v, 0.1) == pytest.approx(0.8)


def test_eq5_camera_lift():
    assert camera_lift(h=1.9, l=1.08, d=0.82, beta=math.pi / 3) == pytest.approx(math.radians(45 - 30))
    assert camera_lift(h=0.0, l=1.0, d=1.0, beta=math.pi / 2) == pytest.approx(-math.pi / 2)
    assert camera_lift(h=1.08, l=1.08, d=3.0, beta=0.8) == pytest.approx(-0.4)


def edge_map(*edges: tuple[list[float], list[float], Interest]) -> ExplorationMap:
    """A map holding only the given edges (closer point, farther point, interest state)."""
    points = np.array([p for a, b, _ in edges for p in (a, b)], dtype=np.float64)
    pairs = np.arange(len(points)).reshape(-1, 2)
    states = np.array([s for _, _, s in edges], dtype=np.uint8)
    return ExplorationMap(GridFrame(0.0, 0.0, 0.1, 2, 2), np.zeros((2, 2), np.float32), points, pairs, states)


LEFT = ([2.1, 1.0, 1.08], [4.0, 2.0, 1.0], Interest.WATCH_NOW)  # bearing atan(1/2) from the axis at (0.1, 0)
RIGHT = ([3.1, -1.5, 0.5], [6.0, -3.0, 0.5], Interest.WATCH_NOW)  # bearing -atan(1/2), 3.35 m away
LATER = ([1.1, 0.2, 0.5], [5.0, 1.0, 0.5], Interest.WATCH_LATER)


def test_watch_the_nearest_edge_and_remember_the_other_side():
    m = edge_map(LEFT, RIGHT, LATER)
    gaze, cmd = next_gaze(Gaze(), m, Pose2D(), now=0.0, params=PARAMS)
    assert (gaze.target, gaze.remembered, gaze.side) == (0, 1, 1)
    assert cmd.pan == pytest.approx(math.atan2(1.0, 2.0))
    assert cmd.tilt == pytest.approx(-HEAD.vertical_fov / 2)  # eq. 5: the point is at lens height
    rho = math.hypot(2.0, 1.0)
    assert cmd.max_speed == pytest.approx(rho * math.radians(300) * 0.8 / math.sin(math.atan2(1.0, 2.0)))
    assert cmd.point == pytest.approx(LEFT[0])


def test_alternate_sides_every_dwell_remembering_pa():
    m = edge_map(LEFT, RIGHT)
    gaze, _ = next_gaze(Gaze(), m, Pose2D(), now=0.0, params=PARAMS)
    gaze, cmd = next_gaze(gaze, m, Pose2D(), now=1.0, params=PARAMS)
    assert gaze.target == 0 and cmd.pan > 0
    gaze, cmd = next_gaze(gaze, m, Pose2D(), now=1.6, params=PARAMS)
    assert (gaze.target, gaze.remembered, gaze.side) == (1, 0, -1)
    assert cmd.pan == pytest.approx(-math.atan2(1.5, 3.0))
    assert cmd.tilt == pytest.approx(math.atan2(0.5 - 1.08, math.hypot(3.0, 1.5)) - HEAD.vertical_fov / 2)
    gaze, _ = next_gaze(gaze, m, Pose2D(), now=3.2, params=PARAMS)
    assert (gaze.target, gaze.remembered) == (0, 1)


def test_turn_to_pa_when_the_point_leaves_the_view_then_back_to_the_front():
    m = edge_map(LEFT, RIGHT)
    gaze, _ = next_gaze(Gaze(), m, Pose2D(), now=0.0, params=PARAMS)
    # driven on to x = 2.5: the left point is 117 degrees off the heading, the right one -72
    gaze, cmd = next_gaze(gaze, m, Pose2D(2.5, 0.0, 0.0), now=0.5, params=PARAMS)
    assert (gaze.target, gaze.remembered, gaze.watched) == (1, None, frozenset({0}))
    assert cmd.pan == pytest.approx(math.atan2(-1.5, 0.5))
    gaze, cmd = next_gaze(gaze, m, Pose2D(4.0, 0.0, 0.0), now=1.0, params=PARAMS)
    assert gaze.target is None and gaze.watched == frozenset({0, 1})
    assert (cmd.pan, cmd.tilt, cmd.max_speed, cmd.point) == (0.0, PARAMS.home_tilt, math.inf, None)
    gaze, _ = next_gaze(gaze, m, Pose2D(), now=2.0, params=PARAMS)  # watched edges are not taken again
    assert gaze.target is None


def test_a_followed_edge_stays_watched_after_leaving_the_now_cone_until_90_degrees():
    m = edge_map(LEFT)
    gaze, _ = next_gaze(Gaze(), m, Pose2D(), now=0.0, params=PARAMS)
    later = ExplorationMap(m.frame, m.evidence, m.points, m.edges, np.array([Interest.WATCH_LATER], np.uint8))
    gaze, cmd = next_gaze(gaze, later, Pose2D(1.5, 0.0, 0.0), now=0.1, params=PARAMS)  # 63 degrees off
    assert gaze.target == 0 and cmd.pan == pytest.approx(math.atan2(1.0, 0.5))
    never = ExplorationMap(m.frame, m.evidence, m.points, m.edges, np.array([Interest.NEVER], np.uint8))
    gaze, cmd = next_gaze(gaze, never, Pose2D(1.5, 0.0, 0.0), now=0.2, params=PARAMS)
    assert gaze.target is None and cmd.pan == 0.0


def test_no_edges_look_ahead():
    empty = ExplorationMap.empty(resolution=0.1, half_size=1.0)
    gaze, cmd = next_gaze(Gaze(), empty, Pose2D(), now=0.0, params=PARAMS)
    assert gaze == Gaze() and cmd.pan == 0.0 and cmd.max_speed == math.inf


def test_survey_covers_the_pan_range_from_the_floor_up_to_the_horizon():
    poses = survey(PARAMS, overlap=0.15)
    tilts = sorted(set(np.round(poses[:, 1], 9)))
    assert tilts[0] == pytest.approx(math.radians(-47))
    assert tilts[-1] + HEAD.vertical_fov / 2 >= 0 > tilts[-2] + HEAD.vertical_fov / 2
    row = poses[poses[:, 1] == poses[0, 1], 0]
    assert row[0] == pytest.approx(math.radians(-159)) and row[-1] == pytest.approx(math.radians(159))
    assert np.all(np.diff(row) <= HEAD.horizontal_fov * 0.85 + 1e-9)
    assert poses[len(row), 0] == pytest.approx(math.radians(159))  # the next row comes back
