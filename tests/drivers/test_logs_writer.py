"""The MCAP writer: a crash loses at most the last second of the run; close() is idempotent."""

from __future__ import annotations

import shutil

from drivers.logs import codec
from drivers.logs import messages as msg
from drivers.logs.reader import open_log
from drivers.logs.writer import LogWriter


def test_a_killed_run_loses_at_most_the_last_second(tmp_path):
    writer = LogWriter(tmp_path / "run.mcap", metadata={"mission": "m"})  # 1 MiB chunks: minutes of flags
    for i in range(25):  # 0.0 to 2.4 s
        writer.write("/robot/stalled", msg.BOOL, codec.bool_message(False), round(0.1 * i, 1))
    shutil.copy(tmp_path / "run.mcap", tmp_path / "killed.mcap")  # what is on disk if the process dies now
    reader = open_log(tmp_path / "killed.mcap")
    times = [m.log_ns for m in reader.messages(["/robot/stalled"])]
    assert times[-1] == 2_000_000_000 and len(times) == 21  # the chunk closed at 2.0 s of the run's clock
    assert reader.contents().cut is not None and reader.contents().metadata == {"mission": "m"}
    writer.close()
    writer.close()
    writer.write("/robot/stalled", msg.BOOL, codec.bool_message(True), 3.0)  # after close: dropped
    whole = open_log(tmp_path / "run.mcap").contents()
    assert whole.cut is None and whole.topics["/robot/stalled"].count == 25 == writer.messages
