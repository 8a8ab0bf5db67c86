"""Perceive in isolation: a frame on the blackboard becomes an observation of bearings."""

from __future__ import annotations

import numpy as np
from py_trees.common import Status

from behaviours.perceive import Perceive
from behaviours.testing import BehaviourHarness
from perception.camera import PanoramaCamera
from perception.frame import Frame, LandmarkBearings


def textured_frame(stamp: float, seed: int = 0) -> Frame:
    import cv2

    rng = np.random.default_rng(seed)
    small = rng.integers(0, 256, size=(43, 180), dtype=np.uint8)
    image = cv2.resize(small, (720, 172), interpolation=cv2.INTER_NEAREST)
    return Frame(image=image, camera=PanoramaCamera(), stamp=stamp, camera_name="panorama")


def test_perceive_publishes_unit_bearings_consistent_with_the_camera():
    frame = textured_frame(1.0)
    harness = BehaviourHarness(Perceive(max_features=300), blackboard={"/perception/frames": {"panorama": frame}})
    assert harness.tick() == Status.SUCCESS
    observation = harness.read("/perception/observation")
    assert 100 <= observation.count <= 300
    assert np.allclose(np.linalg.norm(observation.bearings, axis=1), 1.0)
    uv, valid = frame.camera.bearing_to_pixel(observation.bearings)
    assert valid.all() and np.allclose(uv, observation.features.keypoints_uv, atol=1e-6)
    assert (observation.stamp, observation.camera_name) == (1.0, "panorama")


def test_perceive_skips_a_frame_it_has_seen_and_waits_without_frames():
    harness = BehaviourHarness(Perceive())
    assert harness.tick() == Status.SUCCESS
    assert harness.read("/perception/observation") is None
    harness.write("/perception/frames", {"panorama": textured_frame(1.0)})
    harness.tick()
    first = harness.read("/perception/observation")
    harness.tick()
    assert harness.read("/perception/observation") is first
    harness.write("/perception/frames", {"panorama": textured_frame(2.0, seed=1)})
    harness.tick()
    assert harness.read("/perception/observation").stamp == 2.0


def test_perceive_by_camera_name():
    frames = {"left": textured_frame(3.0), "right": textured_frame(4.0, seed=2)}
    harness = BehaviourHarness(Perceive(camera="right"), blackboard={"/perception/frames": frames})
    harness.tick()
    assert harness.read("/perception/observation").stamp == 4.0


def test_two_perceive_nodes_on_two_cameras_write_two_keys():
    frames = {"left": textured_frame(3.0), "right": textured_frame(4.0, seed=2)}
    left = BehaviourHarness(Perceive(camera="left", observation="{/perception/left}"),
                            blackboard={"/perception/frames": frames})
    left.tick()
    assert left.read("/perception/left").stamp == 3.0 and left.read("/perception/observation") is None
    right = BehaviourHarness(Perceive(camera="right", observation="{/perception/right}"))
    right.write("/perception/frames", frames)
    right.tick()
    assert right.read("/perception/right").stamp == 4.0
    assert right.read("/perception/observation") is None


def test_perceive_passes_identified_bearings_through():
    sensed = LandmarkBearings(ids=np.array([3, 7]), bearings=np.array([[1.0, 0, 0], [0, 1.0, 0]]), stamp=5.0,
                              camera_name="landmarks")
    harness = BehaviourHarness(Perceive(camera="landmarks"), blackboard={"/perception/frames": {"landmarks": sensed}})
    harness.tick()
    observation = harness.read("/perception/observation")
    assert observation.count == 2 and observation.features is None
    assert observation.ids.tolist() == [3, 7] and observation.stamp == 5.0
