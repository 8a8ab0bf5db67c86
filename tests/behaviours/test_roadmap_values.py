"""The values roadmap nodes hand each other: target images by name, frozen records."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from behaviours.roadmap.values import NavigationResult, ScanRecord, Sighting, TargetImages, TargetView
from behaviours.roadmap.vision import describe
from perception.geometry import Pose2D


def view(name: str) -> TargetView:
    image = np.zeros((4, 4), np.uint8)
    return TargetView(name, image, describe(image), source=f"{name}.png")


def test_target_images_keep_their_order_and_are_found_by_name():
    targets = TargetImages((view("window"), view("door")))
    assert targets.names == ("window", "door") and len(targets) == 2
    assert targets.get("door").source == "door.png"


def test_an_unknown_target_name_says_which_there_are():
    with pytest.raises(KeyError, match=r"no target image named 'desk' \(have: window, door\)"):
        TargetImages((view("window"), view("door"))).get("desk")
    with pytest.raises(KeyError, match=r"\(have: none\)"):
        TargetImages().get("desk")


def test_a_target_image_file_has_no_camera_and_no_time():
    target = view("door")
    assert target.camera is None and math.isnan(target.stamp)
    assert target != view("door")  # images are compared by identity, never element by element


def test_records_are_frozen_with_defaults_for_what_may_not_have_happened():
    scan = ScanRecord(1, 0.5, 1.0, (0.0, math.pi))
    assert scan.found == ""
    result = NavigationResult("door", False)
    assert (result.localised_at, result.visited, result.random_moves, result.rescans, result.reason) == (
        "", (), 0, 0, "")
    sighting = Sighting("door", Pose2D(), 0.1, -0.2, 40, 60)
    with pytest.raises(dataclasses.FrozenInstanceError):
        sighting.inliers = 41
