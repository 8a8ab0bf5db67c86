"""Hostile input, round two (issue 22, items 6 and 7): one line where a one-line error is promised,
never a traceback; no file damaged without a word; no hang on a file that is not a file."""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import cv2
import numpy as np
import pytest

from maps.store import json_text, write_json
from missions.cli import main
from perception.calibration import find_corners

TREE_XML = """<root BTCPP_format="4"><BehaviorTree ID="M"><Repeat num_cycles="{cycles}"><AlwaysSuccess/></Repeat>
</BehaviorTree></root>
"""


def _one_line(capsys, exit_code: int, code: int) -> str:
    err = capsys.readouterr().err
    assert exit_code == code and "Traceback" not in err, err
    return err


def test_a_five_thousand_digit_integer_is_a_located_error(tmp_path, capsys):
    xml = tmp_path / "t.xml"
    xml.write_text(TREE_XML.format(cycles="9" * 5000))
    err = _one_line(capsys, main(["import", str(xml)]), 2)
    assert ":1:45: Repeat.num_cycles expects a whole number, got '9999" in err and "(5002 characters)" in err
    mission = tmp_path / "m.yaml"
    mission.write_text("tree: {Wait: {duration: " + "9" * 5000 + "}}\n")
    err = _one_line(capsys, main(["validate", str(mission)]), 2)
    assert err.splitlines()[0].endswith("cannot be read as int (ValueError, 5000 characters)")
    assert len(err.splitlines()[0]) < len(str(mission)) + 120


@pytest.mark.parametrize("side", [1, 5, 12, 39])
def test_calibrating_on_tiny_images_says_they_are_too_small(tmp_path, capsys, side):
    names = []
    for k in range(3):
        names.append(str(tmp_path / f"{k}.png"))
        cv2.imwrite(names[-1], np.full((side, side), 255 * (k % 2), np.uint8))
    err = _one_line(capsys, main(["calibrate", *names, "--board", "9x6", "--square", "0.025",
                                  "-o", str(tmp_path / "c.yaml")]), 2)
    assert f"the images are {side}x{side} pixels: too small to show a 9x6 board (at least 40x28" in err


@pytest.mark.parametrize("shape", [(28, 40), (40, 28), (41, 31), (64, 64)])
def test_the_corner_search_never_raises_on_small_or_blank_images(shape):
    rng = np.random.default_rng(0)
    for image in (np.zeros(shape, np.uint8), rng.integers(0, 256, shape, dtype=np.uint8)):
        assert find_corners(image, 9, 6) is None


def test_the_input_is_never_the_output_and_a_replaced_file_is_named(tmp_path, capsys):
    xml = tmp_path / "t.xml"
    xml.write_text(TREE_XML.format(cycles="3"))
    before = xml.read_text()
    (tmp_path / "link.xml").symlink_to(xml)
    for output in (xml, tmp_path / "link.xml"):
        err = _one_line(capsys, main(["import", str(xml), "-o", str(output)]), 2)
        assert f"cannot write {output}: it is the input file {xml}" in err and xml.read_text() == before
    mission = tmp_path / "m.yaml"
    assert main(["import", str(xml), "-o", str(mission)]) == 0
    assert "replaced" not in capsys.readouterr().err
    assert main(["import", str(xml), "-o", str(mission)]) == 0
    assert f"bearings import: replaced {mission}" in capsys.readouterr().err
    err = _one_line(capsys, main(["show", str(mission), "--format", "xml", "-o", str(mission)]), 2)
    assert "it is the input file" in err


@pytest.fixture
def fifo(tmp_path: Path) -> Path:
    path = tmp_path / "pipe"
    os.mkfifo(path)  # reading it would block until someone writes to it
    return path


@pytest.mark.parametrize("command", [["validate", "{}"], ["run", "square", "--sim", "{}"], ["import", "{}"],
                                     ["map", "info", "{}"], ["show", "{}"]])
def test_a_fifo_is_refused_not_waited_on(fifo, capsys, command):
    code = main([part.format(fifo) for part in command])
    err = _one_line(capsys, code, 2)
    assert f"{fifo}: is a pipe, not a regular file" in err


@pytest.fixture
def full_disk(monkeypatch):
    """Every atomic write fails as on a full file system (ENOSPC when the data is flushed)."""

    def no_space(_fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr("maps.store.os.fsync", no_space)


@pytest.mark.parametrize("command", [["import", "{xml}", "-o", "{out}"], ["show", "square", "-o", "{out}"],
                                     ["schema", "-o", "{out}"]])
def test_a_full_disk_is_one_line_and_the_previous_file_stays(tmp_path, capsys, full_disk, command):
    xml, out = tmp_path / "t.xml", tmp_path / "out.txt"
    xml.write_text(TREE_XML.format(cycles="3"))
    out.write_text("previous\n")
    code = main([part.format(xml=xml, out=out) for part in command])
    err = _one_line(capsys, code, 1)
    assert f"cannot write {out}: No space left on device (nothing was changed)" in err
    assert out.read_text() == "previous\n" and len(err.splitlines()) == 1


def test_a_run_whose_report_cannot_be_written_keeps_its_outcome(tmp_path, capsys, full_disk):
    report = tmp_path / "r.json"
    code = main(["run", "square", "--quiet", "--max-time", "1", "--report", str(report)])
    err = _one_line(capsys, code, 1)  # FAILURE (time limit): the exit code of the run, not of the disk
    assert f"bearings run: the report was not written to {report}: No space left on device; the run ended " \
           "FAILURE (time limit of 1 s reached)" in err
    assert not report.exists()


def test_json_is_strict_non_finite_numbers_are_null(tmp_path):
    data = {"a": float("inf"), "b": [1.0, float("nan"), {"c": -float("inf")}], "d": 1e308}
    assert json_text(data) == '{"a": null, "b": [1.0, null, {"c": null}], "d": 1e+308}'
    write_json(tmp_path / "x.json", data)
    text = (tmp_path / "x.json").read_text()
    assert "Infinity" not in text and "NaN" not in text and json.loads(text)["d"] == 1e308


def test_calibrate_never_writes_over_an_image_it_reads(tmp_path, capsys):
    names = []
    for k in range(3):
        names.append(str(tmp_path / f"{k}.png"))
        cv2.imwrite(names[-1], np.zeros((60, 80), np.uint8))
    before = Path(names[0]).read_bytes()
    err = _one_line(capsys, main(["calibrate", *names, "--board", "9x6", "--square", "0.025", "-o", names[0]]), 2)
    assert f"cannot write {names[0]}: it is the input file {names[0]}" in err
    assert Path(names[0]).read_bytes() == before


def test_a_snapshot_says_when_it_replaced_a_file(tmp_path, capsys):
    out = tmp_path / "view.png"
    for replaced in (False, True):
        assert main(["sim", "snapshot", "--world", "lab", "--pose", "1.5,1.5,0", "-o", str(out)]) == 0
        assert ("replaced the previous file" in capsys.readouterr().out) == replaced
