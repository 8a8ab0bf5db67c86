"""An MCAP file of ROS 2 messages, written as a run goes.

``mcap_ros2`` encodes the messages (CDR, with the schemas of :mod:`drivers.logs.messages`) and
``mcap`` writes them in zstd-compressed chunks. A chunk is closed when it holds
:data:`CHUNK_BYTES` or when :data:`FLUSH_PERIOD` seconds of the run's clock have passed since the
last one, so a crash (power cut, ``kill -9``) loses at most the last second of the run; what is
on disk reads back without the summary that :meth:`LogWriter.close` adds (the readers say the log
was cut). One writer may be called from the run's thread and a driver's stop path at once: a lock
keeps records whole.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import IO, Any

from mcap.records import Schema
from mcap_ros2.writer import Writer

from drivers.logs.codec import nanoseconds
from drivers.logs.messages import definition

CHUNK_BYTES = 1 << 20  # a chunk is closed when it holds this much (before compression)
FLUSH_PERIOD = 1.0  # s of the run's clock: a chunk is closed at least this often


class LogWriter:
    """Write ROS 2 messages to an MCAP file at ``path`` (created or replaced)."""

    def __init__(self, path: str | Path, *, metadata: dict[str, str] | None = None,
                 chunk_bytes: int = CHUNK_BYTES) -> None:
        self.path = Path(path)
        self._file: IO[bytes] = open(self.path, "wb")  # noqa: SIM115 - closed by close(), written as the run goes
        self._writer = Writer(self._file, chunk_size=chunk_bytes)
        self._schemas: dict[str, Schema] = {}
        self._lock = threading.Lock()
        self._flushed_at = 0.0
        self.messages = 0
        self.closed = False
        if metadata:
            self._writer.add_metadata("bearings", dict(metadata))

    def write(self, topic: str, type_name: str, message: dict[str, Any], seconds: float) -> None:
        """One message on ``topic`` at ``seconds`` of the run's clock (its log and publish time)."""
        with self._lock:
            if self.closed:
                return
            schema = self._schemas.get(type_name)
            if schema is None:
                schema = self._schemas[type_name] = self._writer.register_msgdef(type_name, definition(type_name))
            ns = nanoseconds(seconds)
            self._writer.write_message(topic, schema, message, log_time=ns, publish_time=ns, sequence=self.messages)
            self.messages += 1
            if seconds - self._flushed_at >= FLUSH_PERIOD:
                self._flushed_at = seconds
                inner = getattr(self._writer, "_writer", None)  # mcap's Writer: its flush() closes the chunk
                if inner is not None and hasattr(inner, "flush"):
                    inner.flush()

    def close(self) -> None:
        """Write the summary (the index readers seek with) and close the file; idempotent."""
        if not self._lock.acquire(timeout=2.0):  # a write stuck in another thread: leave the file as it is
            return
        try:
            if self.closed:
                return
            self.closed = True
            try:
                self._writer.finish()
            finally:
                self._file.close()
        finally:
            self._lock.release()

    def size_bytes(self) -> int:
        """The file's size on disk now."""
        return self.path.stat().st_size if self.path.exists() else 0
