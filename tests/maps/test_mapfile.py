"""Map files: round trip, and one clear error for every way a file can be wrong."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from maps.mapfile import MAGIC, decode_map, encode_map, read_map_file, write_map_file
from maps.store import InputError


def _arrays():
    return {"bearings": np.arange(12, dtype=np.float32).reshape(4, 3), "ids": np.array([3, 1, 4, 1], np.int64)}


def test_round_trip_keeps_arrays_and_meta(tmp_path):
    path = tmp_path / "route.ltmap"
    write_map_file(path, kind="ltmap", version=1, arrays=_arrays(), meta={"route": "lab", "threshold": 0.2})
    loaded = read_map_file(path, kind="ltmap", versions=(1,))
    assert loaded.header.kind == "ltmap" and loaded.meta == {"route": "lab", "threshold": 0.2}
    for name, array in _arrays().items():
        np.testing.assert_array_equal(loaded.arrays[name], array)
        assert loaded.arrays[name].dtype == array.dtype


@given(hnp.arrays(dtype=st.sampled_from([np.float32, np.float64, np.uint8, np.int32]),
                  shape=hnp.array_shapes(min_dims=1, max_dims=3, max_side=5)))
def test_any_numeric_array_round_trips(array):
    decoded = decode_map(encode_map(kind="x", version=2, arrays={"a": array}), file="f", kind="x", versions=(2,))
    np.testing.assert_array_equal(decoded.arrays["a"], array)


def _error(data: bytes, **kwargs) -> str:
    with pytest.raises(InputError) as info:
        decode_map(data, file="m.map", **kwargs)
    assert len(info.value.diagnostics) == 1
    return str(info.value)


def test_every_damage_is_one_clear_line():
    good = encode_map(kind="ltmap", version=1, arrays=_arrays())
    assert "not a bearings map file" in _error(b"PK\x03\x04 a zip")
    assert "truncated" in _error(good[:-10])
    assert "trailing bytes" in _error(good + b"x")
    flipped = bytearray(good)
    flipped[-20] ^= 0xFF
    assert "checksum" in _error(bytes(flipped))
    assert "header" in _error(MAGIC + b"{not json\n")
    assert "not a roadmap map file" in _error(good, kind="roadmap")
    assert "newer bearings" in _error(encode_map(kind="ltmap", version=3, arrays={}), kind="ltmap", versions=(1, 2))


def test_object_arrays_are_refused():
    with pytest.raises(TypeError, match="object"):
        encode_map(kind="x", version=1, arrays={"a": np.array([{}, None], dtype=object)})


def test_a_failed_save_keeps_the_previous_map(tmp_path, monkeypatch):
    path = tmp_path / "m.map"
    write_map_file(path, kind="ltmap", version=1, arrays=_arrays())
    before = path.read_bytes()

    def crash(*_args):
        raise OSError("disk full")

    monkeypatch.setattr("maps.store.os.fsync", crash)
    with pytest.raises(OSError):
        write_map_file(path, kind="ltmap", version=1, arrays={"other": np.zeros(3)})
    assert path.read_bytes() == before


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_map_file(tmp_path / "nope.map")
    with pytest.raises(InputError, match="directory"):
        read_map_file(tmp_path)
