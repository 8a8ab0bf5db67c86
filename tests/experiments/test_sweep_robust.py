"""Episodes that crash, kill their own process or hang are one failed row each, with the reason; the
others finish. Ctrl-C (and SIGTERM) keep the finished rows, kill the running episodes, and --resume
runs the rest. Both ways of starting an episode's process are covered."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from experiments.sweep import worker
from missions.cli import main

TRAP_PLUGIN = """
import os
import signal
import time

from py_trees.common import Status
from behaviours.base import BearingsBehaviour
from behaviours.ports import InputPort
from behaviours.registry import register


@register
class Trap(BearingsBehaviour):
    '''On its third tick: nothing, kill its own process, exit without a report, or hang (a test plugin).'''
    PORTS = (InputPort("action", str, "none", choices=("none", "kill", "exit", "hang"), doc="what to do"),)

    def initialise(self):
        self.ticks = 0

    def update(self):
        self.ticks += 1
        if self.ticks < 3:
            return Status.RUNNING
        action = self.get_input("action")
        if action == "kill":
            os.kill(os.getpid(), signal.SIGKILL)
        elif action == "exit":
            os._exit(3)
        elif action == "hang":
            with open(os.path.join(os.path.dirname(__file__), f"hanging-{os.getpid()}"), "w"):
                pass  # the test checks that this process is gone after the sweep
            while True:
                time.sleep(3600)
        return Status.SUCCESS
"""

TRAP_MISSION = """
mission: trap
inputs:
  action: {type: str, default: none}
plugins: [./trap.py]
cameras: []
max_time: 20
tree:
  Sequence:
    children:
      - Drive: {distance: 0.05, speed: 0.5}
      - Trap: {action: "${action}"}
"""


@pytest.fixture
def trap(tmp_path: Path) -> Path:
    (tmp_path / "trap.py").write_text(TRAP_PLUGIN)
    mission = tmp_path / "trap.yaml"
    mission.write_text(textwrap.dedent(TRAP_MISSION).lstrip())
    return mission


def rows_of(folder: Path) -> list[dict]:
    return [json.loads(line) for line in (folder / "results.jsonl").read_text().splitlines()]


def hanging_episodes(folder: Path) -> list[int]:
    """Ids of the episode processes that started to hang (the plugin leaves a file each)."""
    return [int(p.name.split("-")[1]) for p in folder.glob("hanging-*")]


def descendants(root: int) -> set[int]:
    """Every live process under ``root`` (its pool workers, their episode servers, episodes)."""
    parents = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                parents[int(entry.name)] = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except OSError:
                continue
    found, frontier = set(), {root}
    while frontier:
        frontier = {pid for pid, parent in parents.items() if parent in frontier} - found
        found |= frontier
    return found


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def episode_startup_s(mission: Path) -> float:
    """Wall time a freshly started episode process of ``mission`` takes to load it and stop before its
    first tick, measured now, on this machine under its present load (about 0.5 s idle, 3 s on a
    loaded 2-core machine)."""
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    started = time.monotonic()
    ended = subprocess.run([sys.executable, "-m", "experiments.sweep.child", "run", str(mission), "--max-time",
                            "1e-9", "--quiet"], env=env, capture_output=True, text=True, timeout=300)
    assert ended.returncode == 1 and "time limit" in ended.stdout, ended.stderr  # FAILURE before the first tick
    return time.monotonic() - started


@pytest.mark.parametrize(("start_method", "seeds", "least"), [("fork", [0, 1], 1.5), ("spawn", [0], 3)])
def test_killed_crashed_and_hung_episodes_are_failed_rows(trap, tmp_path, capsys, start_method, seeds, least):
    """The time limit must let an episode that does not hang finish whatever the machine's speed: it
    is three times a start-up measured just before (a spawned episode's time includes starting Python
    and importing the stack; a forked one's less), and never below ``least``."""
    startup = episode_startup_s(trap)
    timeout = round(max(least, 3 * startup), 1)
    out = tmp_path / "out"
    code = main(["sweep", str(trap), "--set", "action=none,kill,exit,hang", "--seeds", f"0-{len(seeds) - 1}",
                 "--timeout", str(timeout), "--workers", "2", "--start-method", start_method, "-o", str(out)])
    assert code == 0  # every episode has its row
    rows = {(r["inputs.action"], r["seed"]): r for r in rows_of(out)}
    assert len(rows) == 4 * len(seeds)
    for seed in seeds:
        assert rows["none", seed]["status"] == "SUCCESS"
        assert (rows["kill", seed]["status"], rows["kill", seed]["reason"]) == ("ERROR", "killed by SIGKILL")
        assert rows["kill", seed]["exit_code"] == -signal.SIGKILL
        assert rows["exit", seed]["status"] == "ERROR"
        assert rows["exit", seed]["reason"].startswith("exited with code 3 without a report")
        assert rows["hang", seed]["status"] == "ERROR"
        assert rows["hang", seed]["reason"] == f"timed out after {timeout:g} s wall time (episode killed)"
        assert timeout <= rows["hang", seed]["elapsed_s"] < timeout + max(3, startup)  # killed at the limit
    failed = [r for r in rows.values() if r["status"] == "ERROR"]
    assert all((out / "logs" / f"{r['id']}.log").is_file() for r in failed)
    assert len(list((out / "reports").iterdir())) == len(seeds)  # only the episodes that reported
    summary = {line.split()[0]: line.split()[1:5] for line in capsys.readouterr().out.splitlines()[1:5]}
    n = str(len(seeds))
    assert summary == {"exit": [n, "0%", "0", n], "hang": [n, "0%", "0", n], "kill": [n, "0%", "0", n],
                       "none": [n, "100%", "0", "0"]}
    hung = hanging_episodes(trap.parent)
    assert len(hung) == len(seeds) and not any(alive(pid) for pid in hung)


def test_ctrl_c_keeps_finished_rows_kills_running_episodes_and_resume_runs_the_rest(trap, tmp_path):
    out = tmp_path / "out"
    command = [sys.executable, "-m", "missions.cli", "sweep", str(trap), "--set", "action=none,hang",
               "--timeout", "600", "--workers", "2", "-o", str(out)]  # only Ctrl-C can end the hanging episode
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    sweep = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                             start_new_session=True,  # its own process group, as a terminal job
                             preexec_fn=_ctrl_c_live)
    try:
        deadline = time.monotonic() + 30
        while not (out / "results.jsonl").is_file() or not (out / "results.jsonl").read_text().strip():
            assert time.monotonic() < deadline and sweep.poll() is None, sweep.communicate()
            time.sleep(0.05)
        while not hanging_episodes(trap.parent):
            assert time.monotonic() < deadline and sweep.poll() is None, sweep.communicate()
            time.sleep(0.05)
        hung = hanging_episodes(trap.parent)
        assert all(alive(pid) for pid in hung)
        started = descendants(sweep.pid)
        assert set(hung) <= started and len(started) >= 3  # workers, their episode servers, the episode
        os.killpg(sweep.pid, signal.SIGINT)  # Ctrl-C reaches the whole group
        try:
            _, err = sweep.communicate(timeout=180)  # a guard against a hang: a loaded machine needs ~25 s
        except subprocess.TimeoutExpired:
            states = _signal_states([sweep.pid, *sorted(descendants(sweep.pid))])  # which of them held Ctrl-C
            os.killpg(sweep.pid, signal.SIGKILL)
            pytest.fail(f"the sweep did not end within 180 s of Ctrl-C; processes: {states}; "
                        f"it said: {sweep.communicate()[1][-2000:]}")
    finally:
        if sweep.poll() is None:
            os.killpg(sweep.pid, signal.SIGKILL)
            sweep.wait()
    assert sweep.returncode == 1
    assert "interrupted; 1 of 2 runs recorded" in err and "Traceback" not in err
    assert [r["inputs.action"] for r in rows_of(out)] == ["none"]
    deadline = time.monotonic() + 5
    while any(alive(pid) for pid in started) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not [pid for pid in started if alive(pid)]  # the hanging episode was killed, nothing left behind
    first = rows_of(out)[0]
    assert main(["sweep", str(trap), "--set", "action=none,hang", "--timeout", "1", "--workers", "1",
                 "--resume", "-o", str(out)]) == 0
    rows = rows_of(out)
    assert [r["inputs.action"] for r in rows] == ["hang", "none"] and rows[1] == first
    assert rows[0]["reason"] == "timed out after 1 s wall time (episode killed)"
    assert main(["sweep", str(trap), "--set", "action=none,hang", "--timeout", "0.5", "--workers", "1",
                 "--resume", "--retry-errors", "-o", str(out)]) == 0
    rows = rows_of(out)
    assert [r["inputs.action"] for r in rows] == ["hang", "none"] and rows[1] == first
    assert rows[0]["reason"] == "timed out after 0.5 s wall time (episode killed)"  # run again, its row replaced


class _SlowToKill:
    """A warm server that loses touch while killing its episode (a loaded machine)."""

    def run(self, *args: object) -> tuple[int | None, str | None]:
        raise worker._ServerLost("the killed episode did not end")


def test_a_server_lost_while_stopping_does_not_start_the_episode_again(tmp_path, monkeypatch):
    stop = worker.StopToken(str(tmp_path / "stop"))
    stop.set()  # Ctrl-C came first: the server was told to kill the episode and did not answer in time
    started_again = []
    monkeypatch.setattr(worker._Server, "drop", classmethod(lambda cls: None))
    monkeypatch.setattr(worker._Server, "get", classmethod(lambda cls: started_again.append(1)))
    outcome = worker._run_forked(_SlowToKill(), ["run", "x"], tmp_path / "log", time.monotonic(), 60.0, stop)
    assert outcome == (None, "interrupted") and not started_again
    stop.clear()  # not stopped, time left: the episode gets one more server, as before
    worker._run_forked(_SlowToKill(), ["run", "x"], tmp_path / "log", time.monotonic(), 60.0, stop)
    assert started_again == [1]


def _ctrl_c_live() -> None:
    """SIGINT as a terminal's job has it: a test suite started in the background of a shell without
    job control inherits SIGINT ignored, and so would the sweep (Python then leaves it ignored)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _signal_states(pids: list[int]) -> str:
    """Each process's state and signal masks from /proc (blocked, ignored, caught), for a failure message."""
    states = []
    for pid in pids:
        try:
            fields = dict(line.split(":", 1) for line in Path(f"/proc/{pid}/status").read_text().splitlines()
                          if ":" in line)
            cmdline = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ")[:120].decode(errors="replace")
        except OSError:
            continue
        states.append(f"{pid} {fields.get('State', '?').strip()} blk={fields.get('SigBlk', '?').strip()} "
                      f"ign={fields.get('SigIgn', '?').strip()} cgt={fields.get('SigCgt', '?').strip()} [{cmdline}]")
    return "; ".join(states)
