"""The codecs of odometry, the pan-tilt unit, ranges, bumpers, commands and keys: values worked out
by hand, and every value back as it went in (through the real ROS 2 schemas too)."""

from __future__ import annotations

import dataclasses
import io
import math

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from mcap_ros2.writer import Writer

from drivers.interfaces import PanTiltCommand, PanTiltState, VelocityCommand
from drivers.logs import codec
from drivers.logs import messages as msg
from drivers.logs.source import plain
from perception.geometry import Pose2D
from perception.ranges import Bumper, RangeScan, RangeSensor


def through_cdr(type_name: str, message: dict) -> dict:
    """The message written with its ROS 2 schema and read back with the mcap ROS 2 decoder."""
    buffer = io.BytesIO()
    writer = Writer(buffer)
    schema = writer.register_msgdef(type_name, msg.definition(type_name))
    writer.write_message("/t", schema, message, log_time=0)
    writer.finish()
    buffer.seek(0)
    (_, _, _, decoded), = make_reader(buffer, decoder_factories=[DecoderFactory()]).iter_decoded_messages()
    return plain(decoded)


def test_time_is_whole_nanoseconds_split_into_seconds_and_nanoseconds():
    assert codec.time_message(1.25) == {"sec": 1, "nanosec": 250_000_000}
    assert codec.time_message(0.3) == {"sec": 0, "nanosec": 300_000_000}
    assert codec.time_message(-0.5) == {"sec": -1, "nanosec": 500_000_000}  # ROS: sec floors, nanosec >= 0
    assert codec.time_ns({"sec": 2, "nanosec": 5}) == 2_000_000_005


def test_a_heading_is_a_yaw_quaternion_worked_out_by_hand():
    q = codec.yaw_quaternion(math.pi / 2)
    assert (q["x"], q["y"]) == (0.0, 0.0)
    assert q["z"] == pytest.approx(math.sqrt(0.5)) and q["w"] == pytest.approx(math.sqrt(0.5))
    assert codec.quaternion_yaw(q) == pytest.approx(math.pi / 2)
    # a tilted quaternion: the yaw of roll 0.1 then yaw 0.7 (ZYX) is 0.7
    cr, sr, cy, sy = math.cos(0.05), math.sin(0.05), math.cos(0.35), math.sin(0.35)
    tilted = {"x": sr * cy, "y": sr * sy, "z": cr * sy, "w": cr * cy}
    assert codec.quaternion_yaw(tilted) == pytest.approx(0.7)


@pytest.mark.parametrize("theta", [0.0, 0.3, -2.9, math.pi, -math.pi + 1e-9, 1.0e-12])
def test_odometry_comes_back_as_it_went_in(theta):
    pose = Pose2D(1.25, -0.5, theta, stamp=2.5)
    message = through_cdr(msg.ODOMETRY, codec.odometry_message(pose))
    assert message["header"]["frame_id"] == "odom" and message["child_frame_id"] == "base_link"
    back = codec.pose_from_odometry(message, stamp=2.5)
    assert (back.x, back.y, back.stamp) == (1.25, -0.5, 2.5)
    assert abs(math.remainder(back.theta - theta, 2 * math.pi)) < 1e-15


def test_a_command_is_a_twist():
    message = through_cdr(msg.TWIST, codec.twist_message(VelocityCommand(0.3, -0.2)))
    assert message["linear"]["x"] == 0.3 and message["angular"]["z"] == -0.2
    assert codec.command_from_twist(message) == VelocityCommand(0.3, -0.2)


def test_keys_and_flags():
    assert codec.keys_from(through_cdr(msg.STRING, codec.keys_message(["up", "space", "q"]))) == ["up", "space", "q"]
    assert through_cdr(msg.BOOL, codec.bool_message(True)) == {"data": True}


def test_the_pan_tilt_state_moving_flag_is_its_velocity():
    moving = through_cdr(msg.JOINT_STATE, codec.ptu_state_message(PanTiltState(0.5, -0.1, True, 3.0)))
    assert moving["name"] == ["pan", "tilt"] and moving["position"] == [0.5, -0.1]
    assert all(math.isnan(v) for v in moving["velocity"])  # moving at a speed the unit does not report
    assert codec.ptu_state_from(moving, 3.0) == PanTiltState(0.5, -0.1, True, 3.0)
    still = codec.ptu_state_message(PanTiltState(0.5, -0.1, False, 3.0))
    assert still["velocity"] == [0.0, 0.0] and not codec.ptu_state_from(still, 3.0).moving


def test_a_joint_state_of_other_names_reads_by_the_names_given():
    message = {"name": ["wheel", "head_tilt", "head_pan"], "position": [9.0, -0.2, 0.4], "velocity": [0.0, 0.0, 0.1]}
    state = codec.ptu_state_from(message, 1.0, ("head_pan", "head_tilt"))
    assert (state.pan, state.tilt, state.moving) == (0.4, -0.2, True)
    with pytest.raises(ValueError, match="pan and tilt"):
        codec.ptu_state_from(message, 1.0)


def test_pan_tilt_commands_and_halts():
    move = codec.ptu_command_message(PanTiltCommand(0.2, 0.1, 0.5), 1.0)
    assert move["position"] == [0.2, 0.1] and move["velocity"] == [0.5, 0.5]
    halt = through_cdr(msg.JOINT_STATE, codec.ptu_command_message(None, 1.0))
    assert halt["position"] == [] and halt["velocity"] == [0.0, 0.0]


SCAN = RangeScan(
    sensors=(RangeSensor(0.1, 0.0, 0.0), RangeSensor(0.0, 0.1, math.pi / 2, fov=0.3, max_range=3.0, min_range=0.2),
             RangeSensor(-0.1, 0.0, math.pi)),
    ranges=np.array([1.5, math.inf, math.nan]), stamp=4.0,
    bumpers=(Bumper(0.2, 0.05, 1), Bumper(-0.2, 0.0, -1)), pressed=np.array([True, False]))


def test_ranges_are_one_message_per_sensor_that_has_read():
    messages = [through_cdr(msg.RANGE, m) for m in codec.range_messages(SCAN)]
    assert [m["header"]["frame_id"] for m in messages] == ["range_00", "range_01"]  # nan: not read yet, not written
    assert messages[0]["range"] == 1.5 and messages[1]["range"] == math.inf  # no echo
    assert messages[1]["field_of_view"] == pytest.approx(0.3) and messages[1]["max_range"] == 3.0
    assert messages[1]["min_range"] == pytest.approx(0.2)  # float32


def test_bumpers_are_fixed_distance_rangers():
    front, rear = (through_cdr(msg.RANGE, m) for m in codec.bumper_messages(SCAN))
    assert front["range"] == -math.inf and rear["range"] == math.inf
    assert front["min_range"] == front["max_range"] == 0.0
    assert codec.pressed(front) and not codec.pressed(rear)


def test_where_the_sensors_sit_comes_back_from_tf_static():
    mountings = codec.mountings_from(through_cdr(msg.TF, codec.mounting_message(SCAN, 4.0)))
    assert list(mountings) == ["range_00", "range_01", "range_02", "bumper_00", "bumper_01"]
    assert mountings["range_01"].y == 0.1 and mountings["range_01"].heading == pytest.approx(math.pi / 2)
    assert codec.bumper(mountings["bumper_00"]) == Bumper(0.2, 0.05, 1)
    assert codec.bumper(mountings["bumper_01"]) == Bumper(-0.2, 0.0, -1)
    sensor = codec.range_sensor(mountings["range_01"], codec.range_messages(SCAN)[1])
    assert sensor == RangeSensor(0.0, 0.1, pytest.approx(math.pi / 2), fov=0.3, max_range=3.0, min_range=0.2)


def _tf(parent, child, x=0.0, y=0.0, z=0.0, rotation=None):
    rotation = rotation or codec.yaw_quaternion(0.0)
    return {"header": {"frame_id": parent}, "child_frame_id": child,
            "transform": {"translation": {"x": x, "y": y, "z": z}, "rotation": rotation}}


def test_chains_of_static_transforms_are_followed_to_the_base():
    # base_link -> mast (0.1, 0, 0.5) turned 90 deg -> board (0.2, 0, 0) -> range_00 (0, 0.05) turned -45 deg:
    # the board sits 0.2 m along the mast's x axis, i.e. at (0.1, 0.2) on the base, heading 90 deg;
    # the sensor 0.05 m along the board's y axis (the base's -x): (0.05, 0.2), heading 90 - 45 = 45 deg
    message = {"transforms": [
        _tf("range_board", "range_00", y=0.05, rotation=codec.yaw_quaternion(-math.pi / 4)),
        _tf("base_link", "mast", x=0.1, z=0.5, rotation=codec.yaw_quaternion(math.pi / 2)),
        _tf("mast", "range_board", x=0.2),
        _tf("map", "odom", x=3.0),                       # a chain that ends elsewhere is not on the base
        _tf("loop_a", "loop_b"), _tf("loop_b", "loop_a"),  # nor is one that loops
    ]}
    mountings = codec.mountings_from(message)
    assert set(mountings) == {"range_00", "mast", "range_board"}
    sensor = mountings["range_00"]
    assert (sensor.x, sensor.y, sensor.heading) == pytest.approx((0.05, 0.2, math.pi / 4))
    # a sensor pitched 30 deg down keeps its heading seen from above
    pitched = {"x": 0.0, "y": math.sin(math.radians(15)), "z": 0.0, "w": math.cos(math.radians(15))}
    tilted = codec.mountings_from({"transforms": [_tf("mast", "range_01", rotation=pitched), message["transforms"][1]]})
    assert tilted["range_01"].heading == pytest.approx(math.pi / 2)


def test_transforms_from_another_parent_are_not_mountings():
    transform = {"translation": {"x": 1.0, "y": 0.0}, "rotation": codec.yaw_quaternion(0)}
    message = {"transforms": [{"header": {"frame_id": "map"}, "child_frame_id": "odom", "transform": transform}]}
    assert codec.mountings_from(message) == {}


def test_each_range_is_stamped_when_its_sensor_read():
    fired = dataclasses.replace(SCAN, fired=np.array([3.68, 4.0, math.nan]))  # a ring fires in turn
    stamps = [m["header"]["stamp"] for m in codec.range_messages(fired)]
    assert stamps == [{"sec": 3, "nanosec": 680_000_000}, {"sec": 4, "nanosec": 0}]
    assert [m["header"]["stamp"] for m in codec.range_messages(SCAN)] == [{"sec": 4, "nanosec": 0}] * 2
