"""A mission without ``cameras:`` grabs the cameras its nodes read, as the data flow says."""

from __future__ import annotations

import textwrap

import pytest

from missions.camera_use import cameras_read
from missions.loader import load_mission

DRIVE = "tree:\n  Sequence:\n    children:\n      - Drive: {distance: 1.0}\n      - Stop\n"


@pytest.fixture
def mission(tmp_path):
    def load(text: str):
        path = tmp_path / "m.yaml"
        path.write_text(textwrap.dedent(text))
        return load_mission(path)
    return load


def test_a_mission_that_reads_no_frames_grabs_no_camera(mission):
    assert mission("mission: m\n" + DRIVE).cameras == ()


def test_named_cameras_are_grabbed_in_the_order_nodes_name_them(mission):
    loaded = mission("mission: m\nsense:\n  - Perceive: {camera: front}\n"
                     "  - Perceive: {camera: panorama, observation: '{/perception/pano}'}\n"
                     "  - Perceive: {camera: front, observation: '{/perception/again}'}\n" + DRIVE)
    assert loaded.cameras == ("front", "panorama")


def test_a_reader_that_names_no_camera_means_every_camera(mission):
    assert mission("mission: m\nsense:\n  - Perceive\n" + DRIVE).cameras is None  # "the first camera"
    guard = ("mission: m\ntree:\n  Guard: {key: /perception/frame.stamp, op: '>', value: 0,"
             " child: {Drive: {distance: 1.0}}}\n")
    assert mission(guard).cameras is None  # reads a frame key without naming a camera


def test_the_missions_own_list_wins(mission):
    assert mission("mission: m\ncameras: [omni]\nsense:\n  - Perceive: {camera: front}\n" + DRIVE).cameras == ("omni",)


@pytest.mark.parametrize("name", ["explore", "follow_route", "goto_target", "learn_targets", "showcase", "square",
                                  "teach_and_repeat", "teach_route"])
def test_every_shipped_mission_reads_the_cameras_it_lists(name):
    mission = load_mission(name)  # every node that reads frames names its camera: the inference is exact
    read = cameras_read(mission)
    assert read is not None and set(read) == set(mission.cameras)
