"""The data flow between nodes: checked at load time, wired at run time, exported with its ports."""

from __future__ import annotations

import json
import textwrap
import xml.etree.ElementTree as ET

import pytest

from maps.store import InputError
from missions.cli import main
from missions.export import btcpp_xml
from missions.loader import LIBRARY, load_mission

POSE_PLUGIN = """
from py_trees.common import Status
from behaviours.base import BearingsBehaviour
from behaviours.ports import InputPort, OutputPort
from behaviours.registry import register
from perception.geometry import Pose2D

@register
class PickGoal(BearingsBehaviour):
    '''Write a goal pose (a test plugin).'''
    PORTS = (OutputPort("goal", Pose2D, "/map/goal", doc="the chosen goal"),)
    def update(self):
        self.set_output("goal", Pose2D(1.0, 2.0))
        return Status.SUCCESS

@register
class UseDistance(BearingsBehaviour):
    '''Read a distance (a test plugin).'''
    PORTS = (InputPort("distance", float, unit="m"),)
    def update(self):
        return Status.SUCCESS
"""


def problems(path) -> list[tuple[int, str]]:
    with pytest.raises(InputError) as info:
        load_mission(path)
    return [(d.line, d.message) for d in info.value.diagnostics]


def test_reading_a_key_nobody_writes_is_refused_with_its_line(write_mission):
    path = write_mission("""
        inputs: {distance: 1.0}
        tree:
          Sequence:
            children:
              - Drive: {distance: "{/mission/distance_nobody_writes}"}
              - CheckBlackboard: {key: /mission/never_written, op: "==", value: 1}
              - Drive: {distance: "{/mission/distanse}"}
    """)
    assert problems(path) == [
        (5, "Drive.distance reads /mission/distance_nobody_writes, which nothing writes (written keys: "
            "/mission/distance, /perception/frame, /perception/frames, /ptu/state, /robot/command, "
            "/robot/footprint, /robot/odometry, /robot/ranges, /robot/safety, /robot/stalled)"),
        (6, "CheckBlackboard.key reads /mission/never_written, which nothing writes (written keys: "
            "/mission/distance, /perception/frame, /perception/frames, /ptu/state, /robot/command, "
            "/robot/footprint, /robot/odometry, /robot/ranges, /robot/safety, /robot/stalled)"),
        (7, "Drive.distance reads /mission/distanse, which nothing writes; did you mean '/mission/distance'?"),
    ]


def test_a_pose_output_wired_into_a_float_input_is_refused(write_mission, tmp_path):
    (tmp_path / "nodes.py").write_text(POSE_PLUGIN)
    path = write_mission("""
        plugins: [nodes.py]
        tree:
          Sequence:
            children:
              - PickGoal: {goal: "{/mission/goal}"}
              - UseDistance: {distance: "{/mission/goal}"}
              - UseDistance: {distance: "{/mission/goal.x}"}
              - UseDistance: {distance: "{/mission/goal.z}"}
    """)
    assert problems(path) == [
        (6, "UseDistance.distance is float, but /mission/goal holds Pose2D (written by PickGoal)"),
        (8, "UseDistance.distance: /mission/goal holds Pose2D, and Pose2D has no attribute 'z'"),
    ]


def test_writers_of_one_key_agree_on_its_type_and_the_runner_reads_commands_typed(write_mission, tmp_path):
    (tmp_path / "nodes.py").write_text(POSE_PLUGIN)
    path = write_mission("""
        plugins: [nodes.py]
        inputs: {target: 3.0}
        tree:
          Sequence:
            children:
              - PickGoal: {goal: "{/mission/target}"}
              - PickGoal: {goal: "{/robot/command}"}
    """)
    found = problems(path)
    assert (6, "PickGoal writes Pose2D to /mission/target, where the mission input 'target' writes float: one key "
               "holds one type") in found
    assert (7, "PickGoal writes Pose2D to /robot/command, which the runner reads as VelocityCommand") in found


def test_mission_inputs_are_readable_at_run_time_with_their_type(write_mission):
    path = write_mission("""
        inputs:
          side: {type: float, default: 0.5}
          label: {type: str, default: lap}
        tree:
          Sequence:
            children:
              - Drive: {distance: "{/mission/side}"}
              - Drive: {distance: "{/mission/label}"}
    """)
    assert problems(path) == [(8, "Drive.distance is float, but /mission/label holds str (written by the mission "
                                  "input 'label')")]


def test_two_perceive_nodes_on_two_cameras_feed_two_readers(write_mission, tmp_path):
    """Two cameras, two remapped observation keys, a downstream node reading each (in the simulator)."""
    path = write_mission("""
        cameras: [panorama, front]
        sense:
          - Perceive: {name: all round, camera: panorama, observation: "{/perception/panorama}"}
          - Perceive: {name: ahead, camera: front, observation: "{/perception/front}"}
        tree:
          Sequence:
            children:
              - Wait: {duration: 0.2}
              - CheckBlackboard: {key: /perception/panorama.count, op: ">", value: 50}
              - CheckBlackboard: {key: /perception/front.count, op: ">", value: 20}
              - CheckBlackboard: {key: /perception/front.camera_name, op: "==", value: front}
    """)
    mission = load_mission(path)
    assert [node.outputs["observation"] for node in mission.sense] == ["/perception/panorama", "/perception/front"]
    report = tmp_path / "report.json"
    assert main(["run", str(path), "--sim", "lab", "--quiet", "--report", str(report)]) == 0
    assert json.loads(report.read_text())["status"] == "SUCCESS"
    unwired = write_mission(textwrap.dedent("""
        cameras: [panorama]
        sense: [{Perceive: {camera: panorama}}]
        tree: {CheckBlackboard: {key: /perception/front.count, op: ">", value: 20}}
    """), name="unwired.yaml")
    assert problems(unwired)[0][1].startswith("CheckBlackboard.key reads /perception/front, which nothing writes")


@pytest.mark.parametrize("path", sorted(LIBRARY.glob("*.yaml")), ids=lambda p: p.stem)
def test_every_shipped_mission_exports_typed_input_and_output_ports(path):
    mission = load_mission(path)
    root = ET.fromstring(btcpp_xml(mission).split("\n", 1)[1])
    model = root.find("TreeNodesModel")
    assert model is not None
    ports = model.findall("*/input_port") + model.findall("*/output_port")
    assert ports and all(port.get("type") for port in ports)
    assert model.findall("*/output_port"), "every shipped mission moves the robot: some node writes a command"
    for element in model:
        node_type = mission.registry.lookup(element.get("ID"))
        declared = {p.name for p in (*node_type.inputs, *node_type.outputs)}
        assert {p.get("name") for p in element} == declared
    drive = root.find(".//TreeNodesModel/Action[@ID='Drive']")
    if drive is not None:
        command = drive.find("output_port[@name='command']")
        assert command.get("type") == "VelocityCommand" and command.get("default") == "{@robot__command}"
        assert drive.find("input_port[@name='distance']").get("type") == "double"
