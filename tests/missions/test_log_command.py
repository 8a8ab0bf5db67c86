"""``bearings log info`` and ``bearings log check``: what a log holds, what a mission lacks, and a
bad log or topic map as one line with exit 2."""

from __future__ import annotations

import json

from mcap.reader import make_reader

from missions.cli import main
from tests.missions.test_log_check import log_with


def test_info_lists_topics_rates_duration_and_cameras(tmp_path, capsys):
    path = log_with(tmp_path)
    assert main(["log", "info", str(path)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"{path}: mcap, 0.2 s, 9 messages, ")
    assert "  recorded: mission test" in out
    assert any(line.split()[:4] == ["/odom", "nav_msgs/msg/Odometry", "3", "10.0"] for line in out)
    assert "  panorama: /cameras/panorama/image/compressed (sensor_msgs/msg/CompressedImage, 3 messages, 10.0 Hz), " \
           "panorama model, 72x20 grey images" in out
    assert out[-1] == "odometry: /odom (nav_msgs/msg/Odometry, 3 messages, 10.0 Hz)"


def test_info_as_json(tmp_path, capsys):
    path = log_with(tmp_path, odometry=False)
    assert main(["log", "info", str(path), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["duration_s"] == 0.2 and info["messages"] == 6 and info["cameras"]["panorama"]["ok"]
    assert not info["odometry"]["ok"] and info["bytes"] == path.stat().st_size


def test_check_passes_a_log_with_what_the_mission_reads(tmp_path, capsys):
    assert main(["log", "check", str(log_with(tmp_path)), "teach_route"]) == 0
    out = capsys.readouterr().out
    assert "OK: " in out and "warning  keys: the mission can drive by keys" in out


def test_check_fails_with_what_is_missing(tmp_path, capsys):
    path = log_with(tmp_path, odometry=False)
    assert main(["log", "check", str(path), "teach_route", "--set", "camera=landmarks"]) == 2
    captured = capsys.readouterr()
    assert "MISSING  odometry: no nav_msgs/msg/Odometry on /odom" in captured.out
    assert "MISSING  camera landmarks: not in the log" in captured.out
    assert captured.err.strip() == f"{path}: 2 input(s) of teach_route missing: odometry, camera landmarks"


def test_run_replay_stops_before_the_run_when_the_log_lacks_an_input(tmp_path, capsys):
    path = log_with(tmp_path, odometry=False)
    report = tmp_path / "report.json"
    assert main(["run", "teach_route", "--replay", str(path), "--quiet", "--report", str(report)]) == 2
    err = capsys.readouterr().err
    assert "odometry: no nav_msgs/msg/Odometry on /odom (the mission teach_route reads it)" in err
    assert not report.exists()


def test_bad_logs_are_one_line_and_exit_2(tmp_path, capsys):
    (tmp_path / "notes.mcap").write_text("not a log")
    assert main(["log", "info", str(tmp_path / "notes.mcap")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"{tmp_path / 'notes.mcap'}: not an MCAP file, a ROS 2 bag folder or a ROS 1 .bag (it starts with " \
                  "b'not a lo')"
    whole = log_with(tmp_path)
    with open(whole, "rb") as f:
        chunk = make_reader(f).get_summary().chunk_indexes[0]
    damaged = bytearray(whole.read_bytes())
    middle = chunk.chunk_start_offset + chunk.chunk_length // 2
    damaged[middle:middle + 64] = bytes(64)
    (tmp_path / "damaged.mcap").write_bytes(bytes(damaged))
    # the index is whole, so info lists the topics; reading the damaged chunk says where the damage is
    assert main(["run", "teach_route", "--replay", str(tmp_path / "damaged.mcap"), "--quiet"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2 and err[1] == "1 problem found" and "Traceback" not in err[0]
    assert err[0].startswith(f"{tmp_path / 'damaged.mcap'}: camera panorama: at byte ")
    assert ": damaged: CRCValidationError" in err[0]


def test_a_log_cut_short_is_read_up_to_the_cut(tmp_path, capsys):
    whole = log_with(tmp_path)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole.read_bytes()[:-200])
    assert main(["log", "info", str(cut)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1].startswith("  cut at byte ") and "(the run did not close the file)" in out[1]


def test_a_bad_topic_map_is_located(tmp_path, capsys):
    topic_map = tmp_path / "topics.yaml"
    topic_map.write_text("odometry: 3\n")
    assert main(["log", "info", str(log_with(tmp_path)), "--topics", str(topic_map)]) == 2
    assert f"{topic_map}:1:11: " in capsys.readouterr().err
    assert main(["run", "square", "--topics", str(topic_map), "--quiet"]) == 2
    assert "--topics: maps the topics of a log: it goes with --replay LOG" in capsys.readouterr().err
