"""Record on the robot, teach offline: a teach_route run in the simulator recorded with --record
and replayed with --replay through teach_route gives the same LT-map, which takes follow_route
home in the simulator; a ROS 2 bag that rosbags writes from simulator frames (images and
odometry, both storage formats) replays through teach_route to a map."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import cv2
import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as BagWriter
from rosbags.typesys import Stores, get_typestore

from drivers.fake import FakeKeys
from drivers.logs import messages as msg
from drivers.sim.simulation import Simulation
from maps.ltmap.file import load_ltmap
from missions.cli import main
from missions.loader import load_mission
from missions.runner import Runner, RunOptions

ROUTE = "route=[1.0, 0.0, 1.3, 0.3]"  # a short teach: ~1.5 m with a turn


def run(*args: str) -> int:
    return main(["run", *args, "--quiet"])


@pytest.fixture(scope="module")
def taught(tmp_path_factory) -> Path:
    """A live teach recorded losslessly, and its replay through the same mission."""
    folder = tmp_path_factory.mktemp("taught")
    assert run("teach_route", "--sim", "lab", "--set", ROUTE, "--set", f"map={folder / 'live.ltmap'}",
               "--output-dir", str(folder), "--record", str(folder / "run.mcap"), "--record-images", "png",
               "--report", str(folder / "live.json")) == 0
    assert run("teach_route", "--replay", str(folder / "run.mcap"), "--set", ROUTE,
               "--set", f"map={folder / 'replay.ltmap'}", "--output-dir", str(folder),
               "--report", str(folder / "replay.json")) == 0
    return folder


def test_the_replayed_teach_gives_the_same_map_as_the_live_one(taught):
    live, replayed = load_ltmap(taught / "live.ltmap"), load_ltmap(taught / "replay.ltmap")
    assert replayed.summary() == live.summary() and live.viewframe_count >= 3
    assert replayed.node_parents == live.node_parents and replayed.viewframe_leaves == live.viewframe_leaves
    assert np.array_equal(replayed.landmark_nodes, live.landmark_nodes)
    assert np.array_equal(replayed.descriptors, live.descriptors)  # the very ORB features: png is lossless
    assert np.allclose(replayed.bearings, live.bearings, rtol=0, atol=1e-12)  # headings through a quaternion


def test_the_replay_commanded_what_the_live_run_did(taught):
    live = json.loads((taught / "live.json").read_text())
    replayed = json.loads((taught / "replay.json").read_text())
    assert replayed["ticks"] == live["ticks"] and replayed["status"] == "SUCCESS"
    assert replayed["ltmap"]["taught"] == live["ltmap"]["taught"]
    commands = replayed["replay"]["commands"]
    assert commands["compared"] == commands["mission"] == live["ticks"]
    assert commands["max_dv"] == commands["max_dw"] == 0.0
    assert replayed["replay"]["frames"] == {"panorama": live["ticks"]} and replayed["replay"]["ended"]
    assert live["record"]["errors"] == 0 and live["record"]["images"] == "png"


def test_the_log_names_the_robots_outline_and_the_replay_judges_with_it(taught):
    """The lab's robot is the simulator's disc of 0.26 m (a 32-gon round it: corners 0.26 / cos(pi / 32)
    = 0.26126 m out), not the P3-DX box a replay assumed before; the replay's safety section shows
    the outline it judged with."""
    live = json.loads((taught / "live.json").read_text())
    replayed = json.loads((taught / "replay.json").read_text())
    outline = np.array(live["safety"]["footprint"])
    assert outline.shape == (32, 2) and np.allclose(np.hypot(*outline.T), 0.26126, atol=1e-4)
    assert replayed["safety"]["footprint"] == live["safety"]["footprint"]
    with open(taught / "run.mcap", "rb") as f:
        metadata = {m.name: m.metadata for m in make_reader(f).iter_metadata()}["bearings"]
    assert np.allclose(json.loads(metadata["footprint"]), outline, atol=1e-4)  # the report rounds to 0.1 mm


def test_the_replayed_map_takes_follow_route_home(taught):
    report = taught / "follow.json"
    assert run("follow_route", "--sim", "lab", "--set", f"map={taught / 'replay.ltmap'}", "--output-dir", str(taught),
               "--report", str(report)) == 0
    final = json.loads(report.read_text())["ground_truth"]["final_pose"]
    assert np.hypot(final["x"] - 1.5, final["y"] - 1.5) < 0.25  # home: the lab's start


def test_the_recorded_log_opens_with_the_mcap_reader_and_its_ros2_decoder(taught):
    live = json.loads((taught / "live.json").read_text())
    with open(taught / "run.mcap", "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == "ros2"
        counts = Counter((channel.topic, schema.name) for schema, channel, _, _ in reader.iter_decoded_messages())
    ticks = live["ticks"]
    assert counts[("/cameras/panorama/image/compressed", msg.COMPRESSED_IMAGE)] == ticks
    assert counts[("/cameras/panorama/camera_info", msg.CAMERA_INFO)] == ticks
    assert counts[("/odom", msg.ODOMETRY)] == counts[("/clock", "rosgraph_msgs/msg/Clock")] == ticks
    assert counts[("/tree/cmd_vel", msg.TWIST)] == ticks and counts[("/cmd_vel", msg.TWIST)] == ticks + 1  # + stop


# -- a ROS 2 bag from simulator frames -------------------------------------------------------------------
STORE = get_typestore(Stores.ROS2_HUMBLE)
T = STORE.types
START_NS = 1_700_000_000_000_000_000  # a bag on the wall clock


def _header(t_ns: int, frame: str):
    return T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=t_ns // 10**9, nanosec=t_ns % 10**9),
                                    frame_id=frame)


def _odometry(t_ns: int, pose) -> object:
    q = T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=np.sin(pose.theta / 2), w=np.cos(pose.theta / 2))
    p = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=pose.x, y=pose.y, z=0.0), orientation=q)
    zero = T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
    return T["nav_msgs/msg/Odometry"](
        header=_header(t_ns, "odom"), child_frame_id="base_link",
        pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=p, covariance=np.zeros(36)),
        twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=T["geometry_msgs/msg/Twist"](linear=zero, angular=zero),
                                                         covariance=np.zeros(36)))


def _image(t_ns: int, pixels: np.ndarray, compressed: bool) -> tuple[str, object]:
    if compressed:
        data = np.frombuffer(cv2.imencode(".png", pixels)[1].tobytes(), np.uint8)
        return "sensor_msgs/msg/CompressedImage", T["sensor_msgs/msg/CompressedImage"](
            header=_header(t_ns, "camera"), format="png", data=data)
    height, width = pixels.shape
    return "sensor_msgs/msg/Image", T["sensor_msgs/msg/Image"](
        header=_header(t_ns, "camera"), height=height, width=width, encoding="mono8", is_bigendian=0, step=width,
        data=pixels.reshape(-1))


def simulator_bag(path: Path, storage: StoragePlugin) -> Path:
    """Drive 1.2 m straight in the lab and write what the robot sensed as a ROS 2 bag, as another
    recorder would: raw images in the sqlite3 bag, compressed in the MCAP one, and odometry."""
    sim = Simulation.load("lab", seed=3)
    compressed = storage == StoragePlugin.MCAP
    image_topic = "/camera/image/compressed" if compressed else "/camera/image_raw"
    with BagWriter(path, version=9, storage_plugin=storage) as writer:
        odometry = writer.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=STORE)
        images = writer.add_connection(image_topic, _image(0, np.zeros((2, 2), np.uint8), compressed)[0],
                                       typestore=STORE)
        for tick in range(45):
            t_ns = START_NS + tick * 100_000_000
            frame = sim.robot.cameras["panorama"].grab()
            writer.write(odometry, t_ns, STORE.serialize_cdr(_odometry(t_ns, sim.robot.base.odometry()),
                                                             "nav_msgs/msg/Odometry"))
            if frame is not None:
                kind, message = _image(t_ns, frame.image, compressed)
                writer.write(images, t_ns + 5_000_000, STORE.serialize_cdr(message, kind))  # 5 ms later
            sim.robot.base.drive(0.3, 0.0)
            sim.step(0.1)
    return path


@pytest.mark.parametrize("storage", [StoragePlugin.SQLITE3, StoragePlugin.MCAP], ids=["sqlite3", "mcap"])
def test_a_ros2_bag_of_simulator_frames_replays_through_teach_route_to_a_map(tmp_path, storage):
    bag = simulator_bag(tmp_path / "bag", storage)
    image_topic = "/camera/image/compressed" if storage == StoragePlugin.MCAP else "/camera/image_raw"
    topic_map = tmp_path / "topics.yaml"
    topic_map.write_text(f"cameras:\n  panorama:\n    image: {image_topic}\n    model: panorama.yaml\n")
    (tmp_path / "panorama.yaml").write_text("kind: panorama\nwidth: 720\nheight: 172\ndeg_per_px: 0.5\n"
                                            "horizon_row: 60\n")
    report = tmp_path / "report.json"
    assert main(["log", "check", str(bag), "teach_route", "--topics", str(topic_map)]) == 0
    assert run("teach_route", "--replay", str(bag), "--topics", str(topic_map), "--set", "route=[1.0, 0.0]",
               "--set", f"map={tmp_path / 'bag.ltmap'}", "--output-dir", str(tmp_path), "--report", str(report)) == 0, \
        json.loads(report.read_text())["reason"]
    taught = load_ltmap(tmp_path / "bag.ltmap")
    assert taught.viewframe_count >= 3 and taught.landmark_count > 300
    section = json.loads(report.read_text())["replay"]
    assert section["format"] == f"ROS 2 bag ({storage.name.lower()})" and section["frames"]["panorama"] > 30


def test_a_route_taught_by_keys_replays_with_the_logged_keys(tmp_path):
    """On a robot the operator drives the teach by keys: the keys are in the log, so the replay drives
    (and ends) the route as the operator did."""
    keys = FakeKeys([["up"]] * 25 + [["left"]] * 8 + [["up"]] * 10 + [["q"]])
    sets = {"camera": "landmarks", "drive": "keyboard", "map": str(tmp_path / "live.ltmap")}
    sim = Simulation.load("lab", seed=2)
    mission = load_mission("teach_route", overrides=sets, output_dir=tmp_path)
    result = Runner(mission, sim.robot, clock=sim.clock(), observers=[sim],
                    options=RunOptions(record_path=tmp_path / "run.mcap"), keyboard=lambda: keys).run()
    assert result.status == "SUCCESS", result.reason
    assert run("teach_route", "--replay", str(tmp_path / "run.mcap"), "--set", "camera=landmarks",
               "--set", "drive=keyboard", "--set", f"map={tmp_path / 'replay.ltmap'}",
               "--output-dir", str(tmp_path)) == 0
    live, replayed = load_ltmap(tmp_path / "live.ltmap"), load_ltmap(tmp_path / "replay.ltmap")
    assert replayed.summary() == live.summary() and live.viewframe_count >= 3
    assert np.allclose(replayed.bearings, live.bearings, rtol=0, atol=1e-12)
