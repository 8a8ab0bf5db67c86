"""PTU-D46 ASCII protocol: pure functions, bytes in and values out (no port, no thread, no clock).

Commands are ASCII tokens ended by a space (``PP1000 ``, ``PR ``); a reply is a line ended by CR LF
that starts with ``*`` (success; a query adds its value: ``* 185.1428``) or ``!`` (failure:
``! Illegal argument``). A bare ``!P`` / ``!T`` is the unit's unsolicited "pan/tilt limit hit";
any other line (power-up banner, echoed input before ``ED``) is noise to be ignored. Positions are
integers; resolution is in arc-seconds per position (``PR`` / ``TR``). Facts from
``../shared/PROTOCOLS.md``, checked against the flir_ptu driver.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?")
TOKEN = re.compile(r"([A-Za-z]+)([-+]?\d+(?:\.\d+)?)?")
MAX_LINE = 256  # a longer run of bytes without a line end is noise and is dropped


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


class LineReader:
    """Incremental line splitter: :meth:`feed` any chunks, get back complete stripped lines."""

    def __init__(self) -> None:
        self._buffer = bytearray()
        self.dropped = 0  # bytes dropped because no line end came within MAX_LINE

    def feed(self, data: bytes) -> list[str]:
        self._buffer += data
        lines: list[str] = []
        while True:
            ends = [i for i in (self._buffer.find(b"\r"), self._buffer.find(b"\n")) if i >= 0]
            if not ends:
                break
            end = min(ends)
            raw, self._buffer = bytes(self._buffer[:end]), self._buffer[end + 1 :]
            text = raw.decode("ascii", errors="replace").strip()
            if text:
                lines.append(text)
        if len(self._buffer) > MAX_LINE:
            self.dropped += len(self._buffer)
            self._buffer.clear()
        return lines

    def clear(self) -> None:
        self._buffer.clear()


@dataclass(frozen=True, slots=True)
class Reply:
    """One classified line: ``ok`` (``*``), ``error`` (``! message``), ``limit`` (``!P``/``!T``), ``noise``."""

    kind: str
    text: str
    value: float | None = None

    @property
    def axis(self) -> str | None:
        """``"pan"`` or ``"tilt"`` for a limit line."""
        return {"!P": "pan", "!T": "tilt"}.get(self.text.upper().replace(" ", "")) if self.kind == "limit" else None


def parse_line(line: str) -> Reply:
    """Classify one reply line and pull out a query's number (terse ``* 12`` or verbose text)."""
    text = line.strip()
    if text.startswith("*"):
        match = NUMBER.search(text[1:])
        return Reply("ok", text, float(match.group()) if match else None)
    if text.upper().replace(" ", "") in ("!P", "!T"):
        return Reply("limit", text)
    if text.startswith("!"):
        return Reply("error", text[1:].strip() or "error")
    return Reply("noise", text)


def to_positions(angle: float, resolution: float) -> int:
    """Radians to the nearest position count, for ``resolution`` arc-seconds per position."""
    return int(round(math.degrees(angle) * 3600.0 / resolution))


def to_radians(positions: float, resolution: float) -> float:
    """Position counts (or counts per second) to radians (or rad/s)."""
    return math.radians(positions * resolution / 3600.0)
