"""Target images in and out: loading a folder and a roadmap, recording a homed target, all found."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from py_trees.common import Status

from behaviours.roadmap.display import roadmap_section
from behaviours.roadmap.targets import (
    AllTargetsFound,
    LoadRoadmap,
    LoadTargetImages,
    RecordTarget,
    relative_images,
)
from behaviours.roadmap.values import HomingResult, TargetImages, TargetView
from behaviours.roadmap.vision import describe
from behaviours.telemetry import report_sections
from behaviours.testing import BehaviourHarness
from maps.roadmap import EdgeMotion, Roadmap
from maps.room import RoomEstimate
from perception.geometry import Pose2D


def textured(seed: int) -> np.ndarray:
    """A grey image with blobs SIFT finds."""
    rng = np.random.default_rng(seed)
    image = np.full((120, 160), 128, np.uint8)
    for _ in range(40):
        centre = tuple(int(v) for v in rng.integers([0, 0], [160, 120]))
        cv2.circle(image, centre, int(rng.integers(3, 12)), int(rng.integers(0, 255)), -1)
    return image


@pytest.fixture
def folder(tmp_path):
    images = tmp_path / "targets"
    images.mkdir()
    cv2.imwrite(str(images / "door.png"), textured(1))
    cv2.imwrite(str(images / "window.jpg"), textured(2))
    (images / "notes.txt").write_text("not an image")
    return images


def test_loads_a_folder_of_images_named_by_file(folder):
    harness = BehaviourHarness(LoadTargetImages(folder=str(folder)))
    assert harness.tick() == Status.SUCCESS
    targets = harness.read("/map/target_images")
    assert targets.names == ("door", "window")
    door = targets.get("door")
    assert door.image.shape == (120, 160) and len(door.features) > 20 and door.features.kind == "sift"
    assert door.source == str((folder / "door.png").resolve()) and door.camera is None


@pytest.mark.parametrize(("setup", "message"), [
    (lambda p: None, "not a folder of target images"),
    (lambda p: p.mkdir(), "no image files"),
    (lambda p: (p.mkdir(), (p / "a.png").write_bytes(b"not a png")), "not an image OpenCV can read"),
    (lambda p: (p.mkdir(), cv2.imwrite(str(p / "a.png"), textured(1)), cv2.imwrite(str(p / "a.jpg"), textured(2))),
     "two images named 'a'"),
])
def test_a_bad_folder_fails_saying_why(tmp_path, setup, message):
    path = tmp_path / "targets"
    setup(path)
    harness = BehaviourHarness(LoadTargetImages(folder=str(path)))
    assert harness.tick() == Status.FAILURE
    assert message in harness.behaviour.feedback_message


def roadmap_with(images: dict[str, str]) -> Roadmap:
    cov = np.diag([1e-3, 1e-3, 1e-3])
    roadmap = Roadmap()
    for k, (name, image) in enumerate(images.items()):
        roadmap = roadmap.with_target(name, Pose2D(float(k), 0.5 * k, 0.1 * k), image)
    names = list(images)
    return roadmap.with_edge(names[0], names[1], EdgeMotion(0.0, 1.1, 0.1, cov)) if len(names) > 1 else roadmap


def test_loads_a_roadmap_and_its_images_relative_to_the_file(folder, tmp_path):
    path = tmp_path / "maps" / "lab.roadmap"
    path.parent.mkdir()
    roadmap = roadmap_with({"door": str(folder / "door.png"), "window": str(folder / "window.jpg")})
    relative_images(roadmap, path).save(path)
    assert relative_images(roadmap, path).target("door").image == "../targets/door.png"
    harness = BehaviourHarness(LoadRoadmap(file=str(path)))
    assert harness.tick() == Status.SUCCESS
    loaded, targets = harness.read("/map/roadmap"), harness.read("/map/target_images")
    assert loaded.names == ("door", "window") and len(loaded.edges) == 1
    assert targets.names == ("door", "window") and len(targets.get("window").features) > 20


def test_a_damaged_roadmap_or_a_missing_image_fails_saying_why(folder, tmp_path):
    path = tmp_path / "lab.roadmap"
    path.write_bytes(b"garbage")
    harness = BehaviourHarness(LoadRoadmap(file=str(path)))
    assert harness.tick() == Status.FAILURE and str(path) in harness.behaviour.feedback_message
    roadmap_with({"door": str(folder / "gone.png")}).save(path)
    harness = BehaviourHarness(LoadRoadmap(file=str(path)))
    assert harness.tick() == Status.FAILURE and "no such file" in harness.behaviour.feedback_message


def test_records_the_homed_target_relative_to_the_reference():
    reference = Pose2D(1.0, 2.0, math.pi / 2)  # where the reference pose is in the odometry frame
    room = RoomEstimate(np.array([[-1.0, -1.0], [5.0, -1.0], [5.0, 5.0], [-1.0, 5.0]]), np.zeros(2), reference)
    homed = HomingResult("door", Pose2D(0.0, 4.0, math.pi), 0.01, 2, 100, 12.0)  # odometry frame
    targets = TargetImages((TargetView("door", np.zeros((4, 4), np.uint8), describe(np.zeros((4, 4), np.uint8)),
                                       source="/data/door.png"),))
    harness = BehaviourHarness(RecordTarget(), blackboard={"/map/homing": homed, "/map/room": room,
                                                          "/map/target_images": targets})
    assert harness.tick() == Status.SUCCESS
    door = harness.read("/map/roadmap").target("door")
    # by hand: (0, 4) - (1, 2) = (-1, 2) in odometry, turned by -90 deg into the reference frame: (2, 1)
    assert (door.pose.x, door.pose.y, door.pose.theta) == pytest.approx((2.0, 1.0, math.pi / 2))
    assert door.image == "/data/door.png"
    harness.write("/map/homing", HomingResult("window", Pose2D(1.0, 2.0, math.pi / 2), 0.0, 2, 80, 20.0))
    assert harness.tick() == Status.SUCCESS
    assert harness.read("/map/roadmap").names == ("door", "window")  # added to what was there
    assert report_sections(harness.behaviour)["roadmap"]["targets"]["window"]["x"] == pytest.approx(0.0)


def test_record_reports_and_draws_the_roadmap_on_the_blackboard_once_per_roadmap():
    harness = BehaviourHarness(RecordTarget())
    assert report_sections(harness.behaviour) == {} and list(harness.behaviour.drawings()) == []  # none yet
    roadmap = roadmap_with({"door": "door.png", "window": ""})
    harness.write("/map/roadmap", roadmap)
    assert report_sections(harness.behaviour) == {"roadmap": roadmap_section(roadmap)}
    drawn = [d.entity for d in harness.behaviour.drawings()]
    assert drawn == ["roadmap/targets", "roadmap/graph"]
    assert list(harness.behaviour.drawings()) == []  # the same roadmap: not again


def test_record_fails_without_a_homing_result():
    harness = BehaviourHarness(RecordTarget())
    assert harness.tick() == Status.FAILURE and harness.behaviour.feedback_message == "no homing result"


def test_all_targets_found_names_the_missing_ones(folder):
    loader = BehaviourHarness(LoadTargetImages(folder=str(folder)))
    loader.tick()
    targets = loader.read("/map/target_images")
    harness = BehaviourHarness(AllTargetsFound(), blackboard={"/map/target_images": targets})
    assert harness.tick() == Status.FAILURE and harness.behaviour.feedback_message == "missing: door, window"
    harness.write("/map/roadmap", roadmap_with({"door": ""}))
    assert harness.tick() == Status.FAILURE and harness.behaviour.feedback_message == "missing: window"
    harness.write("/map/roadmap", roadmap_with({"door": "", "window": ""}))
    assert harness.tick() == Status.SUCCESS
