"""Gaze control of the stereo pair: where a point leaves the view (eq. 3), the turn back (eq. 4), the lift
(eq. 5), the speed limit, alternating sides."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration.gaze import (
    Gaze,
    GazeParams,
    camera_lift,
    distance_to_leave,
    leave_angle,
    leave_range,
    next_gaze,
    pan_rate_needed,
    pan_to_point,
    speed_limit,
    survey,
    turn_back,
)
from maps.exploration.grid import ExplorationMap, GridFrame
from maps.exploration.head import StereoHead
from maps.exploration.interest import Interest
from perception.geometry import Pose2D

HEAD = StereoHead(ptu=(0.1, 0.0, 1.0), camera=(0.05, 0.0, 0.08))  # lens 1.08 m up
PARAMS = GazeParams(head=HEAD, dwell=1.5)
EARLIER = GazeParams(head=HEAD, dwell=1.5, leave="pan_limit", turn_back="front")  # the rules before eq. 3-4


def test_eq3_where_the_closer_point_leaves_the_view_by_hand():
    # a = b cos(beta) / cos(alpha)
    # b = 2, beta = 60, alpha = 30 deg: 2 * 0.5 / 0.866025 = 1.154701
    assert leave_range(2.0, math.radians(60.0), math.radians(30.0)) == pytest.approx(1.154701, abs=1e-6)
    # abeam (beta = 0), alpha = 60 deg: 1.5 * 1 / 0.5 = 3.0
    assert leave_range(1.5, 0.0, math.radians(60.0)) == pytest.approx(3.0)
    # b = 2, 30 deg ahead of the beam, alpha = 45 deg: 2 * 0.866025 / 0.707107 = 2.449490 (sqrt 6);
    # the point is 2 sin 30 = 1 ahead and leaves 2.449490 * sin 45 = 1.732051 behind: 2.732051 m to drive
    assert leave_range(2.0, math.radians(30.0), math.radians(45.0)) == pytest.approx(math.sqrt(6.0))
    assert distance_to_leave(np.array([2.0]), np.radians([30.0]), math.radians(45.0)) == pytest.approx([2.732051])
    # the simulator's pair on the paper's 90 degree pan: alpha = 90 + 31.3633 - 90 = 31.3633 deg, so a point
    # 1 m abeam leaves at a = 1 / cos(31.3633) = sqrt(1 + 0.609524^2) = 1.171119 m, after 0.609524 m more
    alpha = leave_angle(math.pi / 2, HEAD.horizontal_fov)
    assert math.degrees(alpha) == pytest.approx(31.3633, abs=1e-4)
    assert leave_range(1.0, 0.0, alpha) == pytest.approx(1.171119, abs=1e-6)
    assert distance_to_leave(np.array([1.0]), np.array([0.0]), alpha) == pytest.approx([0.609524], abs=1e-6)
    # behind that already: 40 deg behind the beam, 1 m away: -0.642788 + 0.766044 / 0.853884 * 0.520357 = -0.176
    assert distance_to_leave(np.array([1.0]), np.radians([-40.0]), alpha)[0] == pytest.approx(-0.176, abs=1e-3)


def test_eq4_the_turn_back_by_hand():
    # delta = phi/2 - atan(b/a)
    # phi = 120 deg, a = sqrt 3, b = 1: 60 - atan(0.577350) = 60 - 30 = 30 deg
    assert math.degrees(turn_back(math.radians(120.0), math.sqrt(3.0), 1.0)) == pytest.approx(30.0)
    # phi = 90 deg, a = b: 45 - 45 = 0: the head must look straight ahead
    assert turn_back(math.pi / 2, 0.7, 0.7) == pytest.approx(0.0)
    # phi = 60 deg, a = 1, b = sqrt 3: 30 - 60 = -30 deg: past the heading
    assert math.degrees(turn_back(math.radians(60.0), 1.0, math.sqrt(3.0))) == pytest.approx(-30.0)
    # the defaults: phi/2 = 31.3633 deg, a = 1 m ahead, b = 0.26 m across: 31.3633 - 14.5742 = 16.7891 deg
    assert math.degrees(turn_back(HEAD.horizontal_fov, 1.0, 0.26)) == pytest.approx(16.7891, abs=1e-4)


def test_eq5_the_lift_by_hand():
    # alpha = atan((h - l) / d) - beta / 2
    # h 1.9, l 1.08, d 0.82: atan(0.82 / 0.82) = 45; beta 60: 45 - 30 = 15 deg
    assert math.degrees(camera_lift(h=1.9, l=1.08, d=0.82, beta=math.pi / 3)) == pytest.approx(15.0)
    # a point on the floor: h 0.08, l 1.08, d sqrt 3: atan(-1 / 1.732051) = -30; beta 40: -30 - 20 = -50 deg
    assert math.degrees(camera_lift(h=0.08, l=1.08, d=math.sqrt(3.0), beta=math.radians(40.0))) == pytest.approx(-50.0)
    # at lens height: atan(0) - 0.8 / 2 = -0.4 rad
    assert camera_lift(h=1.08, l=1.08, d=3.0, beta=0.8) == pytest.approx(-0.4)


def test_the_pan_is_the_bearing_from_the_pan_axis():
    robot = Pose2D(0.0, 0.0, 0.0)
    axis = HEAD.axis_xy(robot)
    assert axis == pytest.approx([0.1, 0.0])
    pts = np.array([[1.1, 1.0], [0.1, 2.0], [-0.9, 1.0], [1.1, -1.0]])
    assert pan_to_point(robot, axis, pts) == pytest.approx(np.radians([45, 90, 135, -45]))
    turned = Pose2D(0.0, 0.0, math.pi / 2)
    assert pan_to_point(turned, HEAD.axis_xy(turned), np.array([[1.0, 1.1]])) == pytest.approx([-math.pi / 4])


def test_pan_rate_needed():
    assert pan_rate_needed(1.0, math.pi / 2, v=0.5) == pytest.approx(0.5)
    assert pan_rate_needed(2.0, math.pi / 6, v=1.0, w=0.1) == pytest.approx(0.25 - 0.1)


def test_speed_limit_at_which_the_pan_keeps_up():
    assert speed_limit(1.0, math.pi / 2, pan_rate=0.5) == pytest.approx(0.5)
    assert speed_limit(1.0, math.pi / 6, pan_rate=0.5) == pytest.approx(1.0)
    assert speed_limit(1.0, math.pi / 2, pan_rate=0.5, w=0.2) == pytest.approx(0.7)  # turning towards it helps
    assert speed_limit(1.0, -math.pi / 2, pan_rate=0.5, w=0.2) == pytest.approx(0.3)  # away from it hurts
    assert speed_limit(1.0, -math.pi / 2, pan_rate=0.5, w=0.6) == 0.0
    assert speed_limit(1.0, 0.0, pan_rate=0.5) == math.inf
    # at the limit, the pan rate needed is exactly the rate available
    v = speed_limit(1.5, math.radians(70), pan_rate=0.8, w=0.1)
    assert pan_rate_needed(1.5, math.radians(70), v, 0.1) == pytest.approx(0.8)


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


def test_earlier_rules_turn_to_pa_when_the_point_passes_90_degrees_then_back_to_the_front():
    m = edge_map(LEFT, RIGHT)
    gaze, _ = next_gaze(Gaze(), m, Pose2D(), now=0.0, params=EARLIER)
    # driven on to x = 2.5: the left point is 117 degrees off the heading, the right one -72
    gaze, cmd = next_gaze(gaze, m, Pose2D(2.5, 0.0, 0.0), now=0.5, params=EARLIER)
    assert (gaze.target, gaze.remembered, gaze.watched) == (1, None, frozenset({0}))
    assert cmd.pan == pytest.approx(math.atan2(-1.5, 0.5))
    gaze, cmd = next_gaze(gaze, m, Pose2D(4.0, 0.0, 0.0), now=1.0, params=EARLIER)
    assert gaze.target is None and gaze.watched == frozenset({0, 1})
    assert (cmd.pan, cmd.tilt, cmd.max_speed, cmd.point) == (0.0, EARLIER.home_tilt, math.inf, None)
    gaze, _ = next_gaze(gaze, m, Pose2D(), now=2.0, params=EARLIER)  # watched edges are not taken again
    assert gaze.target is None


def test_eq3_a_point_is_followed_at_the_pan_limit_until_it_leaves_the_image_then_eq4_turns_back():
    m = edge_map(LEFT)  # the closer point at (2.1, 1.0): 1 m from the line of travel of the pan axis (y = 0)
    gaze, _ = next_gaze(Gaze(), m, Pose2D(), now=0.0, params=PARAMS)
    # the pan axis at x = 2.5 (robot at 2.4): 111.8 degrees off, 21.8 behind the beam; eq. 3 with b = hypot(0.4, 1)
    # = 1.077, beta = -21.8 deg, alpha = 31.36 deg: a = 1.077 * 0.928 / 0.854 = 1.171, it leaves after
    # -0.4 + 1.171 * 0.520 = 0.209 m more: still followed, the pan held at 90 degrees
    gaze, cmd = next_gaze(gaze, m, Pose2D(2.4, 0.0, 0.0), now=0.5, params=PARAMS)
    assert gaze.target == 0 and cmd.pan == pytest.approx(math.pi / 2)
    # 0.3 m on (0.7 behind the point): 0.209 - 0.3 < 0: it has left the image; nothing else to watch:
    # the head turns back to eq. 4's delta on the left, 16.79 degrees, not to the front
    gaze, cmd = next_gaze(gaze, m, Pose2D(2.7, 0.0, 0.0), now=1.0, params=PARAMS)
    assert gaze.target is None and gaze.watched == frozenset({0}) and gaze.side == 1
    assert math.degrees(cmd.pan) == pytest.approx(16.7891, abs=1e-3)
    assert cmd.tilt == PARAMS.home_tilt and cmd.point is None


def test_eq3_keeps_the_view_of_pa_as_long_as_it_is_in_the_image():
    m = edge_map(LEFT, RIGHT)
    gaze, _ = next_gaze(Gaze(), m, Pose2D(), now=0.0, params=PARAMS)
    gaze, cmd = next_gaze(gaze, m, Pose2D(2.5, 0.0, 0.0), now=0.5, params=PARAMS)  # left at 117: still in view
    assert (gaze.target, gaze.remembered) == (0, 1) and cmd.pan == pytest.approx(math.pi / 2)
    gaze, cmd = next_gaze(gaze, m, Pose2D(2.8, 0.0, 0.0), now=0.6, params=PARAMS)  # now out: to P_A on the right
    assert (gaze.target, gaze.watched) == (1, frozenset({0})) and cmd.pan < 0


def test_a_followed_edge_stays_watched_after_leaving_the_now_cone():
    m = edge_map(LEFT)
    gaze, _ = next_gaze(Gaze(), m, Pose2D(), now=0.0, params=PARAMS)
    later = ExplorationMap(m.frame, m.evidence, m.points, m.edges, np.array([Interest.WATCH_LATER], np.uint8))
    gaze, cmd = next_gaze(gaze, later, Pose2D(1.5, 0.0, 0.0), now=0.1, params=PARAMS)  # 63 degrees off
    assert gaze.target == 0 and cmd.pan == pytest.approx(math.atan2(1.0, 0.5))
    never = ExplorationMap(m.frame, m.evidence, m.points, m.edges, np.array([Interest.NEVER], np.uint8))
    gaze, cmd = next_gaze(gaze, never, Pose2D(1.5, 0.0, 0.0), now=0.2, params=EARLIER)
    assert gaze.target is None and cmd.pan == 0.0


def test_the_rules_are_checked():
    with pytest.raises(ValueError, match="leave is one of"):
        GazeParams(leave="later")
    with pytest.raises(ValueError, match="eq. 3 needs"):
        GazeParams(max_pan=math.radians(160.0))
    GazeParams(max_pan=math.radians(160.0), leave="pan_limit")


def test_within_the_limits_a_unit_reports():
    unit = PARAMS.within((math.radians(-158.91), math.radians(158.91)), (math.radians(-46.6), math.radians(31.0)),
                         math.radians(149.2))
    assert unit.pan_limits == pytest.approx(np.radians([-158.91, 158.91]))
    assert unit.tilt_limits == pytest.approx(np.radians([-46.6, 31.0]))
    assert unit.pan_rate == pytest.approx(math.radians(149.2)) and unit.max_pan == PARAMS.max_pan
    narrow = PARAMS.within((-1.0, 1.0), (-1.0, 1.0), 10.0)
    assert narrow.max_pan == 1.0 and narrow.pan_rate == PARAMS.pan_rate
    with pytest.raises(ValueError, match="leave nothing"):
        PARAMS.within((2.9, 3.0), (-1.0, 1.0), 1.0)


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
