"""Helpers for the sensor-log tests: small logs written the way a run writes them."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

from drivers.logs.writer import LogWriter


def write_log(path: Path, messages: Iterable[tuple[str, str, dict[str, Any], float]], *,
              chunk_bytes: int = 1 << 20, close: bool = True) -> Path:
    """An MCAP file of (topic, type, message, seconds) rows, closed (indexed) unless ``close`` is False."""
    writer = LogWriter(path, metadata={"mission": "test"}, chunk_bytes=chunk_bytes)
    for topic, type_name, message, seconds in messages:
        writer.write(topic, type_name, message, seconds)
    if close:
        writer.close()
    else:
        writer._writer._writer.flush()  # what a killed run leaves: chunks on disk, no summary
        writer._file.flush()
    return path
