"""Unbounded work from small files (issue 22, item 5): a map file's declared shapes and stored sizes
are checked before numpy allocates, only what the header declares is read, non-regular files are
refused before a byte is read, and pruning a tall tree takes one pass per quiet stretch of levels."""

from __future__ import annotations

import io
import json
import os
import zipfile

import numpy as np
import pytest

import maps.mapfile
from maps.ltmap.arrays import IDS
from maps.ltmap.file import load_ltmap, save_ltmap
from maps.ltmap.tree import LandmarkTree
from maps.mapfile import MAGIC, decode_map, encode_map, read_map_file
from maps.store import InputError, checksum
from missions.cli import main


def _container(payload: bytes, kind: str = "ltmap") -> bytes:
    """A map file around any payload, with a correct length and checksum (the hostile part is inside)."""
    header = {"kind": kind, "version": 1, "payload_bytes": len(payload), "sha256": checksum(payload), "meta": {}}
    return MAGIC + json.dumps(header).encode() + b"\n" + payload


def _npy_header(shape: tuple[int, ...], dtype: str = "<f8") -> bytes:
    stream = io.BytesIO()
    np.lib.format.write_array_header_1_0(stream, {"descr": dtype, "fortran_order": False, "shape": shape})
    return stream.getvalue()


def _zip(members: dict[str, bytes], compression: int = zipfile.ZIP_STORED) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=compression) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return buffer.getvalue()


def _message(data: bytes) -> str:
    with pytest.raises(InputError) as info:
        decode_map(data, file="m.ltmap")
    [diagnostic] = info.value.diagnostics
    return str(diagnostic)


def test_an_array_declaring_a_huge_shape_is_refused_before_anything_is_allocated():
    payload = _zip({"ids.npy": _npy_header((10**12,)) + b"\0" * 64})
    message = _message(_container(payload))
    assert message == ("m.ltmap: damaged map file: array 'ids.npy' declares (1000000000000,) float64 "
                       "(8000000000000 bytes) in a member of 192 bytes")


def test_a_compressed_payload_is_refused_whatever_it_would_inflate_to():
    zeros = _npy_header((4_000_000,)) + bytes(32_000_000)  # 32 MB of zeros deflate to ~30 KB
    payload = _zip({"ids.npy": zeros}, zipfile.ZIP_DEFLATED)
    assert len(payload) < 100_000
    assert "array 'ids.npy' is compressed (map arrays are stored plain)" in _message(_container(payload))


def test_an_honest_map_still_loads():
    good = encode_map(kind="ltmap", version=1, arrays={"a": np.arange(5.0)})
    np.testing.assert_array_equal(decode_map(good, file="m").arrays["a"], np.arange(5.0))


def test_only_the_declared_payload_is_read(tmp_path, monkeypatch):
    """A 3 GiB file of zeros (sparse: it costs no disk) is refused after its first bytes."""
    sparse = tmp_path / "zeros.ltmap"
    with open(sparse, "wb") as handle:
        handle.truncate(3 << 30)
    read = []
    real = maps.mapfile.open_regular

    def counting(path):
        handle = real(path)
        original = handle.read

        def counted(size=-1):
            data = original(size)
            read.append(len(data))
            return data

        handle.read = counted  # type: ignore[method-assign]
        return handle

    monkeypatch.setattr(maps.mapfile, "open_regular", counting)
    with pytest.raises(InputError, match="not a bearings map file"):
        read_map_file(sparse)
    assert sum(read) <= len(MAGIC)


@pytest.mark.parametrize("kind", ["fifo", "device", "folder"])
def test_a_map_that_is_not_a_regular_file_is_refused_at_once(tmp_path, capsys, kind):
    path = {"fifo": tmp_path / "pipe.ltmap", "device": "/dev/zero", "folder": tmp_path}[kind]
    if kind == "fifo":
        os.mkfifo(path)  # opening it for reading would block until someone writes
    assert main(["map", "info", str(path)]) == 2
    expected = {"fifo": "is a pipe", "device": "is a device or socket", "folder": "is a directory"}[kind]
    assert f"{expected}, not a regular file" in capsys.readouterr().err


def _tall(height: int, branches: int) -> LandmarkTree:
    """A root with ``branches`` chains of ``height`` nodes, one landmark per node (a hostile shape:
    a file of a few MB, 10^5 levels)."""
    parent = [-1]
    leaves = []
    for _ in range(branches):
        above = 0
        for _ in range(height):
            parent.append(above)
            above = len(parent) - 1
        leaves.append(above)
    count = len(parent)
    bearings = np.zeros((count, 3), np.float32)
    bearings[:, 0] = 1
    return LandmarkTree.from_arrays({"ids": np.arange(count, dtype=np.int64), "bearings": bearings,
                                     "node_parent": np.array(parent, np.int32),
                                     "node_size": np.ones(count, np.int32),
                                     "viewframe_leaf": np.array(leaves, np.int32)}, kind=IDS)


def test_a_tall_narrow_tree_is_pruned_in_a_few_passes(tmp_path, capsys):
    tree = _tall(100_000, 2)
    report = tree.copy().prune_to(1, min_landmarks=0)
    assert not report.fits and report.smallest_bytes == 200_001 * 20 + 8 + 4  # all rows kept; start and goal meet
    fitting = tree.prune_to(tree.memory_bytes() - 4 * 2 * 8)  # 4 levels of 2 nodes; start and goal keep their rows
    assert fitting.fits and fitting.levels_cut == 4 and tree.height == 99_996 and len(fitting.steps) == 1
    path = tmp_path / "tall.ltmap"
    save_ltmap(path, _tall(100_000, 2))
    assert main(["map", "prune", str(path), "--budget", "4100KB", "-o", str(tmp_path / "o.ltmap")]) == 0
    out = capsys.readouterr().out
    assert "93753 level(s) cut, height 100000 -> 6247" in out and load_ltmap(tmp_path / "o.ltmap").viewframe_count == 2


def test_a_single_chain_collapses_in_one_cut():
    tree = _tall(200_000, 1)
    step = tree.prune_level(0)
    assert step is not None and tree.height == 0 and tree.node_count == 1 and tree.landmark_count == 200_001
