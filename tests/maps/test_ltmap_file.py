"""LT-map files: identical round trip, atomic saves, one clear line for every bad file."""

from __future__ import annotations

import numpy as np
import pytest

from maps.ltmap.file import KIND, decode_ltmap, encode_ltmap, load_ltmap, save_ltmap
from maps.ltmap.learner import RouteLearner
from maps.mapfile import encode_map
from maps.store import InputError
from perception.synthetic_route import make_route_world, observe_route, straight_route


def taught(kind: str, length: float = 2.0, places: bool = True):
    world, rng, learner = make_route_world(3, length=length, n_near=300), np.random.default_rng(4), RouteLearner()
    for pose in straight_route(length, 0.05):
        place = (pose.x, pose.y) if places else None
        learner.observe(observe_route(world, pose, rng, kind=kind, noise_deg=0.1), pose.theta, place)
    learner.finish()
    return learner.tree


@pytest.mark.parametrize("kind", ["orb", "ids"])
def test_a_saved_map_loads_identical(tmp_path, kind):
    tree = taught(kind)
    path = tmp_path / "route.ltmap"
    save_ltmap(path, tree)
    loaded = load_ltmap(path)
    original, again = tree.to_arrays(), loaded.to_arrays()
    assert original.keys() == again.keys()
    for name, array in original.items():
        assert np.array_equal(again[name], array) and again[name].dtype == array.dtype
    assert (loaded.kind, loaded.threshold, loaded.scale) == (tree.kind, tree.threshold, tree.scale)
    assert loaded.summary() == tree.summary()
    assert loaded.has_places and loaded.place(-1).tolist() == pytest.approx([2.0, 0.0])  # the goal's, taught last
    for i in range(tree.viewframe_count):  # the same viewframes, landmark for landmark
        a, b = tree.viewframe(i), loaded.viewframe(i)
        data_a = a.ids if kind == "ids" else a.descriptors
        data_b = b.ids if kind == "ids" else b.descriptors
        order_a, order_b = np.lexsort(np.asarray(a.bearings).T), np.lexsort(np.asarray(b.bearings).T)
        assert np.array_equal(data_a[order_a], data_b[order_b])
    payload_bytes = sum(a.nbytes for a in original.values())
    assert tree.memory_bytes() == payload_bytes < path.stat().st_size < payload_bytes + 4096


def one_line_error(data: bytes) -> str:
    with pytest.raises(InputError) as info:
        decode_ltmap(data, file="route.ltmap")
    assert len(info.value.diagnostics) == 1 and "\n" not in str(info.value)
    assert str(info.value).startswith("route.ltmap: ")
    return str(info.value)


def test_every_bad_file_is_one_clear_line():
    tree = taught("ids", 1.0)
    good = encode_ltmap(tree)
    assert "truncated" in one_line_error(good[: len(good) // 2])
    flipped = bytearray(good)
    flipped[-30] ^= 0x01
    assert "checksum" in one_line_error(bytes(flipped))
    assert "not a bearings map" in one_line_error(b"\x89PNG\r\n\x1a\n")
    assert "roadmap map file, not a ltmap" in one_line_error(encode_map(kind="roadmap", version=1, arrays={}))
    assert "version 4" in one_line_error(encode_map(kind=KIND, version=4, arrays={}))


def test_a_version_1_map_is_read_with_the_eq1_threshold_of_the_same_bearing_change():
    tree = taught("ids", 1.0)
    # version 1 held the angle form's 1e-3 rad^2: 3.04300 deg (tests/perception/test_similarity.py);
    # eq. 1 at 3.043 deg: x = 1 - cos(3.043 deg) = 1.410024e-3, x / b = 2.314653, sqrt(1 + 5.357619) - 1 = 1.521432,
    # times 2 b^2 = 7.421836e-7: 1.129182e-6
    old = encode_map(kind=KIND, version=1, arrays=tree.to_arrays(), meta={"landmarks": "ids", "threshold": 1e-3})
    loaded = decode_ltmap(old, file="old.ltmap")
    assert loaded.threshold == pytest.approx(1.129182e-6, rel=1e-4)
    assert loaded.scale == tree.scale and loaded.viewframe_count == tree.viewframe_count


def test_a_version_2_map_has_no_places_and_follows_as_before():
    tree = taught("ids", 1.0, places=False)
    assert "viewframe_place" not in tree.to_arrays()
    old = encode_map(kind=KIND, version=2, arrays=tree.to_arrays(),
                     meta={"landmarks": "ids", "threshold": tree.threshold})
    loaded = decode_ltmap(old, file="old.ltmap")
    assert not loaded.has_places and loaded.place(0) is None and loaded.viewframe_count == tree.viewframe_count


def test_a_sound_container_with_an_inconsistent_tree_is_refused():
    arrays = taught("ids", 1.0).to_arrays()
    meta = {"landmarks": "ids", "threshold": 0.001}

    def broken(**changes) -> str:
        return one_line_error(encode_map(kind=KIND, version=1, arrays={**arrays, **changes}, meta=meta))

    assert "node_size" in broken(node_size=arrays["node_size"] + 1)
    assert "node_parent" in broken(node_parent=np.roll(arrays["node_parent"], 1))
    assert "leaf" in broken(viewframe_leaf=arrays["viewframe_leaf"][:-1])
    assert "bearings" in broken(bearings=arrays["bearings"] * 2)
    assert "int64" in broken(ids=arrays["ids"].astype(np.float64))
    assert "meta" in one_line_error(encode_map(kind=KIND, version=1, arrays=arrays, meta={"landmarks": "surf"}))
    assert "unexpected" in broken(extra=np.zeros(3))
    views = len(arrays["viewframe_leaf"])
    assert "viewframe_place" in broken(viewframe_place=np.zeros((views - 1, 2), dtype=np.float32))
    assert "viewframe_place" in broken(viewframe_place=np.full((views, 2), np.nan, dtype=np.float32))
    assert "viewframe_place" in broken(viewframe_place=np.zeros((views, 2)))  # float64


def test_a_failed_save_keeps_the_previous_map(tmp_path, monkeypatch):
    path = tmp_path / "route.ltmap"
    save_ltmap(path, taught("ids", 1.0))
    before = path.read_bytes()

    def crash(*_args):
        raise OSError("disk full")

    monkeypatch.setattr("maps.store.os.replace", crash)
    with pytest.raises(OSError):
        save_ltmap(path, taught("ids", 2.0))
    assert path.read_bytes() == before and load_ltmap(path).viewframe_count > 0
    assert [p.name for p in tmp_path.iterdir()] == ["route.ltmap"]  # no temporary file left


def test_missing_file_is_one_line(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        load_ltmap(tmp_path / "nope.ltmap")
