"""How a run ends whatever a plugin or a device does (issue 22, items 4 and 8): a plugin's threads
cannot keep the process after its report; a robot that never answers is a device fault (exit 1, a
report), not invalid input. (A plugin that ends the process: tests/drivers/test_link_guard.py.)"""

from __future__ import annotations

import json
import os
import pty
import subprocess
import sys
import textwrap
from pathlib import Path

from missions.cli import main
from tests.drivers.conftest import FAST_BASE

ROOT = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "PYTHONPATH": str(ROOT)}

PLUGIN = """
import os
import threading
import time

from py_trees.common import Status
from behaviours.base import BearingsBehaviour
from behaviours.ports import InputPort
from behaviours.registry import register


@register
class Leave(BearingsBehaviour):
    '''On its fifth tick: end the process (os._exit), or start a thread that never ends and succeed.'''
    PORTS = (InputPort("how", str, "exit", choices=("exit", "thread"), literal_only=True, doc="what to do"),)

    def initialise(self):
        self.ticks = 0

    def update(self):
        self.ticks += 1
        if self.ticks < 5:
            return Status.RUNNING
        if self.get_input("how") == "exit":
            os._exit(0)
        threading.Thread(target=lambda: time.sleep(3600), name="plugin-forever").start()  # not a daemon
        return Status.SUCCESS
"""

MISSION = """
plugins: [leave.py]
cameras: []
tree:
  Parallel:
    policy: one
    children:
      - Drive: {{distance: 5.0, speed: 0.3}}
      - Leave: {{how: {how}}}
"""


def mission_file(folder: Path, how: str) -> Path:
    (folder / "leave.py").write_text(PLUGIN)
    path = folder / f"{how}.yaml"
    path.write_text(textwrap.dedent(MISSION.format(how=how)).lstrip())
    return path


def robot_profile(folder: Path, port: str, **extra: object) -> Path:
    settings = {**FAST_BASE, **extra}
    fields = ", ".join(f"{k}: {json.dumps(v)}" for k, v in settings.items())
    path = folder / "robot.yaml"
    path.write_text(f'robot: bench\nbase: {{driver: pioneer, port: "{port}", {fields}}}\n')
    return path


def test_a_plugins_thread_does_not_keep_the_process_after_its_report(tmp_path):
    mission, report = mission_file(tmp_path, "thread"), tmp_path / "r.json"
    run = subprocess.run([sys.executable, "-m", "missions.cli", "run", str(mission), "--report", str(report),
                          "--quiet"], env=ENV, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert json.loads(report.read_text())["status"] == "SUCCESS"
    assert "1 thread(s) a plugin left running: plugin-forever" in run.stderr


def test_a_robot_that_never_answers_is_a_device_fault_with_a_report(tmp_path, capsys):
    master, slave = pty.openpty()  # a port that exists and never says a word
    try:
        report = tmp_path / "r.json"
        profile = robot_profile(tmp_path, os.ttyname(slave), connect_timeout=0.5)
        assert main(["run", "square", "--robot", str(profile), "--report", str(report), "--quiet"]) == 1
        err = capsys.readouterr().err
        assert f"square: FAILURE (device fault: cannot open the robot of {profile}:" in err and "Traceback" not in err
        data = json.loads(report.read_text())
        assert data["status"] == "FAILURE" and data["reason"].startswith("device fault: cannot open the robot")
        assert data["last_command"] == {"v": 0.0, "w": 0.0}
    finally:
        os.close(master)
        os.close(slave)
