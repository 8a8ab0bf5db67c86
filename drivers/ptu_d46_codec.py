"""PTU-D46 ASCII protocol: pure functions, bytes in and values out (no port, no thread, no clock).

Commands are ASCII tokens ended by a space (``PP1000 ``, ``PR ``). What the unit sends is a stream
of messages, each starting with ``*`` (success; a query adds its value: ``* 185.1428``) or ``!``
(failure: ``! Illegal argument``; ``!P`` / ``!T``: a pan / tilt limit was hit). Messages need not
be on lines of their own: a unit that resets and homes writes ``!T!T!P!P*`` in one go (limit hits
while it finds its limits, then ``*`` when it is done), so :class:`MessageReader` splits the
stream at the markers, as ARIA's ``ArDPPTU::readPacket`` does, not at line ends. Text outside a
message (power-up banner, echoed input before ``ED``) is noise. Positions are integers;
resolution is in arc-seconds per position (``PR`` / ``TR``). The grammar and its sources are in
``docs/protocols.md``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?")
TOKEN = re.compile(r"([A-Za-z]+)([-+]?\d+(?:\.\d+)?)?")
MAX_MESSAGE = 256  # a longer message is noise and is dropped
LIMIT_AXES = {"!P": "pan", "!T": "tilt"}


def encode(command: str, value: int | None = None) -> bytes:
    """One command with an optional integer argument, ended by a space: ``encode("PP", -90)``."""
    if not command.isalpha():
        raise ValueError(f"PTU command {command!r} must be letters only")
    return f"{command.upper()}{'' if value is None else int(value)} ".encode("ascii")


def split_commands(data: str) -> list[tuple[str, float | None]]:
    """``"pp100 TP  ps"`` -> ``[("PP", 100), ("TP", None), ("PS", None)]`` (the emulator's side).

    Tokens are separated by spaces or line ends; a token that is not letters + optional number is
    returned as ``("?" + token, None)`` so the caller can answer with an error.
    """
    out: list[tuple[str, float | None]] = []
    for token in data.split():
        match = TOKEN.fullmatch(token)
        if match is None:
            out.append(("?" + token, None))
            continue
        number = match.group(2)
        out.append((match.group(1).upper(), float(number) if number is not None else None))
    return out


@dataclass(frozen=True, slots=True)
class Reply:
    """One message: ``ok`` (``*``), ``error`` (``! message``), ``limit`` (``!P``/``!T``), ``homed``
    (the ``*`` that ends a reset: it follows limit hits on both axes), or ``noise``."""

    kind: str
    text: str
    value: float | None = None

    @property
    def axis(self) -> str | None:
        """``"pan"`` or ``"tilt"`` for a limit message."""
        return LIMIT_AXES.get(self.text.upper().replace(" ", "")) if self.kind == "limit" else None


def parse_message(text: str) -> Reply:
    """Classify one complete message and pull out a query's number (terse ``* 12`` or verbose text)."""
    text = text.strip()
    if text.startswith("*"):
        match = NUMBER.search(text[1:])
        return Reply("ok", text, float(match.group()) if match else None)
    if text.upper().replace(" ", "") in LIMIT_AXES:
        return Reply("limit", text)
    if text.startswith("!"):
        return Reply("error", text[1:].strip() or "error")
    return Reply("noise", text)


class MessageReader:
    """Incremental splitter of the unit's output: :meth:`feed` any chunks, get back :class:`Reply`.

    A message starts at ``*`` (always, even inside another one) or at ``!`` (unless it is inside the
    text of a ``* ...`` / ``! ...`` message), and ends at a line end or where the next one starts;
    ``!P`` / ``!T`` end at their letter. Limit hits on both axes followed by a bare ``*`` with no
    other message between them are a reset that finished: that ``*`` is ``homed``, not an answer.
    Its ``*`` has no line end after it: :meth:`idle` (nothing arrived for a while) completes it.
    """

    def __init__(self) -> None:
        self._text: str | None = None  # the message being read, from its marker; None between messages
        self._limit_axes: set[str] = set()  # axes of the limit hits since the last other message
        self.noise = 0  # characters outside any message (banner, echo) and over-long messages

    def feed(self, data: bytes) -> list[Reply]:
        out: list[Reply] = []
        for char in data.decode("ascii", errors="replace"):
            self._take(char, out)
        return out

    def idle(self) -> list[Reply]:
        """Nothing more arrived: a bare ``*`` after limit hits (the end of a reset) is complete."""
        out: list[Reply] = []
        if self._text == "*" and self._limit_axes:
            self._finish(out)
        return out

    def clear(self) -> None:
        """Drop a half-received message (a late reply cut by a new command), keep the limit hits seen."""
        if self._text is not None:
            self.noise += len(self._text)
        self._text = None

    def reset(self) -> None:
        self.clear()
        self._limit_axes.clear()

    def _take(self, char: str, out: list[Reply]) -> None:
        text = self._text
        if char in "\r\n":
            if text is not None:
                self._finish(out)
            return
        if char == "*" or (char == "!" and not (text is not None and text[1:2] == " ")):
            if text is not None:
                self._finish(out)
            self._text = char
            return
        if text is None:
            self.noise += 1
            return
        self._text = text + char
        if text == "!" and char.upper() in "PT":
            self._finish(out)  # "!P" / "!T" are complete at their letter
        elif len(self._text) > MAX_MESSAGE:
            self.clear()

    def _finish(self, out: list[Reply]) -> None:
        reply = parse_message(self._text or "")
        self._text = None
        if reply.kind == "limit":
            self._limit_axes.add(reply.axis or "")
        else:
            if reply.kind == "ok" and reply.text == "*" and self._limit_axes >= {"pan", "tilt"}:
                reply = Reply("homed", "*")
            self._limit_axes.clear()
        out.append(reply)


def to_positions(angle: float, resolution: float) -> int:
    """Radians to the nearest position count, for ``resolution`` arc-seconds per position."""
    return int(round(math.degrees(angle) * 3600.0 / resolution))


def to_radians(positions: float, resolution: float) -> float:
    """Position counts (or counts per second) to radians (or rad/s)."""
    return math.radians(positions * resolution / 3600.0)
