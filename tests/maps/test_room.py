"""Room estimate: synthetic stereo views of a known rectangular room against the truth."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maps.room import (
    FreeGrid,
    RigMount,
    RoomEstimate,
    RoomEstimateError,
    RoomParams,
    StereoView,
    dodecagon,
    dodecagon_centre,
    estimate_room,
    reference_index,
)
from perception.camera import PinholeCamera, StereoRig
from perception.geometry import Pose2D
from perception.stereo import points_from_disparity

RIG = StereoRig(PinholeCamera(640, 480, 525.0, 525.0, 319.5, 239.5), PinholeCamera(640, 480, 525.0, 525.0, 319.5,
                                                                                   239.5), 0.12)
MOUNT = RigMount(height=1.08, axis=(0.1, 0.0), offset=(0.05, 0.0))
ROOM_W, ROOM_H, CEILING = 8.0, 6.0, 2.6
RECT = np.array([[0.0, 0.0], [ROOM_W, 0.0], [ROOM_W, ROOM_H], [0.0, ROOM_H]])


def _rect_distance(origin: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Distance from inside the 8 x 6 room to its walls along each angle (analytic)."""
    c, s = np.cos(angle), np.sin(angle)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        tx = np.where(c > 0, (ROOM_W - origin[..., 0]) / c, np.where(c < 0, -origin[..., 0] / c, np.inf))
        ty = np.where(s > 0, (ROOM_H - origin[..., 1]) / s, np.where(s < 0, -origin[..., 1] / s, np.inf))
    return np.minimum(tx, ty)


def _view(pose: Pose2D, pan: float, rng: np.random.Generator, *, count: int = 300, noise_px: float = 0.2,
          outliers: float = 0.02) -> StereoView:
    """Stereo points of the textured walls (and floor) seen from a corner, through real disparities."""
    uv = rng.uniform([0, 0], [639, 479], size=(count, 2))
    body = RIG.left.pixel_to_bearing(uv)  # rig body frame (x forward, y left, z up)
    camera = pose.compose(MOUNT.camera_pose(pan))
    c, s = math.cos(camera.theta), math.sin(camera.theta)
    world_dir = np.column_stack((c * body[:, 0] - s * body[:, 1], s * body[:, 0] + c * body[:, 1]))
    horizontal = np.hypot(world_dir[:, 0], world_dir[:, 1])
    t_wall = _rect_distance(np.array([camera.x, camera.y]), np.arctan2(world_dir[:, 1], world_dir[:, 0])) / horizontal
    z_wall = MOUNT.height + t_wall * body[:, 2]
    t_floor = np.where(body[:, 2] < 0, -MOUNT.height / np.minimum(body[:, 2], -1e-12), np.inf)
    t = np.where(z_wall < 0, t_floor, t_wall)
    seen = z_wall <= CEILING  # the ceiling is untextured
    depth = t[seen] * body[seen, 0]
    disparity = RIG.left.fx * RIG.baseline / depth + rng.normal(0, noise_px, seen.sum())
    bad = rng.random(len(disparity)) < outliers  # mismatches: any disparity
    disparity[bad] = rng.uniform(1.0, 60.0, bad.sum())
    keep = disparity > 0.5
    return StereoView(pose, pan, points_from_disparity(RIG, uv[seen][keep], disparity[keep]).points)


def _views(start: Pose2D, seed: int = 0, **kwargs) -> list[StereoView]:
    rng = np.random.default_rng(seed)
    return [_view(corner, 0.0, rng, **kwargs) for corner in dodecagon(start, 0.25)]


def _truth_in_reference(room: RoomEstimate) -> RoomEstimate:
    ref = room.reference_pose
    pts = [Pose2D(x, y).relative_to(ref) for x, y in RECT]
    return RoomEstimate.from_polygon(np.array([[p.x, p.y] for p in pts]), room.centre)


def test_dodecagon_turns_thirty_degrees_and_closes():
    start = Pose2D(1.0, 2.0, 0.3)
    corners = dodecagon(start, 0.25)
    assert len(corners) == 12
    headings = np.unwrap([c.theta for c in corners])
    np.testing.assert_allclose(np.diff(headings), math.radians(30.0))
    back = corners[-1].compose(Pose2D(0, 0, math.radians(30))).compose(Pose2D(0.25, 0, 0))
    assert back.distance_to(start) < 1e-12
    centre = np.mean([[c.x, c.y] for c in corners], axis=0)
    radii = [math.hypot(c.x - centre[0], c.y - centre[1]) for c in corners]
    np.testing.assert_allclose(radii, 0.25 / (2 * math.sin(math.pi / 12)))


def test_view_from_a_rectified_pair_of_a_wall():
    """A textured wall 1.96875 m ahead: a shift of 32 px between the images (fx B / d)."""
    rng = np.random.default_rng(0)
    texture = cv2.GaussianBlur((rng.random((480, 700)) * 255).astype(np.uint8), (5, 5), 1.2)
    left, right = texture[:, :640].copy(), texture[:, 32:672].copy()  # right: the same point 32 px to the left
    view = StereoView.from_pair(Pose2D(1.0, 2.0, 0.5), 0.25, left, right, RIG)
    assert view.features == len(view.points) > 50
    assert np.median(view.points[:, 0]) == pytest.approx(RIG.left.fx * RIG.baseline / 32, abs=0.01)


def test_reference_is_the_view_with_most_features_first_on_a_tie():
    views = [StereoView(Pose2D(i, 0, 0), 0.0, np.zeros((0, 3)), features=f) for i, f in enumerate([5, 9, 2, 9])]
    assert reference_index(views) == 1
    assert StereoView(Pose2D(), 0.0, np.ones((4, 3))).features == 4  # default: the stereo points


def test_rectangular_room_matches_the_truth():
    start = Pose2D(3.7, 2.6, 0.4)
    room = estimate_room(_views(start), MOUNT)
    truth = _truth_in_reference(room)
    assert room.reference_pose == dodecagon(start, 0.25)[room.reference_index]
    angles = np.linspace(-math.pi, math.pi, 720, endpoint=False)
    error = room.distances(angles) - truth.distances(angles)
    assert np.median(np.abs(error)) < 0.05  # stereo noise at 3-5 m is about 5 cm (measured: 3 cm)
    assert np.quantile(error, 0.95) < 0.03  # the 3rd nearest point: rarely beyond the wall
    assert np.quantile(error, 0.05) > -0.2  # corners are cut by a chord at most a sector wide
    grid = room.free_grid(0.05)
    centres = grid.centres()[grid.free]
    assert truth.contains(centres).mean() > 0.999  # free floor is (almost) never outside the room
    assert grid.free.sum() * 0.05**2 > 0.95 * (ROOM_W - 0.1) * (ROOM_H - 0.1)


def test_reference_frame_round_trip():
    room = estimate_room(_views(Pose2D(4.0, 3.0, -1.0), seed=1), MOUNT)
    pose = Pose2D(1.0, 2.0, 0.5)
    back = room.to_odometry(room.to_reference(pose))
    assert back.distance_to(pose) < 1e-12 and abs(back.theta - pose.theta) < 1e-12
    assert room.to_reference(room.reference_pose).distance_to(Pose2D()) < 1e-12


def test_one_near_mismatch_does_not_close_a_direction():
    views = _views(Pose2D(4.0, 3.0, 0.0), outliers=0.0, seed=2)
    spoiled = views[0].points.copy()
    spoiled[0] = [0.6, 0.0, 0.0]  # one point 60 cm ahead of the first corner at rig height
    views[0] = StereoView(views[0].pose, 0.0, spoiled)
    room = estimate_room(views, MOUNT)
    ahead = room.to_reference(views[0].pose.compose(Pose2D(0.75, 0.0)))
    assert room.contains(np.array([[ahead.x, ahead.y]]))[0]


def test_floor_and_overhead_points_are_not_obstacles():
    views = _views(Pose2D(4.0, 3.0, 0.0), outliers=0.0, seed=3)
    floor = np.array([[1.5, 0.0, -MOUNT.height], [1.5, 0.1, -MOUNT.height], [1.5, -0.1, -MOUNT.height]])
    overhead = floor + [0.0, 0.0, MOUNT.height + 1.0]  # 1 m above the floor
    views[0] = StereoView(views[0].pose, 0.0, np.vstack((views[0].points, floor, overhead)))
    room = estimate_room(views, MOUNT, RoomParams(max_obstacle_height=0.8))
    spot = room.to_reference(views[0].pose.compose(MOUNT.camera_pose(0.0)).compose(Pose2D(1.6, 0.0)))
    assert room.contains(np.array([[spot.x, spot.y]]))[0]


def test_views_that_do_not_go_all_around_are_an_error():
    views = _views(Pose2D(4.0, 3.0, 0.0), seed=4)[:5]
    with pytest.raises(RoomEstimateError, match="all around"):
        estimate_room(views, MOUNT)
    with pytest.raises(RoomEstimateError, match="too few"):
        estimate_room([StereoView(Pose2D(), 0.0, np.zeros((0, 3)))], MOUNT)


@settings(max_examples=60, deadline=None)
@given(st.floats(0.05, 0.95), st.floats(0.05, 0.95), st.floats(-math.pi, math.pi))
def test_ray_casting_matches_the_analytic_rectangle(fx, fy, angle):
    room = RoomEstimate.from_polygon(RECT)
    origin = np.array([fx * ROOM_W, fy * ROOM_H])
    got = room.distance_to_scene(origin[None], np.array([angle]))[0]
    assert got == pytest.approx(_rect_distance(origin, np.array(angle)), rel=1e-9, abs=1e-9)
    assert room.contains(origin[None])[0]
    assert not room.contains(np.array([[ROOM_W + 0.01, origin[1]]]))[0]


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.0, 0.4), st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_standing_is_conservative(seed, radius, fx, fy):
    """Where the robot may stand, every non-free cell square is at least its radius away."""
    rng = np.random.default_rng(seed)
    free = rng.random((24, 20)) > 0.08
    grid = FreeGrid(free, 0.05, (0.3, -0.2))
    x0, y0, x1, y1 = grid.bounds
    p = np.array([x0 + fx * (x1 - x0), y0 + fy * (y1 - y0)])
    if not grid.can_stand(p[None], radius)[0]:
        return
    padded = np.pad(free, 1, constant_values=False)
    blocked = np.argwhere(~padded) - 1  # cell indices, the ring beyond the grid included
    centres = np.asarray(grid.origin) + blocked * grid.cell
    gap = np.maximum(np.abs(p - centres) - grid.cell / 2, 0.0)
    assert np.hypot(gap[:, 0], gap[:, 1]).min() >= radius


def test_the_dodecagon_centre_is_the_corners_circle_radius_at_105_degrees_to_the_start_heading():
    """Worked by hand: side 0.25 m, circle 0.25 / (2 sin 15 deg) = 0.48296 m; facing +y (90 deg) the
    centre lies at 195 deg: (1 + 0.48296 cos 195, 2 + 0.48296 sin 195) = (0.53349, 1.87500). From
    the origin facing +x, at 105 deg: (-0.12500, 0.46651), the mean of the drive's 12 corners."""
    assert dodecagon_centre(Pose2D(1.0, 2.0, math.pi / 2), 0.25) == pytest.approx((0.53349, 1.87500), abs=1e-5)
    corners = np.array([[c.x, c.y] for c in dodecagon(Pose2D(), 0.25)])
    assert corners.mean(axis=0) == pytest.approx((-0.125, 0.46651), abs=1e-5)
    assert dodecagon_centre(Pose2D(), 0.25) == pytest.approx((-0.125, 0.46651), abs=1e-5)
