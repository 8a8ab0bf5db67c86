"""Open a log: an MCAP file (:mod:`drivers.logs.mcap_log`), a ROS 2 bag folder or a ROS 1 bag
(:mod:`drivers.logs.bags`), each streamed in log-time order and never loaded whole.

Every reader says what the log holds (``contents()``: topics, types, counts, times; from the
index when the file has one) and streams the messages of the topics asked for as plain dicts,
decoded one at a time. A log that cannot be read is one :class:`~drivers.logs.source.LogError`
line naming the file and where in it, never a traceback.
"""

from __future__ import annotations

import os
from pathlib import Path

from drivers.logs.bags import BagLog
from drivers.logs.mcap_log import McapLog
from drivers.logs.source import LogError, LogReader

MCAP_MAGIC = b"\x89MCAP0\r\n"


def open_log(path: str | Path) -> LogReader:
    """The reader for ``path``: an MCAP file, a ROS 2 bag folder (``metadata.yaml`` and its
    storage files, sqlite3 or MCAP) or a ROS 1 ``.bag``. :class:`LogError` when it is none of them."""
    path = Path(path)
    if not path.exists():
        raise LogError(f"{path}: no such file or folder")
    if path.is_dir() or path.suffix == ".bag":
        return BagLog(path)
    try:
        with open(path, "rb") as f:
            start = f.read(16)
    except OSError as exc:
        raise LogError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if not start.startswith(MCAP_MAGIC):
        if start.startswith(b"SQLite format"):
            raise LogError(f"{path}: a ROS 2 bag's storage file: open its folder (with metadata.yaml) instead")
        raise LogError(f"{path}: not an MCAP file, a ROS 2 bag folder or a ROS 1 .bag (it starts with {start[:8]!r})")
    return McapLog(path)


def file_size(path: str | Path) -> int:
    """Bytes on disk of a log file, or of every file of a bag folder."""
    path = Path(path)
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return os.path.getsize(path)
