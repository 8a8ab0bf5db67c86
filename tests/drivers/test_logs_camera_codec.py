"""Images, camera models and the ideal bearings sensor to ROS 2 messages and back."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from drivers.logs import camera_codec as cc
from drivers.logs import messages as msg
from perception.camera import CatadioptricCamera, PanoramaCamera, PinholeCamera, StereoRig
from perception.frame import LandmarkBearings
from tests.drivers.test_logs_codec import through_cdr

GREY = (np.arange(48 * 64, dtype=np.uint32).reshape(48, 64) * 7 % 251).astype(np.uint8)
COLOUR = np.dstack([GREY, 255 - GREY, GREY // 2])


def test_image_formats_parse():
    assert cc.parse_image_format("jpeg") == cc.ImageFormat("jpeg", 90)
    assert cc.parse_image_format("JPEG:75") == cc.ImageFormat("jpeg", 75)
    assert cc.parse_image_format("png") == cc.ImageFormat("png")
    assert str(cc.ImageFormat("jpeg", 75)) == "jpeg:75"
    for bad in ("jpeg:0", "jpeg:101", "png:3", "tiff", "jpeg:x"):
        with pytest.raises(ValueError, match="jpeg, jpeg:Q"):
            cc.parse_image_format(bad)


@pytest.mark.parametrize("image", [GREY, COLOUR], ids=["grey", "colour"])
def test_png_gives_the_very_pixels_back(image):
    message = through_cdr(msg.COMPRESSED_IMAGE, cc.compressed_image_message(image, 1.5, "cam", cc.ImageFormat("png")))
    assert message["format"] == "png" and message["header"]["frame_id"] == "cam"
    assert np.array_equal(cc.image_from_compressed(message), image)


def test_jpeg_is_close_and_smaller():
    image = cv2.GaussianBlur(GREY, (5, 5), 2.0)  # a natural-ish image: JPEG's case
    message = cc.compressed_image_message(image, 0.0, "cam", cc.ImageFormat("jpeg", 90))
    back = cc.image_from_compressed(message)
    assert back.shape == image.shape and np.abs(back.astype(int) - image).mean() < 2.0
    assert len(message["data"]) < image.nbytes


def test_an_image_we_cannot_write_or_read_is_a_value_error_naming_it():
    with pytest.raises(ValueError, match="8-bit"):
        cc.compressed_image_message(GREY.astype(np.float32), 0.0, "cam", cc.ImageFormat())
    with pytest.raises(ValueError, match="'theora'"):
        cc.image_from_compressed({"format": "theora", "data": b"\x00"})
    with pytest.raises(ValueError, match="does not decode"):
        cc.image_from_compressed({"format": "jpeg", "data": b"not a jpeg at all"})
    with pytest.raises(ValueError, match="'bayer_rggb8' is not one we read"):
        cc.image_from_raw({"encoding": "bayer_rggb8", "height": 2, "width": 2, "step": 2, "data": b"\x00" * 4})
    with pytest.raises(ValueError, match="needs 2 rows"):
        cc.image_from_raw({"encoding": "mono8", "height": 2, "width": 3, "step": 3, "data": b"\x00" * 4})


def test_the_declared_size_is_read_from_the_header_by_hand():
    # a JPEG: SOI, an APP0 segment of length 4 (2 bytes of payload), a fill byte, then SOF2 (progressive):
    # length 17, precision 8, height 0x0102 = 258, width 0x0304 = 772
    jpeg = b"\xff\xd8" + b"\xff\xe0\x00\x04ab" + b"\xff" + b"\xff\xc2\x00\x11\x08\x01\x02\x03\x04" + b"\x00" * 12
    assert cc.compressed_image_size(jpeg) == (772, 258)
    # DHT (0xC4) is not a frame header: its bytes are skipped by its length
    assert cc.compressed_image_size(b"\xff\xd8\xff\xc4\x00\x03x" + jpeg[2:]) == (772, 258)
    png = b"\x89PNG\r\n\x1a\n" + b"\x00\x00\x00\x0dIHDR" + (640).to_bytes(4, "big") + (480).to_bytes(4, "big")
    assert cc.compressed_image_size(png) == (640, 480)
    assert cc.compressed_image_size(b"not an image") is None
    ok, data = cv2.imencode(".jpg", COLOUR)
    assert ok and cc.compressed_image_size(data.tobytes()) == (64, 48)  # OpenCV's own JPEG agrees


@pytest.mark.parametrize("ext", [".jpg", ".png"])
def test_a_small_message_declaring_a_huge_image_is_refused_before_decoding(ext):
    ok, data = cv2.imencode(ext, GREY)
    raw = bytearray(data.tobytes())
    if ext == ".png":
        raw[16:24] = (30_000).to_bytes(4, "big") * 2
    else:
        at = next(i for i in range(2, len(raw) - 1) if raw[i] == 0xFF and raw[i + 1] in (0xC0, 0xC2))
        raw[at + 5:at + 9] = (30_000).to_bytes(2, "big") * 2
    with pytest.raises(ValueError, match="declares 30000x30000 pixels"):
        cc.image_from_compressed({"format": ext[1:], "data": bytes(raw)})


def test_raw_images_in_every_eight_bit_encoding_come_back_as_grey_or_bgr():
    padded = np.zeros((48, 70), np.uint8)  # rows padded to a step of 70 bytes
    padded[:, :64] = GREY
    assert np.array_equal(cc.image_from_raw({"encoding": "mono8", "height": 48, "width": 64, "step": 70,
                                             "data": padded.tobytes()}), GREY)
    rgb = COLOUR[:, :, ::-1]
    for encoding, pixels in (("bgr8", COLOUR), ("rgb8", rgb), ("rgba8", np.dstack([rgb, GREY]))):
        message = {"encoding": encoding, "height": 48, "width": 64, "step": 64 * pixels.shape[2],
                   "data": np.ascontiguousarray(pixels).tobytes()}
        assert np.array_equal(cc.image_from_raw(message), COLOUR), encoding


PINHOLE = PinholeCamera(640, 480, 500.0, 510.0, 320.5, 240.5, (-0.1, 0.02, 0.001, -0.002))
MODELS = [PINHOLE, PinholeCamera(640, 480, 500.0, 500.0, 320.0, 240.0),
          PinholeCamera(640, 480, 500.0, 500.0, 320.0, 240.0, (0.1, 0.01, 0.0, 0.0, 0.001, 0.0, 0.0, 0.002)),
          PanoramaCamera(720, 172, 0.5, 60.0), CatadioptricCamera(azimuth_offset=0.1)]


@pytest.mark.parametrize("model", MODELS, ids=lambda m: f"{m.kind}{len(getattr(m, 'dist', ()))}")
def test_camera_models_come_back_exactly(model):
    (info,) = cc.camera_info_messages(model, 2.0, "cam")
    assert cc.camera_from_info(through_cdr(msg.CAMERA_INFO, info)) == model


def test_a_pinhole_is_a_standard_camera_info():
    (info,) = cc.camera_info_messages(PINHOLE, 0.0, "cam")
    assert info["distortion_model"] == "plumb_bob" and info["d"] == [-0.1, 0.02, 0.001, -0.002]
    assert info["k"] == [500.0, 0.0, 320.5, 0.0, 510.0, 240.5, 0.0, 0.0, 1.0]
    assert info["p"][:4] == [500.0, 0.0, 320.5, 0.0]


def test_a_panorama_is_uncalibrated_for_ros_tools_and_exact_for_us():
    (info,) = cc.camera_info_messages(PanoramaCamera(720, 172, 0.5, 60.0), 0.0, "panorama")
    assert info["distortion_model"] == "bearings_panorama" and info["d"] == [0.5, 60.0] and info["k"] == [0.0] * 9


def test_a_stereo_pair_is_two_infos_with_the_baseline_in_the_right_projection():
    rig = StereoRig(PINHOLE, PINHOLE, baseline=0.12)
    left, right = cc.camera_info_messages(rig, 0.0, "stereo")
    assert right["p"][3] == pytest.approx(-500.0 * 0.12) and left["p"][3] == 0.0
    back = cc.camera_from_info(left, right)
    assert isinstance(back, StereoRig) and back.left == back.right == PINHOLE
    assert back.baseline == pytest.approx(0.12, rel=1e-15)


def test_camera_infos_we_cannot_read_say_why():
    (info,) = cc.camera_info_messages(PINHOLE, 0.0, "cam")
    with pytest.raises(ValueError, match="'equidistant' is not one we read"):
        cc.camera_from_info({**info, "distortion_model": "equidistant"})
    with pytest.raises(ValueError, match="not calibrated"):
        cc.camera_from_info({**info, "k": [0.0] * 9})
    with pytest.raises(ValueError, match="3 distortion coefficients"):
        cc.camera_from_info({**info, "d": [0.1, 0.2, 0.3]})
    padded = cc.camera_from_info({**info, "d": [-0.1, 0.02, 0.001, -0.002, 0.0, 0.0]})  # padded with zeros
    assert padded.dist == (-0.1, 0.02, 0.001, -0.002, 0.0)


def test_landmark_bearings_are_a_point_cloud_with_ids():
    bearings = np.array([[1.0, 0.0, 0.0], [0.0, 0.6, 0.8], [0.0, 0.0, -1.0]])
    seen = LandmarkBearings(np.array([3, 7, 42]), bearings, 1.5, "landmarks")
    message = through_cdr(msg.POINT_CLOUD, cc.bearings_message(seen))
    assert message["width"] == 3 and [f["name"] for f in message["fields"]] == ["x", "y", "z", "id"]
    back = cc.bearings_from_cloud(message, 1.5, "landmarks")
    assert np.array_equal(back.ids, seen.ids) and np.array_equal(back.bearings, bearings)
    empty = cc.bearings_from_cloud(cc.bearings_message(LandmarkBearings(np.zeros(0, int), np.zeros((0, 3)), 0.0)),
                                   0.0, "landmarks")
    assert len(empty) == 0 and empty.bearings.shape == (0, 3)


def test_a_bearings_cloud_of_float32_points_in_another_order_reads_sorted_by_id():
    points = np.zeros(2, dtype=[("id", "<u4"), ("x", "<f4"), ("y", "<f4"), ("z", "<f4")])
    points["id"], points["x"], points["z"] = [9, 2], [1.0, 0.0], [0.0, 1.0]
    fields = [{"name": "id", "offset": 0, "datatype": 6, "count": 1}] + [
        {"name": n, "offset": 4 + 4 * i, "datatype": 7, "count": 1} for i, n in enumerate("xyz")]
    message = {"fields": fields, "point_step": 16, "width": 2, "height": 1, "data": points.tobytes()}
    back = cc.bearings_from_cloud(message, 0.0, "landmarks")
    assert back.ids.tolist() == [2, 9] and back.bearings[0].tolist() == [0.0, 0.0, 1.0]
    with pytest.raises(ValueError, match="missing: id"):
        cc.bearings_from_cloud({**message, "fields": fields[1:]}, 0.0, "landmarks")
    with pytest.raises(ValueError, match="holds 16 bytes"):
        cc.bearings_from_cloud({**message, "data": points.tobytes()[:16]}, 0.0, "landmarks")
    assert not math.isnan(back.stamp)
