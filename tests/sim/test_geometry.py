"""Closed-form geometry: bearings to known landmarks, walls at known distances in the panorama,
occlusion by walls and pillars, landmark discs where the camera model puts them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.camera import PanoramaCamera
from perception.geometry import Pose2D

PANO = PanoramaCamera()
CAMERA_Z = 0.9

# uniform grey surfaces: wall black (10), floor mid grey (128), sky bright (170-230)
PLAIN = f"""
floor: {{texture: {{seed: 1, brightness: 128, contrast: 0}}}}
cameras:
  - {{name: panorama, kind: panorama, pose: {{z: {CAMERA_Z}}}}}
  - {{name: landmarks, kind: bearings, pose: {{z: {CAMERA_Z}}}, max_range: 1000}}
"""


def wall_world(x: float, y0: float, y1: float, height: float) -> str:
    return PLAIN + (
        f"walls: [{{points: [[{x}, {y0}], [{x}, {y1}]], height: {height}, "
        "texture: {seed: 2, brightness: 10, contrast: 0}}]\n"
    )


def dark_runs(values: np.ndarray) -> tuple[int, int]:
    idx = np.flatnonzero(values < 60)
    return int(idx.min()), int(idx.max())


@pytest.mark.parametrize(("distance", "height"), [(3.0, 2.5), (6.0, 1.5), (1.5, 3.0)])
def test_wall_top_and_bottom_rows_follow_the_elevation_of_its_edges(sim_from, distance, height) -> None:
    sim = sim_from(wall_world(distance, -40, 40, height))
    image = sim.snapshot(Pose2D(0, 0, 0)).image
    step = math.radians(PANO.deg_per_px)
    top_row = PANO.horizon_row - math.atan((height - CAMERA_Z) / distance) / step
    bottom_row = PANO.horizon_row + math.atan(CAMERA_Z / distance) / step
    first, last = dark_runs(image[:, PANO.width // 2].astype(int))
    assert first == pytest.approx(max(0.0, top_row), abs=1.0)
    assert last == pytest.approx(min(PANO.height - 1.0, bottom_row), abs=1.0)
    assert int(image[min(PANO.height - 1, int(bottom_row) + 3), PANO.width // 2]) == pytest.approx(128, abs=3)


@pytest.mark.parametrize("heading_deg", [0.0, 30.0, -75.0])
def test_wall_columns_follow_the_azimuth_of_its_ends(sim_from, heading_deg) -> None:
    sim = sim_from(wall_world(3.0, -1.0, 2.0, 2.0))
    theta = math.radians(heading_deg)
    image = sim.snapshot(Pose2D(0, 0, theta)).image
    step = math.radians(PANO.deg_per_px)
    left_u = PANO.width / 2 - (math.atan2(2.0, 3.0) - theta) / step
    right_u = PANO.width / 2 - (math.atan2(-1.0, 3.0) - theta) / step
    first, last = dark_runs(image[int(PANO.horizon_row)].astype(int))
    assert first == pytest.approx(left_u, abs=1.0)
    assert last == pytest.approx(right_u, abs=1.0)


def test_bearing_to_a_known_landmark(sim_from) -> None:
    sim = sim_from(PLAIN + "landmarks: [{id: 7, position: [4, 3, 1.9]}]\n")
    pose = Pose2D(1.0, 1.0, 0.3)
    seen = sim.observe(pose)
    assert seen.ids.tolist() == [7]
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    world = np.array([3.0, 2.0, 1.9 - CAMERA_Z])
    body = np.array([c * world[0] + s * world[1], -s * world[0] + c * world[1], world[2]])
    np.testing.assert_allclose(seen.bearing_of(7), body / np.linalg.norm(body), atol=1e-12)


def test_bearing_noise_has_the_configured_spread(sim_from) -> None:
    text = PLAIN.replace("max_range: 1000", "max_range: 1000, noise_deg: 1.0")
    sim = sim_from(text + "landmarks: [{id: 1, position: [5, 0, 0.9]}]\n")
    sensor = sim.robot.cameras["landmarks"]
    errors = [math.degrees(math.acos(min(1.0, sensor.grab().bearings[0] @ [1.0, 0.0, 0.0]))) for _ in range(400)]
    # the angle off the true bearing of a 2D isotropic Gaussian of sigma 1 deg: Rayleigh, mean 1.25 deg
    assert np.mean(errors) == pytest.approx(1.0 * math.sqrt(math.pi / 2), rel=0.15)


def test_field_of_view_and_range_limit_what_the_sensor_reports(sim_from) -> None:
    text = PLAIN.replace("max_range: 1000", "max_range: 10, azimuth_fov_deg: 90, elevation_limits_deg: [-10, 20]")
    sim = sim_from(
        text
        + """landmarks:
  - {id: 1, position: [5, 1, 1]}      # ahead: seen
  - {id: 2, position: [-5, 0, 1]}     # behind: outside 90 deg
  - {id: 3, position: [20, 0, 1]}     # too far
  - {id: 4, position: [3, 0, 3]}      # 39 deg up: above the limit
  - {id: 5, position: [3, 2.9, 1]}    # 44 deg left: inside
"""
    )
    assert sim.observe(Pose2D(0, 0, 0)).ids.tolist() == [1, 5]


OCCLUSION = (
    PLAIN
    + """walls:
  - {points: [[3, -1], [3, 1]], height: 1.5, texture: {seed: 2, brightness: 10, contrast: 0}}
pillars:
  - {center: [0, 3], radius: 0.3, height: 2.0, texture: {seed: 3, brightness: 10, contrast: 0}}
landmarks:
  - {id: 1, position: [6, 0, 1.0], size: 0.6}    # behind the wall, below its top: hidden
  - {id: 2, position: [6, 0.2, 3.5], size: 0.6}  # behind the wall, seen above it
  - {id: 3, position: [0, 6, 1.0], size: 0.6}    # behind the pillar: hidden
  - {id: 4, position: [-6, 1.5, 2.0], size: 0.6}  # in the open
  - {id: 5, position: [3, 0.5, 1.2], size: 0.1}  # on the wall itself: seen
"""
)


def test_walls_and_pillars_hide_landmarks_in_3d(sim_from) -> None:
    sim = sim_from(OCCLUSION)
    assert sim.observe(Pose2D(0, 0, 0)).ids.tolist() == [2, 4, 5]
    # from the other side of the wall, landmark 1 is in the open
    assert 1 in sim.observe(Pose2D(8, 0, math.pi)).ids.tolist()


def test_landmark_discs_are_drawn_where_the_model_projects_them_and_hidden_like_the_sensor(sim_from) -> None:
    text = OCCLUSION.replace("brightness: 128", "brightness: 128, pixels_per_m: 5")
    pose = Pose2D(0, 0, 0)
    image = sim_from(text).snapshot(pose).image.astype(int)
    bare = sim_from(text[: text.index("landmarks:")]).snapshot(pose).image.astype(int)  # no landmarks
    drawn = np.abs(image - bare) > 40
    sim = sim_from(text)
    for lm in sim.world.landmarks:
        if lm.id == 5:
            continue
        uv, valid = PANO.bearing_to_pixel(np.array([[lm.x, lm.y, lm.z - CAMERA_Z]]))
        assert valid[0]
        u, v = np.round(uv[0]).astype(int)
        rows, cols = np.nonzero(drawn[max(0, v - 12) : v + 13, u - 12 : u + 13])
        if lm.id in (2, 4):
            centre = [cols.mean() + u - 12, rows.mean() + max(0, v - 12)]
            np.testing.assert_allclose(centre, uv[0], atol=0.75)
        else:
            assert rows.size == 0, lm.id


def test_a_box_pushed_against_a_wall_never_shows_through_it_from_the_other_side(sim_from) -> None:
    """A wall along y = 0 and a box south of it whose north face lies in the wall (x 1-3): seen from
    the north every column on the wall's face takes the wall, none the box face behind it (the two
    at one distance, the nearer changed with the rounding: stripes)."""
    sim = sim_from(PLAIN + "start: {x: 0, y: 2}\nwalls: [{points: [[-4, 0], [6, 0]], height: 2.5}]\n"
                   "boxes: [{center: [2.0, -0.5], size: [2.0, 1.0], height: 0.8}]\n")
    scene = sim.scene
    scene.ensure_textures()
    wall = int(np.flatnonzero(scene.seg_two_sided)[0])
    for viewer_x in (1.3, 2.0, 2.77):  # the angles to the face's span differ: the rounding with them
        origin = np.array([viewer_x, 1.7])
        tips = np.linspace(1.0 + 1e-3, 3.0 - 1e-3, 997)  # the hits along the box's face, in the wall
        angles = np.arctan2(0.0 - origin[1], tips - origin[0])
        nearest = scene.layers(origin, CAMERA_Z, angles, 2)[0]
        assert nearest.distance == pytest.approx(np.hypot(tips - origin[0], origin[1]), abs=1e-9)
        assert set(nearest.surface.tolist()) == {wall}
