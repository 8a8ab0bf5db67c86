"""The file store: located YAML and atomic writes."""

from __future__ import annotations

import os

import pytest

from maps import store
from maps.store import InputError, load_yaml, write_json, write_text_atomic


def test_located_values(tmp_path):
    path = tmp_path / "a.yaml"
    path.write_text("a: 1\nb:\n  - {c: 2}\n  - 3\n")
    doc = load_yaml(path)
    assert doc == {"a": 1, "b": [{"c": 2}, 3]}
    assert (doc.mark_of("b").line, doc["b"].mark_of(1).line, doc["b"][0].mark.col) == (2, 4, 5)


def test_atomic_write_replaces_whole_file(tmp_path):
    path = tmp_path / "sub" / "map.json"
    write_json(path, {"a": 1})
    write_json(path, {"a": 2})
    assert path.read_text() == '{\n  "a": 2\n}\n'
    assert os.listdir(path.parent) == ["map.json"]  # no temporary left behind


def test_a_crash_while_writing_keeps_the_old_file(tmp_path, monkeypatch):
    path = tmp_path / "map.txt"
    write_text_atomic(path, "old")

    def crash(*_args):
        raise OSError("disk on fire")

    monkeypatch.setattr(store.os, "fsync", crash)
    with pytest.raises(OSError, match="disk on fire"):
        write_text_atomic(path, "new")
    assert path.read_text() == "old"
    assert os.listdir(tmp_path) == ["map.txt"]


def test_directory_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match="is a directory"):
        load_yaml(tmp_path)
