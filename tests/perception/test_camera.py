"""Camera models: pixel <-> bearing round trips, axis conventions, YAML data, unwarping."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from perception.camera import (
    CatadioptricCamera,
    PanoramaCamera,
    PinholeCamera,
    StereoRig,
    camera_from_dict,
    unwarp,
)

# the OpenCV sample camera (tests/data/chessboard/left_intrinsics.yml): strong barrel distortion
SAMPLE = PinholeCamera(
    640, 480, 535.9157, 535.9157, 342.2832, 235.5708, (-0.26637, -0.038589, 0.0017832, -0.00028122, 0.23839)
)
PANO = PanoramaCamera()
DONUT = CatadioptricCamera()

pixels = st.tuples(st.floats(-0.49, 639.49), st.floats(-0.49, 479.49))


@settings(max_examples=200, deadline=None)
@given(pixels)
def test_pinhole_round_trip(uv):
    pix = np.array([uv])
    bearing = SAMPLE.pixel_to_bearing(pix)
    assert np.linalg.norm(bearing, axis=1) == pytest.approx(1.0)
    back, valid = SAMPLE.bearing_to_pixel(bearing)
    assert valid.all()
    assert np.abs(back - pix).max() < 1e-6


def test_pinhole_axes_follow_the_body_convention():
    cam = PinholeCamera(640, 480, 500.0, 500.0, 320.0, 240.0)
    b = cam.pixel_to_bearing(np.array([[320.0, 240.0], [0.0, 240.0], [320.0, 0.0]]))
    assert np.allclose(b[0], [1, 0, 0])  # principal point: straight ahead (x)
    assert b[1, 1] > 0.5 and abs(b[1, 2]) < 1e-12  # left image edge: +y (left)
    assert b[2, 2] > 0.4 and abs(b[2, 1]) < 1e-12  # top image edge: +z (up)
    _, valid = cam.bearing_to_pixel(np.array([[-1.0, 0, 0], [1.0, 5.0, 0.0]]))
    assert not valid.any()  # behind the camera; outside the image


def test_pinhole_rays_outside_the_view_do_not_fold_back_into_the_image():
    barrel = PinholeCamera(640, 480, 500.0, 500.0, 320.0, 240.0, (-0.3, 0.0, 0.0, 0.0))
    a = np.radians(55.0)  # tan 55 deg = 1.43: the polynomial maps it to radius 0.55, inside the image
    uv, valid = barrel.bearing_to_pixel(np.array([[np.cos(a), np.sin(a), 0.0], [1.0, 0.3, 0.0]]))
    assert _inside_image(uv[0]) and not valid[0]
    assert valid[1]


def _inside_image(uv: np.ndarray) -> bool:
    return bool(0 <= uv[0] < 640 and 0 <= uv[1] < 480)


@settings(max_examples=200, deadline=None)
@given(st.floats(-0.49, 719.49), st.floats(-0.49, 171.49))
def test_panorama_round_trip(u, v):
    pix = np.array([[u, v]])
    back, valid = PANO.bearing_to_pixel(PANO.pixel_to_bearing(pix))
    assert valid.all() and np.abs(back - pix).max() < 1e-9


def test_panorama_azimuth_is_left_positive_and_wraps_at_the_seam():
    b = PANO.pixel_to_bearing(np.array([[360.0, 60.0], [180.0, 60.0], [540.0, 60.0], [360.0, 0.0]]))
    assert np.allclose(b[0], [1, 0, 0]) and np.allclose(b[1], [0, 1, 0]) and np.allclose(b[2], [0, -1, 0])
    assert math.degrees(math.asin(b[3, 2])) == pytest.approx(30.0)  # row 0 is 30 deg up
    behind = np.array([[-1.0, 1e-9, 0.0], [-1.0, -1e-9, 0.0]])
    uv, valid = PANO.bearing_to_pixel(behind)
    assert valid.all()
    assert uv[0, 0] == pytest.approx(0.0, abs=1e-5) and uv[1, 0] == pytest.approx(0.0, abs=1e-5)
    below = PANO.pixel_to_bearing(np.array([[360.0, 171.0]]))
    assert math.degrees(math.asin(below[0, 2])) == pytest.approx(-55.5)
    _, valid = PANO.bearing_to_pixel(np.array([[0.0, 0.0, 1.0]]))  # straight up: not in view
    assert not valid.any()


@settings(max_examples=200, deadline=None)
@given(st.floats(-math.pi, math.pi), st.floats(math.radians(-55), math.radians(29)))
def test_catadioptric_round_trip(azimuth, elevation):
    ce = math.cos(elevation)
    b = np.array([[ce * math.cos(azimuth), ce * math.sin(azimuth), math.sin(elevation)]])
    uv, valid = DONUT.bearing_to_pixel(b)
    assert valid.all()
    assert np.abs(DONUT.pixel_to_bearing(uv) - b).max() < 1e-9


def test_catadioptric_geometry():
    b = DONUT.pixel_to_bearing(np.array([[DONUT.cx, DONUT.cy - 100.0], [DONUT.cx - 100.0, DONUT.cy]]))
    assert b[0, 1] == pytest.approx(0.0, abs=1e-12) and b[0, 0] > 0  # image up = ahead
    assert b[1, 0] == pytest.approx(0.0, abs=1e-12) and b[1, 1] > 0  # image left = left
    _, valid = DONUT.bearing_to_pixel(np.array([[0.0, 0.0, -1.0]]))  # straight down: inside r_inner
    assert not valid.any()


def test_unwarp_puts_each_donut_pixel_where_the_panorama_expects_it():
    maps = DONUT.unwarp_maps(PANO)
    assert maps[0].shape == (PANO.height, PANO.width) and maps[0].dtype == np.float32
    # paint a donut whose intensity encodes azimuth; unwarping must give columns of that azimuth
    vs, us = np.mgrid[0 : DONUT.height, 0 : DONUT.width]
    bearings = DONUT.pixel_to_bearing(np.column_stack((us.ravel(), vs.ravel())).astype(float))
    az = np.degrees(np.arctan2(bearings[:, 1], bearings[:, 0]))
    donut = ((az + 180.0) / 360.0 * 250.0).reshape(DONUT.height, DONUT.width).astype(np.float32)
    pano = unwarp(donut, maps)
    expected = (np.degrees(PANO.azimuth(np.arange(PANO.width))) + 180.0) / 360.0 * 250.0
    rows = slice(5, 160)
    interior = slice(20, 700)  # away from the +-180 deg discontinuity of the painted azimuth
    assert np.abs(pano[rows, interior] - expected[None, interior]).max() < 1.0


def test_stereo_rig():
    right = PinholeCamera(640, 480, 500.0, 500.0, 320.0, 240.0)
    rig = StereoRig(right, right, 0.12)
    assert np.allclose(rig.right_centre, [0, -0.12, 0])
    assert rig.depth_from_disparity(np.array([60.0, 0.0])) == pytest.approx([1.0, np.inf])
    with pytest.raises(ValueError):
        StereoRig(right, PinholeCamera(320, 240, 500.0, 500.0, 160.0, 120.0), 0.1)


@pytest.mark.parametrize("camera", [SAMPLE, PANO, DONUT, StereoRig(SAMPLE, SAMPLE, 0.1)])
def test_dict_round_trip(camera):
    assert camera_from_dict(camera.to_dict()) == camera


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"kind": "fisheye"}, "unknown camera kind"),
        ({"kind": "pinhole", "width": 640, "height": 480, "fx": 500.0}, "missing"),
        ({"kind": "panorama", "colour": True}, "unknown key"),
        ({"kind": "panorama", "width": 720.5}, "must be an integer"),
        ({"kind": "pinhole", "width": 64, "height": 48, "fx": -1, "fy": 1, "cx": 0, "cy": 0}, "positive"),
        ({"kind": "stereo", "left": {}}, "missing"),
        ([], "mapping"),
    ],
)
def test_bad_camera_data_is_a_clear_value_error(data, message):
    with pytest.raises(ValueError, match=message):
        camera_from_dict(data)
