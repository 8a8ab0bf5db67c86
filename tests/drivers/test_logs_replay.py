"""Replaying a log as a robot: the readings of each tick at that tick, frames as logged (drops
included), ranges rebuilt, the logged keys, commands compared and sent nowhere, the end of the log."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from drivers.interfaces import PanTiltState
from drivers.logs import codec, topics
from drivers.logs import messages as msg
from drivers.logs.camera_codec import camera_info_messages
from drivers.logs.reader import open_log
from drivers.logs.replay import EndOfLog, Replay
from drivers.logs.source import LogError
from drivers.logs.topics import resolve_topics
from perception.frame import Frame, LandmarkBearings
from perception.geometry import Pose2D
from tests.drivers.log_files import write_log
from tests.drivers.test_logs_record import PANORAMA, image, recorded_run


def replay_of(path) -> Replay:
    reader = open_log(path)
    return Replay(reader, resolve_topics(reader.contents().types()))


def test_each_tick_sees_what_the_run_read_at_that_tick(tmp_path):
    recorded_run(tmp_path / "run.mcap")
    replay = replay_of(tmp_path / "run.mcap")
    clock, robot = replay.clock(), replay.robot
    seen = []
    for tick in range(3):
        if tick:
            clock.next_tick(0.1)
        frame = robot.cameras["panorama"].grab()
        seen.append((robot.base.odometry(), frame))
    assert [pose.x for pose, _ in seen] == [0.0, 0.1, 0.2]
    assert [pose.theta for pose, _ in seen] == pytest.approx([0.0, 0.05, 0.1], abs=1e-15)
    assert isinstance(seen[0][1], Frame) and seen[1][1] is None  # the drop is a drop again
    assert np.array_equal(seen[2][1].image, image(2)) and seen[2][1].camera == PANORAMA
    assert seen[2][1].stamp == pytest.approx(0.2) and robot.cameras["panorama"].grab() is None  # grabbed once
    # the fake unit jumped to the move of tick 1; its unstamped state reads with the time it was logged
    assert robot.ptu.state() == PanTiltState(0.5, 0.0, False, stamp=0.2) and not robot.base.stalled()
    with pytest.raises(EndOfLog, match=r"run\.mcap ended at 0\.200 s"):
        clock.next_tick(0.1)


def test_the_other_cameras_come_back_as_they_were(tmp_path):
    recorded_run(tmp_path / "run.mcap")
    replay = replay_of(tmp_path / "run.mcap")
    assert replay.robot.cameras["stereo"].grab() is None  # nothing is delivered before the clock starts
    replay.clock()
    stereo, ideal = replay.robot.cameras["stereo"].grab(), replay.robot.cameras["landmarks"].grab()
    assert np.array_equal(stereo.image, image(9, (8, 8))) and np.array_equal(stereo.right, image(10, (8, 8)))
    assert stereo.camera.baseline == pytest.approx(0.1)
    assert isinstance(ideal, LandmarkBearings) and ideal.ids.tolist() == [1, 2]


def test_ranges_and_bumpers_are_rebuilt_from_where_the_sensors_sit(tmp_path):
    recorded_run(tmp_path / "run.mcap")
    replay = replay_of(tmp_path / "run.mcap")
    clock, ranges = replay.clock(), replay.robot.ranges
    first = ranges.read()
    assert first.ranges[0] == 1.0 and math.isnan(first.ranges[1]) and not first.pressed[0]
    assert [(s.x, s.y) for s in first.sensors] == [(0.1, 0.0), (0.0, 0.1)]
    assert first.sensors[1].heading == pytest.approx(math.pi / 2) and first.bumpers[0].facing == 1
    clock.next_tick(0.1)
    clock.next_tick(0.1)
    later = ranges.read()
    assert later.ranges[0] == pytest.approx(0.9) and later.ranges[1] == math.inf and later.pressed[0]
    assert later.stamp == pytest.approx(0.2)
    assert later.fired == pytest.approx([later.stamp] * 2)  # each range's own header stamp (codec.range_messages)


def test_the_logged_keys_and_the_mission_commands(tmp_path):
    recorded_run(tmp_path / "run.mcap")
    replay = replay_of(tmp_path / "run.mcap")
    clock, keys = replay.clock(), replay.keyboard()
    got = []
    for tick in range(3):
        if tick:
            clock.next_tick(0.1)
        got.append(keys.read())
        replay.robot.base.drive(0.2, 0.1 * tick + (0.05 if tick == 2 else 0.0))  # the mission turns more at the end
    assert got == [[], ["up", "up"], ["q"]]
    report = replay.report_sections({})["replay"]
    assert report["commands"] == {"mission": 3, "ptu": 0, "compared": 3, "max_dv": 0.0,
                                  "max_dw": pytest.approx(0.05)}
    assert report["ended"] and report["frames"] == {"panorama": 0, "stereo": 0, "landmarks": 0}


def test_a_log_without_keys_has_no_keyboard(tmp_path):
    rows = [(topics.ODOMETRY, msg.ODOMETRY, codec.odometry_message(Pose2D(stamp=0.0)), 0.0)]
    replay = replay_of(write_log(tmp_path / "run.mcap", rows))
    with pytest.raises(OSError, match="no operator keys"):
        replay.keyboard()
    assert replay.robot.ptu is None and replay.robot.ranges is None and replay.robot.cameras == {}


def test_odometry_starts_at_the_origin_as_a_run_does(tmp_path):
    start = 1_700_000_000.0  # a bag on the wall clock, its odometry where the robot had got to
    rows = [(topics.ODOMETRY, msg.ODOMETRY, codec.odometry_message(Pose2D(5.0 + 0.1 * i, 2.0, math.pi / 2, start)),
             start + 0.1 * i) for i in range(3)]
    replay = replay_of(write_log(tmp_path / "run.mcap", rows))
    clock = replay.clock()
    first = replay.robot.base.odometry()
    assert (first.x, first.y, first.theta, first.stamp) == pytest.approx((0.0, 0.0, 0.0, 0.0), abs=1e-12)
    clock.next_tick(0.2)
    pose = replay.robot.base.odometry()
    assert (pose.x, pose.y, pose.theta) == pytest.approx((0.0, -0.2, 0.0))  # 0.2 m along the start heading (+y)


def test_frames_arrive_at_their_own_rate_between_ticks(tmp_path):
    rows = [("/cameras/panorama/image/compressed", msg.COMPRESSED_IMAGE,
             {"header": codec.header(0.04 * i, "panorama"), "format": "png",
              "data": cv2.imencode(".png", image(i))[1].tobytes()}, 0.04 * i) for i in range(10)]
    rows += [("/cameras/panorama/camera_info", msg.CAMERA_INFO, camera_info_messages(PANORAMA, 0.0, "p")[0], 0.0)]
    replay = replay_of(write_log(tmp_path / "run.mcap", sorted(rows, key=lambda r: r[3])))
    clock, camera = replay.clock(), replay.robot.cameras["panorama"]
    stamps = []
    for _ in range(4):
        clock.next_tick(0.1)
        stamps.append(camera.grab().stamp)
    assert stamps == pytest.approx([0.08, 0.2, 0.28, 0.36])  # the newest frame logged by each tick
    assert replay.report_sections({})["replay"]["frames"] == {"panorama": 4}


def test_a_frame_that_does_not_decode_is_a_located_error(tmp_path):
    rows = [("/cameras/panorama/image/compressed", msg.COMPRESSED_IMAGE,
             {"header": codec.header(0.5, "panorama"), "format": "webp", "data": b"RIFF"}, 0.5)]
    replay = replay_of(write_log(tmp_path / "run.mcap", rows))
    replay.clock()
    with pytest.raises(LogError, match=r"run\.mcap: /cameras/panorama/image/compressed at 0\.000 s: compressed "
                                       r"image format 'webp' is not one we read"):
        replay.robot.cameras["panorama"].grab()


def test_a_range_without_a_mounting_is_a_located_error(tmp_path):
    rows = [(topics.RANGES, msg.RANGE, {"header": codec.header(0.0, "sonar_3"), "range": 1.0}, 0.0)]
    replay = replay_of(write_log(tmp_path / "run.mcap", rows))
    with pytest.raises(LogError, match=r"/ranges at 0\.000 s: frame 'sonar_3' has no transform"):
        replay.clock()


def test_a_sensor_on_a_chain_of_frames_sent_in_two_messages_sits_where_the_chain_puts_it(tmp_path):
    def tf(parent, child, x, yaw):
        return {"header": codec.header(0.0, parent), "child_frame_id": child,
                "transform": {"translation": {"x": x, "y": 0.0, "z": 0.0}, "rotation": codec.yaw_quaternion(yaw)}}

    range_message = {"header": codec.header(0.0, "range_00"), "field_of_view": 0.3, "min_range": 0.1,
                     "max_range": 3.0, "range": 1.0}
    rows = [(topics.TF_STATIC, msg.TF, {"transforms": [tf("sonar_board", "range_00", 0.1, 0.0)]}, 0.0),
            (topics.TF_STATIC, msg.TF, {"transforms": [tf("base_link", "sonar_board", 0.2, math.pi)]}, 0.0),
            (topics.RANGES, msg.RANGE, range_message, 0.0)]
    replay = replay_of(write_log(tmp_path / "run.mcap", rows))
    replay.clock()
    sensor = replay.robot.ranges.read().sensors[0]  # 0.1 m ahead of a board that faces back from x = 0.2
    assert (sensor.x, sensor.y, sensor.heading) == pytest.approx((0.1, 0.0, math.pi))


def test_a_log_cut_short_replays_up_to_the_cut(tmp_path):
    rows = [(topics.ODOMETRY, msg.ODOMETRY, codec.odometry_message(Pose2D(0.01 * i, stamp=0.1 * i)), 0.1 * i)
            for i in range(300)]
    path = write_log(tmp_path / "run.mcap", rows, chunk_bytes=4096, close=False)
    path.write_bytes(path.read_bytes()[:-300])
    replay = replay_of(path)
    clock = replay.clock()
    with pytest.raises(EndOfLog):
        for _ in range(400):
            clock.next_tick(0.1)
    assert 200 < replay.consumed < 300 and "cut at byte" in replay.report_sections({})["replay"]["cut"]
