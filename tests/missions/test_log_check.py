"""What a mission reads from the robot, and whether a log holds it."""

from __future__ import annotations

import pytest

from drivers.logs import codec, topics
from drivers.logs import messages as msg
from drivers.logs.camera_codec import ImageFormat, camera_info_messages, compressed_image_message
from drivers.logs.reader import open_log
from drivers.logs.topics import resolve_topics
from maps.store import InputError
from missions.loader import load_mission
from missions.log_check import Needs, check_log, mission_needs, open_replay
from perception.camera import PanoramaCamera
from perception.geometry import Pose2D
from tests.drivers.log_files import write_log
from tests.drivers.test_logs_record import image


def test_what_the_shipped_missions_read():
    assert mission_needs(load_mission("teach_route")) == Needs(cameras=("panorama",), keys=True)
    assert mission_needs(load_mission("teach_route", overrides={"camera": "landmarks"})).cameras == ("landmarks",)
    assert mission_needs(load_mission("square")) == Needs()
    explore = mission_needs(load_mission("explore"))
    assert explore.ptu and "stereo" in explore.cameras


def test_a_mission_without_a_cameras_list_needs_the_cameras_its_nodes_name(write_mission):
    path = write_mission("""
        tree:
          Sequence:
            children:
              - Perceive: {camera: front, features: orb}
              - Stop
        """)
    assert mission_needs(load_mission(path)).cameras == ("front",)


def log_with(tmp_path, *, odometry=True, camera=True, fmt="png"):
    rows = []
    for i in range(3):
        t = 0.1 * i
        if odometry:
            rows.append((topics.ODOMETRY, msg.ODOMETRY, codec.odometry_message(Pose2D(stamp=t)), t))
        if camera:
            rows.append(("/cameras/panorama/camera_info", msg.CAMERA_INFO,
                         camera_info_messages(PanoramaCamera(72, 20, 5.0, 6.0), t, "panorama")[0], t))
            message = compressed_image_message(image(i), t, "panorama", ImageFormat("png"))
            rows.append(("/cameras/panorama/image/compressed", msg.COMPRESSED_IMAGE, {**message, "format": fmt}, t))
    return write_log(tmp_path / "run.mcap", rows)


def findings(path, needs):
    reader = open_log(path)
    return {f.role: f for f in check_log(path, resolve_topics(reader.contents().types()), reader.contents(), needs)}


def test_a_log_with_what_the_mission_reads(tmp_path):
    found = findings(log_with(tmp_path), Needs(cameras=("panorama",)))
    assert all(f.ok for f in found.values())
    assert "panorama model, 72x20 grey images" in found["camera panorama"].text
    assert str(found["odometry"]) == "ok       odometry: /odom (nav_msgs/msg/Odometry, 3 messages, 10.0 Hz)"


def test_what_is_missing_is_said(tmp_path):
    found = findings(log_with(tmp_path, odometry=False), Needs(cameras=("panorama", "front"), ptu=True, keys=True))
    assert not found["odometry"].ok and "no nav_msgs/msg/Odometry on /odom" in found["odometry"].text
    assert not found["camera front"].ok and "image topics: /cameras/panorama/image/compressed" in \
        found["camera front"].text
    assert not found["pan-tilt"].ok and found["pan-tilt"].required
    assert not found["keys"].ok and not found["keys"].required  # a warning: the keys may never be needed


def test_an_image_encoding_we_do_not_read_is_found_before_the_run(tmp_path):
    found = findings(log_with(tmp_path, fmt="theora"), Needs(cameras=("panorama",)))
    assert not found["camera panorama"].ok
    assert found["camera panorama"].text == ("/cameras/panorama/image/compressed at 0.000 s: compressed image "
                                             "format 'theora' is not one we read (jpeg, png)")


def test_open_replay_refuses_a_log_that_lacks_an_input_with_every_problem(tmp_path):
    path = log_with(tmp_path, odometry=False, camera=False)
    with pytest.raises(InputError) as raised:
        open_replay(path, None, load_mission("teach_route"))
    lines = str(raised.value).splitlines()
    assert len(lines) == 2 and all(line.startswith(f"{path}: ") for line in lines)
    assert "odometry: no nav_msgs/msg/Odometry on /odom (the mission teach_route reads it)" in lines[0]
    assert "camera panorama: not in the log" in lines[1]
    with pytest.raises(InputError, match=r"nowhere\.mcap: no such file"):
        open_replay(tmp_path / "nowhere.mcap", None, load_mission("teach_route"))
