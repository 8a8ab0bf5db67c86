"""Recording a run's devices: each reading written once as it is read, every command, drops left
out, the file readable by the mcap reader and its ROS 2 decoder, and a failure never stopping the run."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from drivers.fake import FakeBase, FakePanTilt
from drivers.interfaces import PanTiltState, Robot, VelocityCommand
from drivers.logs import topics
from drivers.logs.camera_codec import ImageFormat, image_from_compressed
from drivers.logs.record import SensorLog
from drivers.logs.source import plain
from perception.camera import PanoramaCamera, PinholeCamera, StereoRig
from perception.frame import Frame, LandmarkBearings
from perception.geometry import Pose2D
from perception.ranges import Bumper, RangeScan, RangeSensor

PANORAMA = PanoramaCamera(72, 20, 5.0, 6.0)


class Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def now(self) -> float:
        return self.t


class ScriptedCamera:
    """A camera that hands out the frames of a script, one per grab (None: dropped)."""

    def __init__(self, name: str, frames: list) -> None:
        self.name = name
        self.frames = list(frames)

    def grab(self):
        return self.frames.pop(0) if self.frames else None

    def close(self) -> None:
        pass


class ScriptedRanges:
    def __init__(self, scans: list) -> None:
        self.scans = list(scans)
        self.scan = None

    def read(self):
        if self.scans:
            self.scan = self.scans.pop(0)
        return self.scan

    def describe(self) -> str:
        return "a scripted ring"

    def close(self) -> None:
        pass


class Keys:
    def __init__(self, reads: list[list[str]]) -> None:
        self.reads = list(reads)

    def read(self) -> list[str]:
        return self.reads.pop(0) if self.reads else []

    def close(self) -> None:
        pass


def image(seed: int, shape=(20, 72)) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, shape, dtype=np.uint8)


SENSORS = (RangeSensor(0.1, 0.0, 0.0), RangeSensor(0.0, 0.1, math.pi / 2))
BUMPERS = (Bumper(0.2, 0.0, 1),)


def scan(t: float, ranges, pressed=False) -> RangeScan:
    return RangeScan(SENSORS, np.array(ranges, float), t, BUMPERS, np.array([pressed]))


PNG = ImageFormat("png")


def recorded_run(path, *, images=PNG):
    """Three ticks of a robot with every kind of device, recorded; the file's decoded messages."""
    clock = Clock()
    base, ptu = FakeBase(), FakePanTilt()
    frames = [Frame(image(t), PANORAMA, t * 0.1, "panorama") if t != 1 else None for t in range(3)]
    stereo = [Frame(image(9, (8, 8)), StereoRig(PinholeCamera(8, 8, 5.0, 5.0, 4.0, 4.0),
                                                 PinholeCamera(8, 8, 5.0, 5.0, 4.0, 4.0), 0.1), 0.0, "stereo",
                    right=image(10, (8, 8)))]
    ideal = [LandmarkBearings(np.array([1, 2]), np.array([[1.0, 0, 0], [0, 1.0, 0]]), 0.0, "landmarks")]
    robot = Robot(base=base, ptu=ptu, cameras={"panorama": ScriptedCamera("panorama", frames),
                                               "stereo": ScriptedCamera("stereo", stereo),
                                               "landmarks": ScriptedCamera("landmarks", ideal)},
                  ranges=ScriptedRanges([scan(0.0, [1.0, math.nan]), scan(0.0, [1.0, math.nan]),
                                         scan(0.2, [0.9, math.inf], pressed=True)]))
    log = SensorLog(path, images=images)
    wrapped = log.wrap(robot, clock.now)
    keyboard = log.wrap_keyboard(lambda: Keys([[], ["up", "up"], ["q"]]))()
    log.open(mission="test", timeline="sim_time", rate_hz=10.0)
    for tick in range(3):
        clock.t = tick * 0.1
        base.pose = Pose2D(0.1 * tick, 0.0, 0.05 * tick, clock.t)
        wrapped.base.odometry()
        wrapped.base.odometry()  # read twice in a tick: written once
        wrapped.base.stalled()
        for camera in wrapped.cameras.values():
            camera.grab()
        wrapped.ptu.state()
        wrapped.ranges.read()
        keyboard.read()
        wrapped.base.drive(0.2, 0.1 * tick)
        if tick == 1:
            wrapped.ptu.move(0.5, 0.0, 1.0)
        log.tick(VelocityCommand(0.3, 0.1 * tick))
    wrapped.stop_all()
    log.close()
    with open(path, "rb") as f:
        decoded = [(channel.topic, schema.name, message.log_time, plain(m))
                   for schema, channel, message, m in make_reader(f, decoder_factories=[DecoderFactory()])
                   .iter_decoded_messages()]
    return log, decoded, wrapped


def test_a_recorded_run_opens_with_the_mcap_reader_and_decodes_with_its_ros2_decoder(tmp_path):
    log, decoded, _ = recorded_run(tmp_path / "run.mcap")
    counts = Counter(topic for topic, *_ in decoded)
    assert counts == {
        topics.ODOMETRY: 3, topics.STALLED: 3, topics.PTU_STATE: 3, topics.CLOCK: 3, topics.TREE_COMMAND: 3,
        topics.SENT_COMMAND: 4,  # three drives and the stop
        topics.PTU_COMMAND: 2,  # a move and the halt of stop_all
        "/cameras/panorama/image/compressed": 2, "/cameras/panorama/camera_info": 2,  # the drop is not there
        "/cameras/stereo/image/compressed": 1, "/cameras/stereo/right/image/compressed": 1,
        "/cameras/stereo/camera_info": 1, "/cameras/stereo/right/camera_info": 1, "/cameras/landmarks/bearings": 1,
        topics.TF_STATIC: 1, topics.RANGES: 3, topics.BUMPERS: 2,  # two scans: 1 + 2 ranges read, a bumper each
        topics.KEYS: 2}
    types = {topic: name for topic, name, *_ in decoded}
    assert types[topics.ODOMETRY] == "nav_msgs/msg/Odometry" and types[topics.CLOCK] == "rosgraph_msgs/msg/Clock"
    assert log.summary()["messages"] == len(decoded) and log.summary()["errors"] == 0


def test_readings_are_written_at_the_time_the_run_read_them(tmp_path):
    _, decoded, _ = recorded_run(tmp_path / "run.mcap")
    odometry = [(t, m["pose"]["pose"]["position"]["x"]) for topic, _, t, m in decoded if topic == topics.ODOMETRY]
    assert odometry == [(0, 0.0), (100_000_000, 0.1), (200_000_000, 0.2)]
    keys = [m["data"] for topic, _, _, m in decoded if topic == topics.KEYS]
    assert keys == ["up up", "q"]
    sent = [m["angular"]["z"] for topic, _, _, m in decoded if topic == topics.SENT_COMMAND]
    assert sent == [0.0, 0.1, 0.2, 0.0]


def test_png_frames_are_the_pixels_the_run_saw(tmp_path):
    _, decoded, _ = recorded_run(tmp_path / "run.mcap")
    images = [m for topic, _, _, m in decoded if topic == "/cameras/panorama/image/compressed"]
    assert [m["header"]["stamp"] for m in images] == [{"sec": 0, "nanosec": 0}, {"sec": 0, "nanosec": 200_000_000}]
    assert np.array_equal(image_from_compressed(images[1]), image(2))


def test_a_scan_is_written_once_and_where_the_sensors_sit_before_it(tmp_path):
    _, decoded, _ = recorded_run(tmp_path / "run.mcap")
    order = [topic for topic, *_ in decoded if topic in (topics.TF_STATIC, topics.RANGES)]
    assert order[0] == topics.TF_STATIC
    ranges = [(m["header"]["frame_id"], m["range"]) for topic, _, _, m in decoded if topic == topics.RANGES]
    assert ranges == [("range_00", 1.0), ("range_00", pytest.approx(0.9)), ("range_01", math.inf)]


def test_a_frame_that_cannot_be_written_is_counted_and_the_run_goes_on(tmp_path):
    clock = Clock()
    bad = Frame(np.zeros((4, 4), np.float32), PANORAMA, 0.0, "panorama")
    log = SensorLog(tmp_path / "run.mcap")
    robot = log.wrap(Robot(base=FakeBase(), cameras={"panorama": ScriptedCamera("panorama", [bad])}), clock.now)
    log.open(mission="test", timeline="sim_time", rate_hz=10.0)
    assert robot.cameras["panorama"].grab() is bad  # the run still gets its frame
    robot.base.odometry()
    log.close()
    summary = log.summary()
    assert summary["errors"] == 1 and "8-bit" in summary["first_error"] and summary["messages"] == 1


def test_the_wrapped_devices_keep_their_own_extras(tmp_path):
    log = SensorLog(tmp_path / "run.mcap")
    ranges = ScriptedRanges([])
    robot = log.wrap(Robot(base=FakeBase(), ptu=FakePanTilt(current=PanTiltState(0.3)), ranges=ranges), Clock().now)
    assert robot.ranges.describe() == "a scripted ring"
    assert robot.ptu.state().pan == 0.3 and robot.base.commands == []  # nothing written before open(), no error
    assert log.summary()["errors"] == 0
