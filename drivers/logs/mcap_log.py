"""An MCAP file of ROS 2 (CDR) messages, read with ``mcap`` and its ROS 2 decoder.

An indexed file (one a run closed) is read chunk by chunk in log-time order through its index;
a file without an index (cut short: the run was killed before it closed the file) is read record
by record in file order, the order a run writes it in, up to the cut, and ``cut`` says where that
is. Either way memory holds one chunk at a time, whatever the file's size. A damaged file (a
chunk whose CRC or compression fails, a record that does not parse) is one :class:`LogError`
line with the byte offset.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import IO, Any

from mcap.exceptions import EndOfFile
from mcap.reader import SeekingReader
from mcap.records import Channel, Message, Metadata, Schema
from mcap.stream_reader import StreamReader
from mcap_ros2.decoder import DecoderFactory

from drivers.logs.messages import type_name
from drivers.logs.source import LogContents, LogError, LogMessage, TopicInfo, first_line, plain


class McapLog:
    """An MCAP file of ROS 2 (CDR) messages."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.size = path.stat().st_size
        self.cut: str | None = None  # where a cut-short file ends, once read to there
        self._file: IO[bytes] = open(path, "rb")  # noqa: SIM115 - closed by close()
        try:
            self._seeking = SeekingReader(self._file, validate_crcs=True, record_size_limit=self.size)
        except Exception as exc:  # noqa: BLE001 - the magic was checked; anything else is damage
            self._file.close()
            raise LogError(f"{path}: at byte 0: damaged: {first_line(exc)}") from None
        self._decoders = DecoderFactory()
        self._summary: Any = None
        self._summary_read = False
        self._contents: LogContents | None = None

    def close(self) -> None:
        self._file.close()

    # -- what it holds -------------------------------------------------------------------------------
    def summary(self) -> Any:
        """The file's index (None when it has none: cut short, or written without one)."""
        if not self._summary_read:
            self._summary_read = True
            try:
                self._summary = self._seeking.get_summary()
            except Exception:  # noqa: BLE001 - no readable footer: the file is read without its index
                self._summary = None
        return self._summary

    def contents(self) -> LogContents:
        if self._contents is None:
            summary = self.summary()
            self._contents = self._indexed(summary) if summary is not None and summary.statistics else self._scan()
        return self._contents

    def _indexed(self, summary: Any) -> LogContents:
        stats = summary.statistics
        contents = LogContents(str(self.path), "mcap", start_ns=stats.message_start_time,
                               end_ns=stats.message_end_time, metadata=self._metadata())
        for channel_id, channel in sorted(summary.channels.items()):
            schema = summary.schemas.get(channel.schema_id)
            contents.topics[channel.topic] = _topic(channel, schema, stats.channel_message_counts.get(channel_id, 0))
        return contents

    def _metadata(self) -> dict[str, str]:
        try:
            for record in self._seeking.iter_metadata():
                if record.name == "bearings":
                    return dict(record.metadata)
        except Exception:  # noqa: BLE001 - metadata is a courtesy: a log without it still replays
            pass
        return {}

    def _scan(self) -> LogContents:
        """Every record in file order, counting messages per topic (a file without an index)."""
        contents = LogContents(str(self.path), "mcap")
        counts: dict[int, int] = {}
        declared = _Declared()
        first, last = None, None
        for record in self._records():
            if declared.note(record):
                continue
            if isinstance(record, Message):
                counts[record.channel_id] = counts.get(record.channel_id, 0) + 1
                first = record.log_time if first is None else min(first, record.log_time)
                last = record.log_time if last is None else max(last, record.log_time)
            elif isinstance(record, Metadata) and record.name == "bearings":
                contents.metadata = dict(record.metadata)
        contents.start_ns, contents.end_ns = first or 0, last or 0
        for channel_id, channel in sorted(declared.channels.items()):
            contents.topics[channel.topic] = _topic(channel, declared.schemas.get(channel.schema_id),
                                                    counts.get(channel_id, 0))
        contents.cut = self.cut
        return contents

    # -- messages --------------------------------------------------------------------------------------
    def messages(self, topics: Iterable[str]) -> Iterator[LogMessage]:
        wanted = set(topics)
        summary = self.summary()
        decoders: dict[int, Callable[[bytes], Any] | None] = {}
        if summary is not None and summary.chunk_indexes:
            source = self._indexed_messages(wanted)
        else:
            source = self._unindexed_messages(wanted)
        for schema, channel, message in source:
            if channel.id not in decoders:
                decoders[channel.id] = self._decoder(channel, schema)
            decode = decoders[channel.id]
            if decode is None:
                continue
            try:
                decoded = plain(decode(message.data))
            except Exception as exc:  # noqa: BLE001 - a bad message is one located line
                raise LogError(f"{self.path}: {channel.topic} at {message.log_time / 1e9:.3f} s: cannot decode "
                               f"{schema.name if schema else 'a message without schema'}: {first_line(exc)}") from None
            yield LogMessage(channel.topic, type_name(schema.name), message.log_time, decoded)

    def _decoder(self, channel: Any, schema: Any) -> Callable[[bytes], Any] | None:
        try:
            return self._decoders.decoder_for(channel.message_encoding, schema)
        except Exception as exc:  # noqa: BLE001 - a schema that does not parse
            raise LogError(f"{self.path}: {channel.topic}: its schema {schema.name if schema else ''!r} does not "
                           f"parse: {first_line(exc)}") from None

    def _indexed_messages(self, wanted: set[str]) -> Iterator[tuple[Any, Any, Any]]:
        try:
            yield from self._seeking.iter_messages(topics=wanted, log_time_order=True)
        except Exception as exc:  # noqa: BLE001 - a damaged chunk is one located line
            raise LogError(f"{self.path}: at byte {self._file.tell()}: damaged: {first_line(exc)}") from None

    def _unindexed_messages(self, wanted: set[str]) -> Iterator[tuple[Any, Any, Any]]:
        declared = _Declared()
        for record in self._records():
            if declared.note(record):
                continue
            if isinstance(record, Message):
                channel = declared.channels.get(record.channel_id)
                if channel is None:
                    raise LogError(f"{self.path}: at byte {self._file.tell()}: a message on channel "
                                   f"{record.channel_id}, which no record declared")
                if channel.topic in wanted:
                    yield declared.schemas.get(channel.schema_id), channel, record

    def _records(self) -> Iterator[Any]:
        """The file's records in order; at a cut, stop and say where (``cut``); damage is a LogError."""
        self._file.seek(0)
        reader = StreamReader(self._file, validate_crcs=True, record_size_limit=self.size)
        try:
            yield from reader.records
        except (EndOfFile, struct.error, EOFError):
            self.cut = f"cut at byte {self._file.tell()} of {self.size} (the run did not close the file)"
        except Exception as exc:  # noqa: BLE001 - anything else the library raises is damage
            where = self._file.tell()
            if where >= self.size:
                self.cut = f"cut at byte {where} of {self.size} (the run did not close the file)"
                return
            raise LogError(f"{self.path}: at byte {where}: damaged: {first_line(exc)}") from None


class _Declared:
    """The schemas and channels a file has declared so far, read record by record in file order."""

    def __init__(self) -> None:
        self.schemas: dict[int, Any] = {}
        self.channels: dict[int, Any] = {}

    def note(self, record: Any) -> bool:
        """Keep a schema or channel record (True); any other record is the caller's (False)."""
        if isinstance(record, Schema):
            self.schemas[record.id] = record
        elif isinstance(record, Channel):
            self.channels[record.id] = record
        else:
            return False
        return True


def _topic(channel: Any, schema: Any, count: int) -> TopicInfo:
    if schema is None:
        return TopicInfo(channel.topic, "", count, "no schema")
    if channel.message_encoding != "cdr" or schema.encoding != "ros2msg":
        return TopicInfo(channel.topic, schema.name, count,
                         f"{channel.message_encoding} messages with a {schema.encoding} schema: we read ROS 2 (cdr)")
    return TopicInfo(channel.topic, type_name(schema.name), count)


