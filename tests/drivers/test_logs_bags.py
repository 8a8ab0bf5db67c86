"""ROS bags written by rosbags itself (ROS 2 in both storage formats, ROS 1) read as logs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from drivers.logs import messages as msg
from drivers.logs.reader import open_log
from drivers.logs.source import LogError

ROS2 = get_typestore(Stores.ROS2_HUMBLE)
ROS1 = get_typestore(Stores.ROS1_NOETIC)


def odometry(store, x: float, t_ns: int):
    T = store.types
    stamp = T["builtin_interfaces/msg/Time"](sec=t_ns // 10**9, nanosec=t_ns % 10**9)
    kwargs = {"seq": 0} if store is ROS1 else {}
    header = T["std_msgs/msg/Header"](stamp=stamp, frame_id="odom", **kwargs)
    pose = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=x, y=0.0, z=0.0),
                                       orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0))
    twist = T["geometry_msgs/msg/Twist"](linear=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
                                         angular=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0))
    return T["nav_msgs/msg/Odometry"](header=header, child_frame_id="base_link",
                                      pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose,
                                                                                     covariance=np.zeros(36)),
                                      twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=twist,
                                                                                       covariance=np.zeros(36)))


def ros2_bag(path: Path, storage: StoragePlugin, custom: bool = False) -> Path:
    with Writer2(path, version=9, storage_plugin=storage) as writer:
        connection = writer.add_connection("/odom", msg.ODOMETRY, typestore=ROS2)
        for i in range(5):
            t = 1_700_000_000_000_000_000 + i * 100_000_000
            writer.write(connection, t, ROS2.serialize_cdr(odometry(ROS2, 0.1 * i, t), msg.ODOMETRY))
        if custom:
            writer.add_connection("/thing", "my_msgs/msg/Thing", msgdef="int32 a\n", rihs01="RIHS01_" + "0" * 64)
    return path


@pytest.mark.parametrize("storage", [StoragePlugin.SQLITE3, StoragePlugin.MCAP], ids=["sqlite3", "mcap"])
def test_a_ros2_bag_in_either_storage_streams_as_dicts(tmp_path, storage):
    reader = open_log(ros2_bag(tmp_path / "bag", storage))
    contents = reader.contents()
    assert contents.format == f"ROS 2 bag ({storage.name.lower()})"
    assert contents.topics["/odom"].type == msg.ODOMETRY and contents.topics["/odom"].count == 5
    assert contents.duration_s == pytest.approx(0.4)
    got = list(reader.messages(["/odom"]))
    assert [m.message["pose"]["pose"]["position"]["x"] for m in got] == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4])
    assert got[1].log_ns - got[0].log_ns == 100_000_000
    reader.close()


def test_a_ros1_bag_reads_the_same_way(tmp_path):
    path = tmp_path / "run.bag"
    with Writer1(path) as writer:
        connection = writer.add_connection("/odom", msg.ODOMETRY, typestore=ROS1)
        for i in range(3):
            writer.write(connection, 10**9 + i, ROS1.serialize_ros1(odometry(ROS1, float(i), 10**9 + i), msg.ODOMETRY))
    reader = open_log(path)
    assert reader.contents().format == "ROS 1 bag"
    assert [m.message["pose"]["pose"]["position"]["x"] for m in reader.messages(["/odom"])] == [0.0, 1.0, 2.0]


def test_what_cannot_be_read_is_one_line(tmp_path):
    with pytest.raises(LogError, match="no such file"):
        open_log(tmp_path / "nowhere.mcap")
    (tmp_path / "empty").mkdir()
    with pytest.raises(LogError, match="without metadata.yaml is not a ROS 2 bag"):
        open_log(tmp_path / "empty")
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "metadata.yaml").write_text("rosbag2_bagfile_information: [\n")
    with pytest.raises(LogError, match=r"broken: not a bag we can read: "):
        open_log(tmp_path / "broken")
    (tmp_path / "notes.txt").write_text("hello")
    with pytest.raises(LogError, match=r"notes\.txt: not an MCAP file, a ROS 2 bag folder or a ROS 1 \.bag"):
        open_log(tmp_path / "notes.txt")
    sqlite = next((ros2_bag(tmp_path / "bag", StoragePlugin.SQLITE3)).glob("*.db3"))
    with pytest.raises(LogError, match="open its folder"):
        open_log(sqlite)


def test_a_type_the_bag_defines_itself_is_read_with_its_definition(tmp_path):
    path = tmp_path / "bag"
    with Writer2(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        store = get_typestore(Stores.EMPTY)
        store.register(get_types_from_msg("int32 a\nstring b\n", "my_msgs/msg/Thing"))
        connection = writer.add_connection("/thing", "my_msgs/msg/Thing", typestore=store)
        writer.write(connection, 5, b"\x00\x01\x00\x00" + (7).to_bytes(4, "little") + (3).to_bytes(4, "little")
                     + b"hi\x00")
    reader = open_log(path)
    thing = reader.contents().topics["/thing"]
    assert thing.type == "my_msgs/msg/Thing" and not thing.problem
    (message,) = reader.messages(["/thing"])
    assert message.message == {"a": 7, "b": "hi"}
