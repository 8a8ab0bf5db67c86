"""The landmark map and the keyframe policy: fusion, culling, duplicates, ids, by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.slam.keyframes import Keyframe, KeyframePolicy, view_overlap, wants_keyframe
from maps.slam.landmarks import LandmarkMap, hamming

DESCRIPTORS = np.zeros((3, 32), dtype=np.uint8)


def three() -> LandmarkMap:
    landmarks = LandmarkMap()
    covariances = np.broadcast_to(np.eye(3) * 0.04, (3, 3, 3)).copy()  # 0.2 m on each axis
    landmarks.add(np.array([[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.05, 0.0, 0.0]]), covariances, DESCRIPTORS, anchor=0)
    return landmarks


def test_two_equally_sure_sightings_average_and_halve_the_variance():
    landmarks = three()
    landmarks.fuse(np.array([0]), np.array([[1.2, 0.0, 0.0]]), np.eye(3)[None] * 0.04, floor=0.0)
    assert landmarks.positions[0] == pytest.approx([1.1, 0.0, 0.0])
    assert np.diag(landmarks.covariances[0]) == pytest.approx([0.02, 0.02, 0.02])
    landmarks.fuse(np.array([0]), np.array([[1.1, 0.0, 0.0]]), np.eye(3)[None] * 1e-6, floor=0.01)
    assert np.diag(landmarks.covariances[0]) == pytest.approx([0.01, 0.01, 0.01], abs=1e-4)  # kept at the floor


def test_landmarks_seen_in_view_but_rarely_found_are_culled_and_ids_stay():
    landmarks = three()
    landmarks.visible[:] = (10, 10, 3)
    landmarks.found[:] = (2, 5, 0)
    assert landmarks.cull(min_visible=6, min_found_ratio=0.25) == 1  # 2 of 10: gone; 3 seen: too early to say
    assert landmarks.ids.tolist() == [1, 2] and landmarks.rows_of(np.array([0, 1, 2, 7])).tolist() == [-1, 0, 1, -1]


def test_duplicates_close_in_space_and_descriptor_merge_into_the_older():
    landmarks = three()
    different = DESCRIPTORS.copy()
    different[2] = 255  # 256 bits away
    assert landmarks.merge_duplicates(0.1, 32, floor=0.0) == 1
    assert landmarks.ids.tolist() == [0, 1] and landmarks.positions[1, 0] == pytest.approx(2.025)
    other = three()
    other.descriptors = different
    assert other.merge_duplicates(0.1, 32, floor=0.0) == 0
    assert hamming(DESCRIPTORS[:1], different[2:]).tolist() == [256]


def test_keyframes_when_the_map_covers_the_view_badly_and_not_too_often():
    policy = KeyframePolicy(min_found=40, found_ratio=0.5, min_interval=0.3)
    assert wants_keyframe(found=30, usable=50, since_last=1.0, policy=policy)  # too few found
    assert wants_keyframe(found=60, usable=150, since_last=1.0, policy=policy)  # under half of the usable
    assert not wants_keyframe(found=60, usable=100, since_last=1.0, policy=policy)
    assert not wants_keyframe(found=0, usable=100, since_last=0.2, policy=policy)


def test_two_keyframes_overlap_when_close_and_looking_alike():
    def keyframe(x: float, heading: float, pan: float) -> Keyframe:
        return Keyframe(0, 0.0, np.array([x, 0.0, heading]), np.zeros((3, 3)), pan, 0.0, np.zeros((0, 3)),
                        np.zeros((0, 3, 3)), DESCRIPTORS[:0], np.zeros(0, dtype=np.int64))

    a = keyframe(0.0, 0.0, 0.5)
    assert view_overlap(a, keyframe(1.0, 0.5, 0.0), max_distance=2.0, max_turn=math.radians(60))  # same direction
    assert not view_overlap(a, keyframe(1.0, 0.5, math.pi), max_distance=2.0, max_turn=math.radians(60))
    assert not view_overlap(a, keyframe(3.0, 0.5, 0.0), max_distance=2.0, max_turn=math.radians(60))
