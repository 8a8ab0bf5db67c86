"""The ROS 2 message types a sensor log holds, and their definitions as ROS 2 tooling writes them.

A type is named ``package/msg/Type`` (as ``ros2 bag`` writes it); ``package/Type`` (ROS 1, some
MCAP writers) names the same type (:func:`type_name`). The definitions come from the ROS 2 Humble
store of ``rosbags`` (the ``.msg`` text followed by its dependencies after ``====`` separators),
so the schemas in our files are the ones Foxglove and ``ros2 bag`` expect.
"""

from __future__ import annotations

import functools

CLOCK = "rosgraph_msgs/msg/Clock"
ODOMETRY = "nav_msgs/msg/Odometry"
BOOL = "std_msgs/msg/Bool"
STRING = "std_msgs/msg/String"
JOINT_STATE = "sensor_msgs/msg/JointState"
IMAGE = "sensor_msgs/msg/Image"
COMPRESSED_IMAGE = "sensor_msgs/msg/CompressedImage"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"
POINT_CLOUD = "sensor_msgs/msg/PointCloud2"
RANGE = "sensor_msgs/msg/Range"
TWIST = "geometry_msgs/msg/Twist"
TF = "tf2_msgs/msg/TFMessage"

IMAGE_TYPES = (COMPRESSED_IMAGE, IMAGE, POINT_CLOUD)
"""What a camera's topic may carry: images (compressed or raw) or, for the ideal bearings sensor,
the unit bearings of identified landmarks as a point cloud."""


def type_name(name: str) -> str:
    """``sensor_msgs/Image`` and ``sensor_msgs/msg/Image`` both as ``sensor_msgs/msg/Image``."""
    package, _, rest = name.partition("/")
    if rest and "/" not in rest:
        return f"{package}/msg/{rest}"
    return name


@functools.cache
def definition(name: str) -> str:
    """The ROS 2 message definition of a type, its dependencies appended (KeyError: unknown type)."""
    from rosbags.typesys import Stores, get_typestore

    text, _ = get_typestore(Stores.ROS2_HUMBLE).generate_msgdef(type_name(name), ros_version=2)
    return str(text)
