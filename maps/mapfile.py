"""Map files: a versioned, checksummed container of named numpy arrays, written atomically.

Every map bearings saves (Landmark-Tree maps, target roadmaps, ...) is one file::

    BEARINGS-MAP\\n                       magic line
    {"kind": "ltmap", "version": 1, ...}\\n  header: one line of JSON (:class:`MapHeader`)
    <payload>                             an uncompressed ``.npz`` of the map's arrays

The header says what the file is (``kind``, ``version``), how long the payload is and its
SHA-256, plus free ``meta`` data (JSON values) the map kind defines. Reading checks all of it
before numpy sees a byte, so a truncated, damaged, foreign or newer file is one clear
:class:`~maps.store.InputError` line, never a numpy traceback. Arrays are loaded with
``allow_pickle=False``: a map file is data and cannot run code. Writing goes through
:func:`maps.store.write_bytes_atomic`, so a crash while saving keeps the previous file whole.

Why this and not pickle or HDF5: pickle executes code on load; HDF5 adds a compiled dependency
for what one ``.npz`` and a JSON line do.
"""

from __future__ import annotations

import io
import json
import math
import os
import zipfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, BinaryIO

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from maps.store import Diagnostic, InputError, checksum, open_regular, read_limited, write_bytes_atomic

MAGIC = b"BEARINGS-MAP\n"
MAX_HEADER_BYTES = 1 << 20  # a header is a few hundred bytes; a longer "line" is not a map file
MAX_MAP_BYTES = 1 << 31  # 2 GiB: far above any map's memory budget
MAX_ARRAYS = 64  # named arrays in one map file (an LT-map has 5, a roadmap a few more)


class MapHeader(BaseModel):
    """The header line of a map file (declared once; ``bearings map info`` prints it)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    kind: str = Field(pattern=r"^[a-z][a-z0-9_]*$", max_length=40, description="what map this is: ltmap, roadmap, ...")
    version: int = Field(ge=1, le=1000, description="format version of that kind")
    payload_bytes: int = Field(ge=0, le=MAX_MAP_BYTES, description="length of the .npz payload [bytes]")
    sha256: str = Field(pattern=r"^[0-9a-f]{64}$", description="SHA-256 of the payload, hex")
    meta: dict[str, Any] = Field(default_factory=dict, description="the map kind's own JSON values")


@dataclass(frozen=True)
class MapFile:
    """What :func:`read_map_file` returns: the header and the arrays of the payload."""

    header: MapHeader
    arrays: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def meta(self) -> dict[str, Any]:
        return self.header.meta


def encode_map(*, kind: str, version: int, arrays: Mapping[str, np.ndarray], meta: Mapping[str, Any] | None = None
               ) -> bytes:
    """The bytes of a map file (what :func:`write_map_file` writes)."""
    buffer = io.BytesIO()
    for name, array in arrays.items():
        if np.asarray(array).dtype == object:
            raise TypeError(f"map array {name!r} has dtype object; map files hold plain numeric arrays only")
    np.savez(buffer, allow_pickle=False, **{name: np.asarray(a) for name, a in arrays.items()})
    payload = buffer.getvalue()
    header = MapHeader(kind=kind, version=version, payload_bytes=len(payload), sha256=checksum(payload),
                       meta=dict(meta or {}))
    line = json.dumps(header.model_dump(), separators=(",", ":"), allow_nan=False).encode("utf-8")
    return MAGIC + line + b"\n" + payload


def write_map_file(path: str | os.PathLike, *, kind: str, version: int, arrays: Mapping[str, np.ndarray],
                   meta: Mapping[str, Any] | None = None) -> None:
    """Save a map atomically: the file holds either the previous map or all of this one."""
    write_bytes_atomic(path, encode_map(kind=kind, version=version, arrays=arrays, meta=meta))


def _bad(file: str, message: str) -> InputError:
    return InputError([Diagnostic(file, 0, 0, message)])


def decode_map(data: bytes, *, file: str, kind: str | None = None, versions: Iterable[int] | None = None) -> MapFile:
    """Check and decode map-file bytes; :class:`InputError` (one line) when they are not a valid map."""
    header, end = _decode_header(data, file=file, kind=kind, versions=versions)
    payload = data[end + 1:]
    if len(payload) != header.payload_bytes:
        what = "truncated" if len(payload) < header.payload_bytes else "has trailing bytes"
        raise _bad(file, f"damaged map file: {what} ({len(payload)} of {header.payload_bytes} payload bytes)")
    if checksum(payload) != header.sha256:
        raise _bad(file, "damaged map file: the checksum does not match its content")
    try:
        _check_members(payload, file)
        with np.load(io.BytesIO(payload), allow_pickle=False) as npz:
            arrays = {name: npz[name] for name in npz.files}
    except (ValueError, OSError, zipfile.BadZipFile) as exc:
        raise _bad(file, f"damaged map file: unreadable arrays ({exc})") from None
    return MapFile(header, arrays)


_ARRAY_HEADERS = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0}


def _check_members(payload: bytes, file: str) -> None:
    """Refuse, before numpy allocates anything, a payload whose arrays are not what they declare:
    a compressed member (bearings stores them plain, so nothing inflates past the file's own
    length), or an array header whose shape needs more bytes than the member holds (a (10^12,)
    array in a few bytes)."""
    with zipfile.ZipFile(io.BytesIO(payload)) as archive:
        members = archive.infolist()
        if len(members) > MAX_ARRAYS:
            raise _bad(file, f"damaged map file: {len(members)} arrays (a map has at most {MAX_ARRAYS})")
        for member in members:
            if member.compress_type != zipfile.ZIP_STORED or member.file_size != member.compress_size:
                raise _bad(file, f"damaged map file: array {member.filename!r} is compressed (map arrays are stored "
                                 "plain)")
            with archive.open(member) as stream:
                version = np.lib.format.read_magic(stream)
                read_header = _ARRAY_HEADERS.get(version)
                if read_header is None:
                    raise _bad(file, f"damaged map file: array {member.filename!r} has .npy format {version}")
                shape, _fortran, dtype = read_header(stream)
                needed = math.prod(shape) * dtype.itemsize
                if needed != member.file_size - stream.tell():
                    raise _bad(file, f"damaged map file: array {member.filename!r} declares {shape} {dtype} "
                                     f"({needed} bytes) in a member of {member.file_size} bytes")


def _decode_header(data: bytes, *, file: str, kind: str | None, versions: Iterable[int] | None
                   ) -> tuple[MapHeader, int]:
    """The checked header of map-file bytes and where its line ends."""

    def bad(message: str) -> InputError:
        return _bad(file, message)

    if not data.startswith(MAGIC):
        raise bad("not a bearings map file (it does not start with BEARINGS-MAP)")
    end = data.find(b"\n", len(MAGIC), len(MAGIC) + MAX_HEADER_BYTES)
    if end < 0:
        raise bad("damaged map file: the header line is missing or too long")
    try:
        header = MapHeader.model_validate(json.loads(data[len(MAGIC):end].decode("utf-8")))
    except (UnicodeDecodeError, json.JSONDecodeError, ValidationError) as exc:
        raise bad(f"damaged map file: unreadable header ({type(exc).__name__})") from None
    if kind is not None and header.kind != kind:
        raise bad(f"this is a {header.kind} map file, not a {kind} map file")
    allowed = tuple(versions) if versions is not None else None
    if allowed is not None and header.version not in allowed:
        newest = max(allowed)
        hint = "written by a newer bearings" if header.version > newest else "an old format no longer read"
        raise bad(f"{header.kind} map format version {header.version} is not supported ({hint}; this version "
                  f"reads {', '.join(map(str, allowed))})")
    return header, end


def read_map_file(path: str | os.PathLike, *, kind: str | None = None, versions: Iterable[int] | None = None
                  ) -> MapFile:
    """Load a map file, checking magic, kind, version, length and checksum before decoding. Reads
    the magic line and header first and then only the payload the header declares (and one byte
    more, to tell trailing bytes): ``/dev/zero`` or a foreign file costs a few bytes, not 2 GiB."""
    name = str(path)
    with open_regular(path) as handle:
        head = handle.read(len(MAGIC))
        if head != MAGIC:
            raise _bad(name, "not a bearings map file (it does not start with BEARINGS-MAP)")
        head += _read_line(handle, MAX_HEADER_BYTES, name)
        header, end = _decode_header(head, file=name, kind=kind, versions=versions)
        payload = read_limited(handle, header.payload_bytes, name)
    return decode_map(head + payload, file=name, kind=kind, versions=versions)


def _read_line(handle: BinaryIO, limit: int, name: str) -> bytes:
    """Bytes up to and including the next newline, at most ``limit`` of them (then: what was read)."""
    try:
        return handle.readline(limit)
    except OSError as exc:
        raise _bad(name, f"cannot read: {exc.strerror}") from None
