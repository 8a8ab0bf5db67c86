"""The link guard (issue 22, item 4): a plugin that ends the mission's process (os._exit in a tick)
leaves the robot stopped within a second by the guard process, not by the firmware watchdog; without
the guard the robot drives on until the watchdog."""

from __future__ import annotations

import subprocess
import sys
import time

import pytest

from tests.missions.test_run_ends import ENV, mission_file, robot_profile


@pytest.mark.parametrize("guard", [True, False], ids=["guarded", "unguarded"])
def test_a_plugin_that_ends_the_process_leaves_the_robot_stopped_by_the_guard(tmp_path, arcos, guard):
    robot = arcos(watchdog=5.0)  # a long firmware watchdog: only the guard can stop it within a second
    mission, report = mission_file(tmp_path, "exit"), tmp_path / "r.json"
    run = subprocess.run([sys.executable, "-m", "missions.cli", "run", str(mission), "--robot",
                          str(robot_profile(tmp_path, robot.port, guard=guard)), "--report", str(report), "--quiet"],
                         env=ENV, capture_output=True, text=True, timeout=120)
    ended = time.monotonic()
    assert run.returncode == 0 and not report.exists()  # what os._exit(0) means: nothing of ours ran
    assert [e for e in robot.named("VEL") if e.arg]  # it was driving when the process ended
    if guard:
        assert robot.wait_for(lambda: not robot.moving and robot.named("CLOSE"), timeout=1.0)
        assert not robot.named("watchdog") and not robot.named("ENABLE")[-1].arg  # motors off, not the watchdog
    else:
        time.sleep(max(0.0, ended + 1.0 - time.monotonic()))
        assert robot.moving and not robot.named("CLOSE")  # still driving: the firmware watchdog is 5 s away
