"""Orphans (issue 22, item 3): SIGTERM or SIGKILL of ``bearings sweep`` or ``bearings eval``, during
its pre-flight check or while episodes run, leaves no process of theirs and no temporary folder
after 5 s: pool workers, the episode servers and the episodes die with the command (parent-death
signals) and its reaper ends what is left and removes its private temporary folder."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from experiments.sweep.lifeline import TOKEN_ENV, carrying, lifeline

HANG_PLUGIN = """
import os
import time

from py_trees.common import Status
from behaviours.base import BearingsBehaviour
from behaviours.registry import register

HERE = os.path.dirname(__file__)
if os.path.exists(os.path.join(HERE, "hang-on-import")):  # the sweep's pre-flight check loads this
    open(os.path.join(HERE, f"importing-{os.getpid()}"), "w").close()
    while True:
        time.sleep(3600)


@register
class Hang(BearingsBehaviour):
    '''On its third tick, hangs for good (a test plugin).'''

    def initialise(self):
        self.ticks = 0

    def update(self):
        self.ticks += 1
        if self.ticks >= 3:
            open(os.path.join(HERE, f"hanging-{os.getpid()}"), "w").close()
            while True:
                time.sleep(3600)
        return Status.RUNNING
"""

HANG_MISSION = """
mission: hang
plugins: [./hang.py]
cameras: []
max_time: 20
tree: Hang
"""


def processes_with(marker: str) -> set[int]:
    """Live processes whose environment mentions ``marker`` (the test's private TMPDIR): every
    process the command started inherits it."""
    needle = marker.encode()
    found = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if needle in (entry / "environ").read_bytes():
                    state = (entry / "stat").read_text().rsplit(")", 1)[1].split()[0]
                    if state != "Z":
                        found.add(int(entry.name))
            except OSError:
                continue
    return found - {os.getpid()}


def wait_for(condition, what: str, command: subprocess.Popen, seconds: float = 120) -> None:
    deadline = time.monotonic() + seconds
    while not condition():
        if command.poll() is not None or time.monotonic() > deadline:
            out, err = command.communicate()
            pytest.fail(f"{what} never happened (exit {command.returncode}): {out[-2000:]} {err[-2000:]}")
        time.sleep(0.05)


@pytest.fixture
def hang(tmp_path: Path) -> Path:
    folder = tmp_path / "mission"
    folder.mkdir()
    (folder / "hang.py").write_text(HANG_PLUGIN)
    (folder / "hang.yaml").write_text(textwrap.dedent(HANG_MISSION).lstrip())
    return folder


def start(tmp_path: Path, hang: Path, command: str) -> tuple[subprocess.Popen, Path]:
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    args = {"sweep": ["sweep", str(hang / "hang.yaml"), "--seeds", "0-1", "--timeout", "120"],
            "eval": ["eval", "exploration", "--world", "rooms", "--seeds", "2", "--timeout", "120"]}[command]
    env = {**os.environ, "TMPDIR": str(temporary), "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    process = subprocess.Popen([sys.executable, "-m", "missions.cli", *args, "--workers", "2",
                                "-o", str(tmp_path / "out")], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, env=env, start_new_session=True)
    return process, temporary


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
@pytest.mark.parametrize(("command", "when"), [("sweep", "pre-flight"), ("sweep", "mid-run"), ("eval", "mid-run")])
def test_a_killed_command_leaves_no_process_and_no_temporary_folder(tmp_path, hang, command, when, signum):
    if when == "pre-flight":
        (hang / "hang-on-import").touch()
    process, temporary = start(tmp_path, hang, command)
    try:
        if command == "eval":  # an episode is running when its folder exists
            wait_for(lambda: any(temporary.rglob("bearings-episode-*")), "an episode", process)
        else:
            marker = "importing-*" if when == "pre-flight" else "hanging-*"
            wait_for(lambda: len(list(hang.glob(marker))) >= (1 if when == "pre-flight" else 2), when, process)
        started = processes_with(str(temporary))
        assert len(started) >= 3 and process.pid in started  # the command, its workers, servers, episodes
        os.kill(process.pid, signum)
        process.communicate(timeout=60)
        deadline = time.monotonic() + 5
        while (processes_with(str(temporary)) or any(temporary.iterdir())) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not processes_with(str(temporary)), "processes of the command are still running"
        assert not any(temporary.iterdir()), f"temporary folders left: {list(temporary.iterdir())}"
    finally:
        for pid in processes_with(str(temporary)):  # whatever the assertions say, leave nothing behind
            os.kill(pid, signal.SIGKILL)
    if signum == signal.SIGTERM:
        assert process.returncode == 1


def test_the_lifeline_reaps_what_a_body_leaves_and_spares_the_command(tmp_path):
    """In-process use (a test calling the command's main): the body's stray children are ended and
    the folder removed when the body ends; the calling process and its environment are untouched."""
    before = dict(os.environ)
    with lifeline("test") as folder:
        token = os.environ[TOKEN_ENV]
        stray = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
        (folder / "left.txt").write_text("x")
        assert carrying(token) == {stray.pid}
    assert stray.wait(timeout=10) == -signal.SIGKILL
    assert not folder.exists() and dict(os.environ) == before
