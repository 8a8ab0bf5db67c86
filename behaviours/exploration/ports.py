"""The ports the exploration behaviours share: the map, the goal, the pose, the robot's disc, the head.

A port read by several node types is declared once here, so that its name, type, default and doc
stay the same everywhere (missions, the JSON schema and the BehaviorTree.CPP export read them).
A node's own ports are class attributes of its node type.
"""

from __future__ import annotations

from typing import Any

from behaviours.footprint import robot_radius
from behaviours.ports import InputPort, Ref
from maps.exploration.goal import Goal
from maps.exploration.grid import ExplorationMap
from perception.geometry import Pose2D

ROBOT_RADIUS = InputPort("robot_radius", float, 0.0, unit="m", minimum=0.0, maximum=2.0, literal_only=True,
                         doc="radius of the robot's disc; 0: the disc round the robot's own footprint ('footprint')")
CLEARANCE = InputPort("clearance", float, 0.05, unit="m", minimum=0.0, maximum=1.0, literal_only=True,
                      doc="room kept between the disc and obstacle cells beyond robot_radius (localisation "
                          "error): paths are planned with it, and FollowPath stops the robot short of it")
MARGIN = InputPort("margin", float, 0.3, unit="m", minimum=0.0, maximum=5.0, literal_only=True,
                   doc="paths with less clearance than robot_radius + clearance + margin cost more")
PENALTY = InputPort("penalty", float, 3.0, minimum=0.0, maximum=100.0, literal_only=True,
                    doc="...up to (1 + penalty) times their length")
MAP = InputPort("map", ExplorationMap, Ref("/map/exploration"), doc="the exploration map")
GOAL = InputPort("goal", Goal, Ref("/map/exploration_goal"), doc="the exploration goal (None: none)")
POSE = InputPort("odometry", Pose2D, Ref("/robot/odometry"),
                 doc="the robot's pose (the map's frame): odometry, or a drift-corrected pose")
PTU_POSITION = InputPort("ptu_position", list[float], [0.1, 0.0, 1.0], unit="m", literal_only=True,
                         doc="the pan/tilt axes' intersection on the base: x, y, z")
CAMERA_POSITION = InputPort("camera_position", list[float], [0.05, 0.0, 0.08], unit="m", literal_only=True,
                            doc="the left stereo camera on the pan-tilt head: x, y, z")
FRAMES: InputPort[dict[str, Any]] = InputPort("frames", dict, Ref("/perception/frames"),
                                              doc="the latest frame of each camera, by name")


def disc_radius(node: object) -> float:
    """The radius of the robot's disc for ``node``: its ``robot_radius``, or (0) the disc round the
    robot's own footprint (:mod:`behaviours.footprint`)."""
    return robot_radius(node, node.get_input(ROBOT_RADIUS))  # type: ignore[attr-defined]


def xyz(values: list[float], what: str) -> tuple[float, float, float]:
    """Three numbers from a list port."""
    if len(values) != 3:
        raise ValueError(f"{what} is [x, y, z], got {values}")
    return float(values[0]), float(values[1]), float(values[2])
