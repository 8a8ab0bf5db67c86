"""ROS bags through ``rosbags`` (no ROS installation): a ROS 2 bag folder (``metadata.yaml`` with
sqlite3 or MCAP storage) or a ROS 1 ``.bag`` file, streamed in time order.

A bag's own message definitions are used where it has them; a bag without any (older ROS 2
sqlite3 bags) is read with the ROS 2 Humble definitions, which cover ``sensor_msgs``,
``nav_msgs``, ``geometry_msgs``, ``std_msgs`` and ``tf2_msgs``. A topic whose type neither knows
is listed with that problem and never read.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from drivers.logs.messages import type_name
from drivers.logs.source import LogContents, LogError, LogMessage, TopicInfo, first_line, plain


class BagLog:
    """A ROS 2 bag folder or a ROS 1 bag file."""

    def __init__(self, path: Path) -> None:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore

        self.path = path
        if path.is_dir() and not (path / "metadata.yaml").exists():
            raise LogError(f"{path}: a folder without metadata.yaml is not a ROS 2 bag")
        try:
            self._reader = AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
            self._reader.open()
        except Exception as exc:  # noqa: BLE001 - whatever rosbags says about a bag it cannot open, in one line
            raise LogError(f"{path}: not a bag we can read: {first_line(exc)}") from None
        self.cut: str | None = None
        self._contents: LogContents | None = None

    def close(self) -> None:
        if self._reader.stack is not None:
            self._reader.close()

    def contents(self) -> LogContents:
        if self._contents is None:
            reader = self._reader
            storage = "ROS 1 bag" if not reader.is2 else f"ROS 2 bag ({self._storage()})"
            contents = LogContents(str(self.path), storage, start_ns=reader.start_time if reader.connections else 0,
                                   end_ns=reader.end_time if reader.connections else 0)
            known = reader.typestore.fielddefs
            for connection in reader.connections:
                previous = contents.topics.get(connection.topic)
                count = connection.msgcount + (previous.count if previous else 0)
                problem = "" if connection.msgtype in known else "unknown type (no definition in the bag or ROS 2)"
                contents.topics[connection.topic] = TopicInfo(connection.topic, type_name(connection.msgtype), count,
                                                              problem)
            self._contents = contents
        return self._contents

    def _storage(self) -> str:
        files = [p.suffix for p in self.path.iterdir()] if self.path.is_dir() else []
        return "mcap" if ".mcap" in files else "sqlite3" if ".db3" in files else "storage"

    def messages(self, topics: Iterable[str]) -> Iterator[LogMessage]:
        wanted = set(topics)
        reader = self._reader
        known = reader.typestore.fielddefs
        connections = [c for c in reader.connections if c.topic in wanted and c.msgtype in known]
        if not connections:
            return
        stream: Iterator[tuple[Any, int, bytes]] = iter(reader.messages(connections=connections))
        while True:
            try:
                connection, log_ns, raw = next(stream)
            except StopIteration:
                return
            except Exception as exc:  # noqa: BLE001 - a damaged bag is one located line
                raise LogError(f"{self.path}: damaged: {first_line(exc)}") from None
            try:
                message = plain(reader.deserialize(raw, connection.msgtype))
            except Exception as exc:  # noqa: BLE001 - a message that does not decode
                raise LogError(f"{self.path}: {connection.topic} at {log_ns / 1e9:.3f} s: cannot decode "
                               f"{connection.msgtype}: {first_line(exc)}") from None
            yield LogMessage(connection.topic, type_name(connection.msgtype), int(log_ns), message)
