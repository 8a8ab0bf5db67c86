"""The one place that reads files named by the user and writes files atomically.

Reading: YAML is parsed with PyYAML's *safe* loader and every mapping and sequence remembers the
line and column of each entry, so validators anywhere can report ``file:line:col: message``.
Writing: a temporary file in the same directory, flushed and fsynced, then renamed over the
target, so a crash never leaves a half-written map, calibration or report. Outputs are checked
before work starts (:func:`output_problem`); the writer keeps a replaced file's permissions,
writes through symbolic links, refuses anything that is not a regular file and never creates
folders silently.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import stat
import tempfile
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import yaml


@dataclass(frozen=True, slots=True)
class Diagnostic:
    """One problem in an input file, located at a 1-based line and column (0: unknown)."""

    file: str
    line: int
    col: int
    message: str

    def __str__(self) -> str:
        if self.line <= 0:
            return f"{self.file}: {self.message}"
        return f"{self.file}:{self.line}:{self.col}: {self.message}"


class InputError(Exception):
    """Invalid user input: one or more located diagnostics, reported together (exit code 2)."""

    def __init__(self, diagnostics: Iterable[Diagnostic]) -> None:
        self.diagnostics = list(diagnostics)
        super().__init__("\n".join(str(d) for d in self.diagnostics))


@dataclass(frozen=True, slots=True)
class Mark:
    """Where a YAML value starts: 1-based line and column."""

    line: int
    col: int


class YamlMap(dict):
    """A dict that remembers where it and each of its keys and values start in the file."""

    mark: Mark
    key_marks: dict[Any, Mark]
    value_marks: dict[Any, Mark]

    def mark_of(self, key: Any) -> Mark:
        return self.key_marks.get(key, self.mark)

    def value_mark_of(self, key: Any) -> Mark:
        return self.value_marks.get(key, self.mark_of(key))


class YamlList(list):
    """A list that remembers where it and each of its items start in the file."""

    mark: Mark
    item_marks: list[Mark]

    def mark_of(self, index: int) -> Mark:
        return self.item_marks[index] if 0 <= index < len(self.item_marks) else self.mark


def mark_of(value: Any, default: Mark | None = None) -> Mark:
    """The start of a located YAML value (maps and lists carry one; scalars do not)."""
    return getattr(value, "mark", None) or default or Mark(0, 0)


_BASE_LOADER: type = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml parses ~10x faster than pure Python


class _SafeLoader(_BASE_LOADER):
    """PyYAML's safe loader (libyaml's parser when the wheel has it, as PyPI's do), plus YAML 1.2
    floats: ``1e-3`` and ``1.0e9`` are numbers, not text."""


YAML12_FLOAT = re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$")
"""Numbers YAML 1.2 reads as floats and PyYAML's YAML 1.1 as text (``1e-3``, ``1.0e9``)."""

_SafeLoader.add_implicit_resolver("tag:yaml.org,2002:float", YAML12_FLOAT, list("-+0123456789"))


class _Dumper(yaml.SafeDumper):
    """PyYAML's safe dumper, quoting text that YAML 1.2 reads as a number, so that what is written
    reads back (with :func:`parse_yaml`) as the same values."""


_Dumper.add_implicit_resolver("tag:yaml.org,2002:float", YAML12_FLOAT, list("-+0123456789"))


def _mark(node: yaml.Node) -> Mark:
    return Mark(node.start_mark.line + 1, node.start_mark.column + 1)


_PLAIN_TAGS = ("tag:yaml.org,2002:map", "tag:yaml.org,2002:seq")
MAX_NODES = 200_000  # values beyond what the text itself can hold: guards against alias bombs ("billion laughs")
MAX_FILE_BYTES = 16 * 1024 * 1024  # a mission, world, profile or calibration file is kilobytes, not gigabytes


class _Budget:
    """How many values a document may expand to: its length (a value takes at least two characters
    of text) plus a margin; only aliases expanding over and over can exceed it."""

    def __init__(self, file: str, text_length: int) -> None:
        self.total = MAX_NODES + text_length // 2
        self.left = self.total
        self.file = file

    def spend(self, node: yaml.Node) -> None:
        self.left -= 1
        if self.left < 0:
            raise InputError([Diagnostic(self.file, *_pos(node), f"more than {self.total} YAML values in "
                                         "the document: an alias expands too often")])


def _construct(node: yaml.Node, loader: _SafeLoader, file: str, budget: _Budget) -> Any:
    budget.spend(node)
    if isinstance(node, (yaml.MappingNode, yaml.SequenceNode)) and node.tag not in _PLAIN_TAGS:
        raise InputError([Diagnostic(file, *_pos(node), f"malformed YAML: unsupported tag {node.tag!r} "
                                     "(files are data: only plain YAML is accepted)")])
    if isinstance(node, yaml.MappingNode):
        loader.flatten_mapping(node)  # resolves YAML merge keys (<<)
        out = YamlMap()
        out.mark, out.key_marks, out.value_marks = _mark(node), {}, {}
        for key_node, value_node in node.value:
            key = _construct(key_node, loader, file, budget)
            if isinstance(key, (YamlMap, YamlList)):
                raise InputError([Diagnostic(file, *_pos(key_node), "a mapping key must be a plain value")])
            if key in out:
                raise InputError([Diagnostic(file, *_pos(key_node), f"duplicate key {key!r}")])
            out[key] = _construct(value_node, loader, file, budget)
            out.key_marks[key] = _mark(key_node)
            out.value_marks[key] = _mark(value_node)
        return out
    if isinstance(node, yaml.SequenceNode):
        items = YamlList(_construct(child, loader, file, budget) for child in node.value)
        items.mark, items.item_marks = _mark(node), [_mark(child) for child in node.value]
        return items
    try:
        return loader.construct_object(node, deep=True)
    except (ValueError, TypeError, OverflowError) as exc:  # an explicit tag on a value it cannot hold
        text = node.value if len(node.value) <= 40 else f"{node.value[:20]}...{node.value[-8:]}"
        length = "" if text is node.value else f", {len(node.value)} characters"
        raise InputError([Diagnostic(file, *_pos(node), f"malformed YAML: {text!r} cannot be read as "
                                     f"{node.tag.rsplit(':', 1)[-1]} ({type(exc).__name__}{length})")]) from None


def _pos(node: yaml.Node) -> tuple[int, int]:
    return node.start_mark.line + 1, node.start_mark.column + 1


def parse_yaml(text: str, *, file: str = "<string>") -> Any:
    """Parse YAML text safely into located values; raise :class:`InputError` with the position."""
    loader = None
    try:
        loader = _SafeLoader(text)
        node = loader.get_single_node()
        if node is None:
            raise InputError([Diagnostic(file, 1, 1, "the file is empty")])
        return _construct(node, loader, file, _Budget(file, len(text)))
    except yaml.reader.ReaderError as exc:
        line = text.count("\n", 0, exc.position) + 1
        col = exc.position - (text.rfind("\n", 0, exc.position) + 1) + 1
        raise InputError([Diagnostic(file, line, col, f"character #x{exc.character:04x} is not allowed in "
                                     "YAML")]) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (0, 0)
        problem = exc.problem or exc.context or "malformed YAML"
        raise InputError([Diagnostic(file, line, col, f"malformed YAML: {problem}")]) from None
    except yaml.YAMLError as exc:
        raise InputError([Diagnostic(file, 0, 0, f"malformed YAML: {exc}")]) from None
    except RecursionError:
        raise InputError([Diagnostic(file, 0, 0, "malformed YAML: nested too deeply")]) from None
    finally:
        if loader is not None:
            loader.dispose()


def open_regular(path: str | os.PathLike) -> BinaryIO:
    """A regular file named by the user, open for reading; :class:`InputError` in one line for
    anything else. Opened without blocking and checked before a byte is read: a FIFO would block
    until someone writes to it, ``/dev/zero`` never ends, a directory is not a file."""
    name = str(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise InputError([Diagnostic(name, 0, 0, "no such file")]) from None
    except IsADirectoryError:
        raise InputError([Diagnostic(name, 0, 0, "is a directory, not a file")]) from None
    except OSError as exc:
        raise InputError([Diagnostic(name, 0, 0, f"cannot read: {exc.strerror}")]) from None
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        what = "a directory" if stat.S_ISDIR(mode) else "a pipe" if stat.S_ISFIFO(mode) else "a device or socket"
        raise InputError([Diagnostic(name, 0, 0, f"is {what}, not a regular file")])
    os.set_blocking(fd, True)
    return os.fdopen(fd, "rb")


def read_bytes(path: str | os.PathLike, *, limit: int, what: str) -> bytes:
    """The bytes of a regular file named by the user (:func:`open_regular`), at most ``limit`` of
    them (a 300 MB line must not fill memory); a clear :class:`InputError` on any failure.
    ``what`` names the kind of file in the too-large message."""
    with open_regular(path) as handle:
        data = read_limited(handle, limit, str(path))
    if len(data) > limit:
        raise InputError([Diagnostic(str(path), 0, 0, f"larger than {limit // (1024 * 1024)} MB: not {what}")])
    return data


def read_limited(handle: BinaryIO, limit: int, name: str) -> bytes:
    """Up to ``limit + 1`` bytes from ``handle`` (one more than allowed tells a file too large)."""
    try:
        return handle.read(limit + 1)
    except OSError as exc:
        raise InputError([Diagnostic(name, 0, 0, f"cannot read: {exc.strerror}")]) from None


def read_text(path: str | os.PathLike) -> str:
    """Read a UTF-8 text file named by the user; clear :class:`InputError` on any failure."""
    name = str(path)
    data = read_bytes(path, limit=MAX_FILE_BYTES, what="a mission, world or profile file")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        col = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise InputError([Diagnostic(name, line, col, "the file is not valid UTF-8 text")]) from None


def load_yaml(path: str | os.PathLike) -> Any:
    """Read and safely parse a YAML file named by the user, keeping positions for diagnostics."""
    text = read_text(path)
    if not text.strip():
        raise InputError([Diagnostic(str(path), 1, 1, "the file is empty")])
    return parse_yaml(text, file=str(path))


def output_problem(path: str | os.PathLike) -> str | None:
    """Why ``path`` cannot be written as an output file, or None (checked before work starts).

    A missing folder, a folder or device in the way, an unwritable folder: each is one line.
    Symbolic links are written through (the file they point to is replaced atomically).
    """
    target = Path(os.path.realpath(path))
    folder = target.parent
    if target.exists() and not target.is_file():
        return "is a directory" if target.is_dir() else "is not a regular file (a device, socket or pipe?)"
    if not folder.is_dir():
        return f"the folder {folder} does not exist"
    if not os.access(folder, os.W_OK | os.X_OK):
        return f"the folder {folder} is not writable"
    if target.exists() and not os.access(target, os.W_OK):
        return "is not writable"
    return None


@dataclass(frozen=True, slots=True)
class OutputFolders:
    """Where a mission's files go: relative paths resolve against ``base``, and a file the mission
    writes must lie inside one of ``roots`` (its own folder, the ``--output-dir``) once every
    symbolic link on the way is followed, so neither ``/any/where`` nor ``..`` nor a link inside
    the folder that points out can make it write elsewhere. Both are absolute, links resolved."""

    base: Path
    roots: tuple[Path, ...]

    @classmethod
    def of(cls, base: str | os.PathLike, *roots: str | os.PathLike) -> OutputFolders:
        real = Path(os.path.realpath(base))
        return cls(real, tuple(dict.fromkeys([real, *(Path(os.path.realpath(r)) for r in roots)])))

    def resolve(self, text: str) -> Path:
        """The file a port's text names: absolute, every existing symbolic link followed."""
        return Path(os.path.realpath(self.base / os.fspath(text)))

    def outside(self, text: str) -> str | None:
        """Why a file the mission would write at ``text`` is refused (outside every root), or None."""
        target = self.resolve(text)
        if any(target == root or root in target.parents for root in self.roots):
            return None
        where = " or ".join(str(root) for root in self.roots)
        via = f" (through a symbolic link: {target})" if target != Path(os.path.abspath(self.base / text)) else ""
        return f"{text!r} is outside the mission's output folder {where}{via}: give --output-dir to write elsewhere"


def check_not_redirected(path: str | os.PathLike) -> None:
    """``OSError`` when a file a mission writes is now reached through a symbolic link: the loader
    gave the node an absolute path with every link resolved (:class:`OutputFolders`), so a link
    there now (or in an absolute path's folders) was put in its way since and must not take the
    write out of the output folder."""
    text = os.fspath(path)
    folder = os.path.dirname(text)
    moved = os.path.isabs(text) and os.path.realpath(folder) != os.path.normpath(folder)
    if os.path.islink(text) or moved:
        raise OSError(f"{text} is reached through a symbolic link (to {os.path.realpath(text)}); a mission's "
                      "file is not written through one")


def write_bytes_atomic(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` so that ``path`` holds either the old content or all of the new one.

    The folder must exist (nothing is created silently); a symbolic link is written through; a
    file that is replaced keeps its permissions, a new one gets the umask's; anything but a
    regular file in the way (a directory, ``/dev/full``) is refused with ``IsADirectoryError``
    or ``OSError`` before anything is written.
    """
    target = Path(os.path.realpath(path))
    if target.exists() and not target.is_file():
        raise (IsADirectoryError if target.is_dir() else OSError)(f"{path}: not a regular file; not replaced")
    mode = _mode_for(target)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as handle:
            os.fchmod(handle.fileno(), mode)
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    try:  # make the rename itself durable
        dir_fd = os.open(target.parent, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(dir_fd)
    except OSError:
        pass
    finally:
        os.close(dir_fd)


def _mode_for(target: Path) -> int:
    """The permissions of the file being replaced, or those the umask gives a new file."""
    try:
        return target.stat().st_mode & 0o7777
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Atomic UTF-8 text write (see :func:`write_bytes_atomic`)."""
    write_bytes_atomic(path, text.encode("utf-8"))


def dump_yaml(data: Any, *, width: int = 110) -> str:
    """Plain data as block-style YAML text that :func:`parse_yaml` reads back to the same values."""
    return yaml.dump(_plain(data), Dumper=_Dumper, sort_keys=False, default_flow_style=None, allow_unicode=True,
                     width=width)


def write_yaml(path: str | os.PathLike, data: Any, *, header: str = "") -> None:
    """Atomically write plain data as block-style YAML, with an optional ``# header`` comment."""
    body = dump_yaml(data)
    comment = "".join(f"# {line}\n" for line in header.splitlines())
    write_text_atomic(path, comment + body)


def finite(data: Any) -> Any:
    """``data`` with every non-finite float (inf, nan) replaced by None, in mappings and lists."""
    if isinstance(data, float):
        return data if math.isfinite(data) else None
    if isinstance(data, dict):
        return {key: finite(value) for key, value in data.items()}
    if isinstance(data, (list, tuple)):
        return [finite(value) for value in data]
    return data


def json_text(data: Any, **options: Any) -> str:
    """Strict JSON (RFC 8259: no ``Infinity`` or ``NaN``, which other readers refuse): non-finite
    numbers become ``null``, as the docs promise for every JSON file and line bearings writes."""
    return json.dumps(finite(data), allow_nan=False, **options)


def write_json(path: str | os.PathLike, data: Any) -> None:
    """Atomically write strict JSON (reports, summaries), indented for people."""
    write_text_atomic(path, json_text(data, indent=2, sort_keys=False) + "\n")


def checksum(payload: bytes) -> str:
    """The checksum stored in versioned map files (SHA-256, hex)."""
    return hashlib.sha256(payload).hexdigest()


def _plain(value: Any) -> Any:
    """Located containers and numpy scalars to plain Python for dumping."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item") and callable(value.item):  # numpy scalar
        return value.item()
    if hasattr(value, "tolist"):
        return value.tolist()
    return value
