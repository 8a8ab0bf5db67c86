"""The file store: located YAML and atomic writes."""

from __future__ import annotations

import json
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
    path = tmp_path / "map.json"
    write_json(path, {"a": 1})
    write_json(path, {"a": 2})
    assert path.read_text() == '{\n  "a": 2\n}\n'
    assert os.listdir(path.parent) == ["map.json"]  # no temporary left behind


def test_no_folder_is_created_silently(tmp_path):
    with pytest.raises(FileNotFoundError):
        write_json(tmp_path / "sub" / "map.json", {"a": 1})
    assert not (tmp_path / "sub").exists()
    assert store.output_problem(tmp_path / "sub" / "map.json") == f"the folder {tmp_path / 'sub'} does not exist"


def test_a_replaced_file_keeps_its_mode_and_a_new_one_follows_the_umask(tmp_path):
    kept = tmp_path / "shared.json"
    kept.write_text("{}")
    kept.chmod(0o644)
    write_json(kept, {"a": 1})
    assert kept.stat().st_mode & 0o777 == 0o644
    old = os.umask(0o027)
    try:
        write_json(tmp_path / "new.json", {"a": 1})
    finally:
        os.umask(old)
    assert (tmp_path / "new.json").stat().st_mode & 0o777 == 0o640


def test_symlinks_are_written_through(tmp_path):
    target = tmp_path / "real.json"
    target.write_text("{}")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    write_json(link, {"a": 3})
    assert link.is_symlink() and json.loads(target.read_text()) == {"a": 3}


def test_non_regular_targets_are_refused_before_writing(tmp_path):
    with pytest.raises(IsADirectoryError):
        write_text_atomic(tmp_path, "x")
    assert store.output_problem(tmp_path) == "is a directory"
    assert store.output_problem("/dev/full") == "is not a regular file (a device, socket or pipe?)"
    with pytest.raises(OSError, match="not a regular file"):
        write_text_atomic("/dev/full", "x")
    assert os.path.exists("/dev/full")


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
