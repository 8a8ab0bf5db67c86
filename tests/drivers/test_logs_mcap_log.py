"""MCAP files: what they hold from the index, messages streamed in time order as dicts, a file cut
short read up to the cut, damage as one located line, memory bounded whatever the length."""

from __future__ import annotations

import tracemalloc

import pytest
from mcap.reader import make_reader
from mcap.writer import Writer as RawWriter

from drivers.logs import codec
from drivers.logs import messages as msg
from drivers.logs.reader import open_log
from drivers.logs.source import LogError
from perception.geometry import Pose2D
from tests.drivers.log_files import write_log


def odometry_rows(count: int, period: float = 0.1):
    for i in range(count):
        yield "/odom", msg.ODOMETRY, codec.odometry_message(Pose2D(0.1 * i, 0.0, 0.0, i * period)), i * period
        yield "/robot/stalled", msg.BOOL, codec.bool_message(i % 2 == 1), i * period


def test_an_indexed_file_says_what_it_holds_without_reading_the_messages(tmp_path):
    reader = open_log(write_log(tmp_path / "run.mcap", odometry_rows(30)))
    contents = reader.contents()
    assert contents.format == "mcap" and contents.cut is None
    assert {t.name: (t.type, t.count) for t in contents.topics.values()} == {
        "/odom": (msg.ODOMETRY, 30), "/robot/stalled": (msg.BOOL, 30)}
    assert (contents.start_ns, contents.end_ns) == (0, 2_900_000_000) and contents.duration_s == pytest.approx(2.9)
    assert contents.metadata == {"mission": "test"}


def test_messages_of_the_topics_asked_for_stream_in_time_order_as_dicts(tmp_path):
    reader = open_log(write_log(tmp_path / "run.mcap", odometry_rows(30), chunk_bytes=512))
    got = list(reader.messages(["/odom"]))
    assert [m.log_ns for m in got] == [i * 100_000_000 for i in range(30)]
    assert {m.topic for m in got} == {"/odom"} and got[0].type == msg.ODOMETRY
    assert got[3].message["pose"]["pose"]["position"]["x"] == pytest.approx(0.3)
    assert isinstance(got[3].message["header"], dict)


def test_a_file_cut_short_reads_up_to_the_cut_and_says_where(tmp_path):
    path = write_log(tmp_path / "run.mcap", odometry_rows(200), chunk_bytes=2048, close=False)
    data = path.read_bytes()
    path.write_bytes(data[:-700])  # the run was killed mid-chunk
    reader = open_log(path)
    contents = reader.contents()
    assert contents.cut is not None and "cut at byte" in contents.cut and "did not close" in contents.cut
    odometry = contents.topics["/odom"].count
    assert 100 < odometry < 200  # all but the last chunk
    assert len(list(reader.messages(["/odom"]))) == odometry and reader.cut is not None


def test_a_damaged_chunk_is_one_located_line(tmp_path):
    path = write_log(tmp_path / "run.mcap", odometry_rows(200), chunk_bytes=2048)
    with open(path, "rb") as f:
        chunk = make_reader(f).get_summary().chunk_indexes[3]
    data = bytearray(path.read_bytes())
    middle = chunk.chunk_start_offset + chunk.chunk_length // 2
    data[middle:middle + 40] = bytes(40)  # zeros in the middle of a compressed chunk
    path.write_bytes(bytes(data))
    reader = open_log(path)
    with pytest.raises(LogError, match=r"run\.mcap: at byte \d+: damaged: "):
        list(reader.messages(["/odom", "/robot/stalled"]))


def test_a_message_that_does_not_decode_names_its_topic_and_time(tmp_path):
    path = tmp_path / "bad.mcap"
    with open(path, "wb") as f:
        writer = RawWriter(f)
        writer.start(profile="ros2")
        schema = writer.register_schema(msg.ODOMETRY, "ros2msg", msg.definition(msg.ODOMETRY).encode())
        channel = writer.register_channel("/odom", "cdr", schema)
        writer.add_message(channel, log_time=1_500_000_000, data=b"\x00\x01\x00\x00" + b"\x07" * 9, publish_time=0)
        json_channel = writer.register_channel("/json", "json", writer.register_schema("Foo", "jsonschema", b"{}"))
        writer.add_message(json_channel, log_time=0, data=b"{}", publish_time=0)
        writer.finish()
    reader = open_log(path)
    assert "we read ROS 2 (cdr)" in reader.contents().topics["/json"].problem
    assert "/json" not in reader.contents().types()
    with pytest.raises(LogError, match=r"bad\.mcap: /odom at 1\.500 s: cannot decode nav_msgs/msg/Odometry"):
        list(reader.messages(["/odom"]))


def flag_rows(count: int):
    for i in range(count):
        yield "/robot/stalled", msg.BOOL, codec.bool_message(i % 3 == 0), i * 0.01


def _peak_streaming(path) -> tuple[int, int]:
    reader = open_log(path)
    reader.contents()  # the index (its size grows with the number of chunks, not of messages)
    tracemalloc.start()
    try:
        count = sum(1 for _ in reader.messages(["/robot/stalled"]))
        return count, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
        reader.close()


def test_memory_stays_bounded_however_many_messages_the_log_holds(tmp_path):
    small = write_log(tmp_path / "small.mcap", flag_rows(2_000), chunk_bytes=16 * 1024)
    large = write_log(tmp_path / "large.mcap", flag_rows(16_000), chunk_bytes=16 * 1024)
    (count_small, peak_small), (count_large, peak_large) = _peak_streaming(small), _peak_streaming(large)
    assert (count_small, count_large) == (2_000, 16_000)
    # eight times the messages, the same one chunk in memory (~60 kB here; all 16 000 held at once: ~4.6 MB)
    assert peak_large < 1.3 * peak_small + 50_000, (peak_small, peak_large)
    assert peak_large < 500_000
