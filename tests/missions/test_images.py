"""Recorded images: JPEG bytes, new frames only, at most the rate asked per camera."""

from __future__ import annotations

import cv2
import numpy as np

from missions.images import ImageRate, jpeg
from perception.frame import Frame, LandmarkBearings


def _frame(stamp: float, name: str = "front") -> Frame:
    return Frame(np.zeros((4, 4, 3), np.uint8), camera=None, stamp=stamp, camera_name=name)


def test_jpeg_keeps_the_colours_in_rgb_order():
    image = np.zeros((16, 16, 3), np.uint8)
    image[:, :, 0] = 250  # pure red in RGB
    data = jpeg(image)
    assert data[:2] == b"\xff\xd8"  # a JPEG's start-of-image marker
    decoded = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)  # BGR
    assert decoded[8, 8, 2] > 200 and decoded[8, 8, 0] < 40


def test_jpeg_takes_grey_and_rgba_images():
    assert jpeg(np.full((8, 8), 128, np.uint8))[:2] == b"\xff\xd8"
    assert jpeg(np.zeros((8, 8, 4), np.uint8))[:2] == b"\xff\xd8"


def test_a_camera_is_logged_at_most_at_the_rate_and_never_the_same_frame_twice():
    rate = ImageRate(2.0)  # one image per 0.5 s
    logged = []
    for tick in range(21):  # 10 Hz for 2 s, a new frame every tick
        now = tick * 0.1
        logged += [(now, name) for name, _ in rate.due({"front": _frame(now)}, now)]
    assert [round(t, 1) for t, _ in logged] == [0.0, 0.5, 1.0, 1.5, 2.0]
    assert list(rate.due({"front": _frame(2.0)}, 5.0)) == []  # the same frame (stamp) again: not logged


def test_rate_zero_logs_every_new_frame_and_skips_bearings_sensors():
    rate = ImageRate(0)
    sensor = LandmarkBearings(np.zeros(0, np.int64), np.zeros((0, 3)), stamp=0.0)
    counts = [len(list(rate.due({"front": _frame(t * 0.1), "landmarks": sensor}, t * 0.1))) for t in range(5)]
    assert counts == [1, 1, 1, 1, 1]
