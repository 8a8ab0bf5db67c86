"""What every log reader hands over: what a log holds (:class:`LogContents`), its messages as
plain dicts (:class:`LogMessage`), and the one-line :class:`LogError` for a log that cannot be read."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

FOOTPRINT = "footprint"
"""The metadata entry of the recorded robot's outline: JSON [[x, y], ...], metres in the base frame."""


class LogError(Exception):
    """A log that cannot be read, as one line: the file, where in it, what is wrong."""


@dataclass(frozen=True)
class TopicInfo:
    """One topic of a log: its ROS 2 type (``package/msg/Type``), how many messages, whether we can
    decode them (``problem`` says why not)."""

    name: str
    type: str
    count: int
    problem: str = ""


@dataclass
class LogContents:
    """What a log holds. Times are the log's own (nanoseconds); ``cut`` is where a cut-short file
    ends (``None``: whole)."""

    path: str
    format: str
    topics: dict[str, TopicInfo] = field(default_factory=dict)
    start_ns: int = 0
    end_ns: int = 0
    metadata: dict[str, str] = field(default_factory=dict)
    cut: str | None = None

    def footprint(self) -> np.ndarray | None:
        """The recorded robot's outline (K x 2, base frame) from the metadata; None when the log gives
        none, or one that is not a polygon (another recorder's log, or an older one of ours)."""
        try:
            polygon = np.asarray(json.loads(self.metadata[FOOTPRINT]), dtype=float)
        except (KeyError, TypeError, ValueError):
            return None
        return polygon if polygon.ndim == 2 and polygon.shape[1] == 2 and len(polygon) >= 3 else None

    @property
    def duration_s(self) -> float:
        return max(0, self.end_ns - self.start_ns) / 1e9

    @property
    def messages(self) -> int:
        return sum(t.count for t in self.topics.values())

    def types(self) -> dict[str, str]:
        """Topic -> type, for the topics we can decode."""
        return {name: t.type for name, t in self.topics.items() if not t.problem}


@dataclass(frozen=True, slots=True)
class LogMessage:
    """One decoded message: topic, type, log time (ns) and the message as nested dicts."""

    topic: str
    type: str
    log_ns: int
    message: dict[str, Any]


class LogReader(Protocol):
    """What every log format offers."""

    path: Path
    cut: str | None  # where a cut-short file ends, once read to there (None: whole, or not there yet)

    def contents(self) -> LogContents: ...

    def messages(self, topics: Iterable[str]) -> Iterator[LogMessage]: ...

    def close(self) -> None: ...


def plain(value: Any) -> Any:
    """A decoded message (mcap_ros2's slotted objects, rosbags' dataclasses) as nested dicts;
    byte strings and arrays stay as they are."""
    if isinstance(value, (bytes, bytearray, str, int, float, bool)) or value is None:
        return value
    if isinstance(value, list):
        if not value or isinstance(value[0], (int, float, str)):
            return value  # an array of numbers or strings (a covariance, joint names) as it is
        return [plain(v) for v in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value) if not f.name.startswith("__")}
    slots = getattr(type(value), "__slots__", None)
    if slots and hasattr(value, "_type"):  # an mcap_ros2 message
        return {name: plain(getattr(value, name)) for name in slots}
    return value



def first_line(exc: BaseException) -> str:
    """An exception as ``Type: first line of its message``."""
    text = str(exc).strip()
    return f"{type(exc).__name__}: {text.splitlines()[0]}" if text else type(exc).__name__
