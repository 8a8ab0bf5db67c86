"""The topic map: the names --record writes by default, cameras found under /cameras/, a map file's
entries over them, models from files or inline, located errors."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from drivers.logs import messages as msg
from drivers.logs import topics
from drivers.logs.topics import CameraSource, load_topic_map, resolve_topics
from maps.store import InputError
from perception.camera import PanoramaCamera, PinholeCamera

RECORDED = {"/odom": msg.ODOMETRY, "/cameras/panorama/image/compressed": msg.COMPRESSED_IMAGE,
            "/cameras/panorama/camera_info": msg.CAMERA_INFO, "/cameras/stereo/image/compressed": msg.COMPRESSED_IMAGE,
            "/cameras/stereo/camera_info": msg.CAMERA_INFO, "/cameras/stereo/right/image/compressed":
            msg.COMPRESSED_IMAGE, "/cameras/stereo/right/camera_info": msg.CAMERA_INFO,
            "/cameras/landmarks/bearings": msg.POINT_CLOUD, "/cameras/odd/camera_info": msg.CAMERA_INFO}


def test_a_recorded_log_needs_no_map():
    resolved = resolve_topics(RECORDED)
    assert resolved.odometry == "/odom" and resolved.ptu == "/ptu/joint_states" and resolved.rebase_odometry
    assert resolved.cameras == {
        "landmarks": CameraSource("landmarks", "/cameras/landmarks/bearings"),
        "panorama": CameraSource("panorama", "/cameras/panorama/image/compressed", "/cameras/panorama/camera_info"),
        "stereo": CameraSource("stereo", "/cameras/stereo/image/compressed", "/cameras/stereo/camera_info",
                               "/cameras/stereo/right/image/compressed", "/cameras/stereo/right/camera_info")}
    assert "/cameras/panorama/image/compressed" in resolved.wanted() and "/odom" in resolved.wanted()


def test_camera_names_become_ros_name_tokens():
    assert topics.camera_topics("front-left 2", "compressed")[0] == "/cameras/front_left_2/image/compressed"
    assert topics.topic_name("3d") == "_3d" and topics.topic_name("") == "camera"


def test_a_map_points_the_roles_at_other_topics(tmp_path):
    (tmp_path / "cam.yaml").write_text("kind: pinhole\nwidth: 640\nheight: 480\nfx: 500\nfy: 500\ncx: 320\n"
                                       "cy: 240\ndist: []\n")
    path = tmp_path / "map.yaml"
    path.write_text("odometry: /wheel/odom\nptu: /joint_states\nptu_joints: [head_pan, head_tilt]\n"
                    "cameras:\n  front: {image: /camera/image_raw, info: /camera/camera_info, model: cam.yaml}\n"
                    "  panorama: {image: /pano/compressed, model: {kind: panorama}}\n"
                    "ranges: [/sonar/a, /sonar/b]\nodometry_origin: log\n")
    resolved = resolve_topics({"/wheel/odom": msg.ODOMETRY}, load_topic_map(path), map_path=path)
    assert resolved.odometry == "/wheel/odom" and resolved.ptu_joints == ("head_pan", "head_tilt")
    assert resolved.cameras["front"].model == PinholeCamera(640, 480, 500.0, 500.0, 320.0, 240.0)
    assert resolved.cameras["panorama"].model == PanoramaCamera()
    assert resolved.ranges == ("/sonar/a", "/sonar/b") and resolved.bumpers == ("/bumpers",)
    assert not resolved.rebase_odometry


def test_a_bad_map_is_located(tmp_path):
    path = tmp_path / "map.yaml"
    path.write_text("odometry: /odom\ncamera:\n  front: {image: /x}\n")
    with pytest.raises(InputError, match=r"map\.yaml:2:1: .*camera.*did you mean 'cameras'"):
        load_topic_map(path)
    path.write_text("cameras:\n  front: {image: /x, model: {kind: fisheye}}\n")
    with pytest.raises(InputError, match=r"map\.yaml.*cameras\.front\.model: not a camera model: unknown camera kind"):
        resolve_topics({}, load_topic_map(path), map_path=path)
    path.write_text("- /odom\n")
    with pytest.raises(InputError, match="a topic map is a mapping"):
        load_topic_map(path)


def test_the_topic_map_of_the_documentation_loads(tmp_path):
    page = (Path(__file__).resolve().parents[2] / "docs" / "recorded-data.md").read_text()
    block = page[page.index("## Replaying other logs"):]
    (tmp_path / "map.yaml").write_text(re.search(r"```yaml\n(.*?)```", block, re.S).group(1))
    (tmp_path / "panorama.yaml").write_text("kind: panorama\n")
    resolved = resolve_topics({}, load_topic_map(tmp_path / "map.yaml"), map_path=tmp_path / "map.yaml")
    assert resolved.cameras["panorama"].model == PanoramaCamera()
    assert resolved.cameras["stereo"].right == "/stereo/right/image_raw" and resolved.odometry == "/wheel/odom"
