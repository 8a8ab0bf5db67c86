"""The task every executor runs: one episode in its own process, watched until it ends.

:func:`run_episode` is what a ``ProcessPoolExecutor`` worker or a Dask worker executes. It starts
``python -m experiments.sweep.child run ...`` (the ``bearings run`` command line) in a new session,
with its report written to a private temporary folder, and waits for it. The episode's process
is the unit of isolation: a crash, a ``SIGKILL`` or a hang kills that process only, never the
worker, so the executor keeps going and the sweep records one failed row. On the time limit or
when the sweep is stopped the whole session is killed (the episode and anything it started).

The result carries the report's text back to the sweep, so workers need no shared folder with the
machine that records the results; only the mission and world files must exist on the workers
(shipped names always do).
"""

from __future__ import annotations

import atexit
import contextlib
import json
import math
import os
import select
import signal
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from experiments.sweep.child import PARENT_ENV
from experiments.sweep.episode import Episode
from maps.located import validate
from maps.store import InputError
from missions.model import RunArguments

OUTPUT_TAIL = 4000
"""Characters of an episode's terminal output kept when it fails without a report."""

SINGLE_THREADED = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OPENCV_FOR_THREADS_NUM")
"""Thread pools of numeric libraries are pinned to one thread per episode: the sweep's parallelism
is across episodes, and N episodes x N threads on N cores would only contend."""


@dataclass(frozen=True)
class StopToken:
    """How a running task learns that the sweep was stopped (Ctrl-C): a file that appears, and on a
    Dask cluster also a ``distributed.Event`` (for workers that do not share the folder)."""

    path: str | None = None
    dask_event: str | None = None

    def is_set(self) -> bool:
        if self.path and os.path.exists(self.path):
            return True
        if self.dask_event:
            return _dask_event_is_set(self.dask_event)
        return False

    def set(self) -> None:
        if self.path:
            Path(self.path).parent.mkdir(parents=True, exist_ok=True)
            Path(self.path).touch()
        if self.dask_event:
            with contextlib.suppress(Exception):
                from distributed import Event

                Event(self.dask_event).set()

    def clear(self) -> None:
        if self.path:
            Path(self.path).unlink(missing_ok=True)
        if self.dask_event:
            with contextlib.suppress(Exception):
                from distributed import Event

                Event(self.dask_event).clear()


@dataclass(frozen=True)
class EpisodeResult:
    """What came back from one episode. ``error`` is None when the run ended normally (exit 0 or 1
    with a report), else ``timeout``, ``killed``, ``invalid``, ``crash`` or ``interrupted``."""

    id: str
    exit_code: int | None
    report_text: str | None
    error: str | None
    reason: str
    elapsed_s: float
    output: str = ""

    @property
    def interrupted(self) -> bool:
        return self.error == "interrupted"


START_METHODS = ("fork", "spawn")
"""``fork``: episodes are forked from a warm server that has imported the run command (see
:mod:`experiments.sweep.server`); ``spawn``: each episode is a fresh interpreter. Either way each
episode is its own process; ``fork`` saves the ~0.3 s of imports per episode."""


def run_number_problem(max_time_s: float | None, timeout_s: float | None) -> str | None:
    """Why a sweep's ``--max-time`` (checked as ``bearings run`` checks it, so no episode can refuse
    it after the pre-flight) or ``--timeout`` (finite, positive wall seconds) is refused, or None."""
    if max_time_s is not None:
        try:
            validate(RunArguments, {"--max-time": max_time_s}, file="--max-time")
        except InputError as exc:
            return str(exc.diagnostics[0].message)
    if timeout_s is not None and not (math.isfinite(timeout_s) and timeout_s > 0):
        return f"--timeout must be a finite number of seconds above 0, got {timeout_s:g}"
    return None


def run_episode(episode: Episode, timeout_s: float | None = None, stop: StopToken | None = None,
                start_method: str = "fork") -> EpisodeResult:
    """Run one episode in its own process; never raises for anything the episode does. The time
    limit and ``elapsed_s`` count from the start of the episode's process (a worker's first
    episode does not pay for starting the worker's episode server)."""
    if start_method not in START_METHODS:
        raise ValueError(f"start_method must be one of {', '.join(START_METHODS)}, not {start_method!r}")
    if stop is not None and stop.is_set():  # queued before the sweep was stopped: do not start it
        return EpisodeResult(episode.id, None, None, "interrupted", "the sweep was stopped", 0.0)
    server = _Server.get() if start_method == "fork" else None
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="bearings-episode-") as folder:
        report = Path(folder) / "report.json"
        log = Path(folder) / "output.txt"
        argv = episode.run_arguments(report)
        ended = _run_forked(server, argv, log, started, timeout_s, stop) if server is not None else None
        code, outcome = ended or _run_spawned(argv, log, started, timeout_s, stop)
        elapsed = time.monotonic() - started
        text = log.read_text(encoding="utf-8", errors="replace") if log.is_file() else ""
        report_text = report.read_text(encoding="utf-8") if report.is_file() else None
    return _result(episode, code, outcome, report_text, text, elapsed, timeout_s)


def _run_spawned(argv: list[str], log: Path, started: float, timeout_s: float | None,
                 stop: StopToken | None) -> tuple[int | None, str | None]:
    with open(log, "wb") as output:
        process = subprocess.Popen(
            [sys.executable, "-m", "experiments.sweep.child", *argv],
            stdin=subprocess.DEVNULL, stdout=output, stderr=subprocess.STDOUT, env=_environment(),
            start_new_session=True,
        )
        outcome = _watch(process, started, timeout_s, stop)
    return process.returncode, outcome


def _run_forked(server: _Server | None, argv: list[str], log: Path, started: float, timeout_s: float | None,
                stop: StopToken | None) -> tuple[int | None, str | None] | None:
    """The episode forked from this thread's warm server (started again once if it dies under
    the episode, unless the sweep was stopped or the time is up meanwhile: a server that was slow
    to kill an episode on a loaded machine must not start it again); None if there is no server
    to use."""
    for attempt in (1, 2):
        if server is None:
            return None
        try:
            return server.run(argv, log, started, timeout_s, stop)
        except _ServerLost:
            _Server.drop()  # its episode goes with it
            ended_by = _must_end(started, timeout_s, stop)
            if attempt == 2 or ended_by:  # a stopped sweep or a spent time limit starts nothing again
                return None, ended_by or "lost"
            server = _Server.get()
    return None


def _watch(process: subprocess.Popen, started: float, timeout_s: float | None, stop: StopToken | None) -> str | None:
    """Wait for the episode; kill its session on the time limit or a stop. What ended it, if not itself."""
    waiter = _ExitWaiter(process)
    try:
        while True:
            ended_by = _must_end(started, timeout_s, stop)
            if ended_by:
                _kill_session(process)
                return ended_by
            if waiter.wait(_poll_interval(started, timeout_s)):
                return None
    except BaseException:
        _kill_session(process)
        raise
    finally:
        waiter.close()


def _must_end(started: float, timeout_s: float | None, stop: StopToken | None) -> str | None:
    if timeout_s is not None and time.monotonic() - started >= timeout_s:
        return "timeout"
    if stop is not None and stop.is_set():
        return "interrupted"
    return None


def _poll_interval(started: float, timeout_s: float | None) -> float:
    if timeout_s is None:
        return 0.25
    return max(0.0, min(0.25, started + timeout_s - time.monotonic()))


class _ServerLost(Exception):
    """The warm server died or stopped answering."""


class _Server:
    """This thread's warm episode server (a process started on first use)."""

    _local = threading.local()
    _unavailable: str | None = None  # why this process cannot use one (then: spawn)

    @classmethod
    def get(cls) -> _Server | None:
        if cls._unavailable is not None:
            return None
        server = getattr(cls._local, "server", None)
        if server is None or server.process.poll() is not None:
            try:
                server = cls()
            except _ServerLost as exc:
                cls._unavailable = str(exc) or "the episode server did not start"
                return None
            cls._local.server = server
        return server

    @classmethod
    def drop(cls) -> None:
        server = getattr(cls._local, "server", None)
        cls._local.server = None
        if server is not None:
            server.close()

    def __init__(self) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "experiments.sweep.server"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL, env=_environment(), start_new_session=True,
        )
        assert self.process.stdin is not None and self.process.stdout is not None  # noqa: S101 - PIPEs
        self.requests, self.replies = self.process.stdin, self.process.stdout
        self.buffer = b""
        hello = self.receive(120.0)
        if not hello or not hello.get("ready"):
            self.close()
            raise _ServerLost((hello or {}).get("reason", "the episode server did not start"))
        atexit.register(self.close)

    def run(self, argv: list[str], log: Path, started: float, timeout_s: float | None,
            stop: StopToken | None) -> tuple[int | None, str | None]:
        self.send({"argv": argv, "output": str(log)})
        if self.receive(60.0) is None:  # {"pid": N} comes right after the fork
            raise _ServerLost("no answer")
        outcome = None
        while True:
            if outcome is None:
                outcome = _must_end(started, timeout_s, stop)
                if outcome:
                    self.send({"kill": True})
            message = self.receive(10.0 if outcome else _poll_interval(started, timeout_s))
            if message is not None and "exit" in message:
                return int(message["exit"]), outcome
            if message is None and outcome:
                raise _ServerLost("the killed episode did not end")

    def send(self, message: dict) -> None:
        try:
            os.write(self.requests.fileno(), (json.dumps(message) + "\n").encode("utf-8"))
        except (BrokenPipeError, OSError, ValueError) as exc:
            raise _ServerLost(str(exc)) from None

    def receive(self, timeout: float) -> dict | None:
        """The next message, None after ``timeout`` seconds; :class:`_ServerLost` at EOF."""
        deadline = time.monotonic() + timeout
        fd = self.replies.fileno()
        while b"\n" not in self.buffer:
            readable, _, _ = select.select([fd], [], [], max(0.0, deadline - time.monotonic()))
            if not readable:
                return None
            chunk = os.read(fd, 65536)
            if not chunk:
                raise _ServerLost("the episode server exited")
            self.buffer += chunk
        line, self.buffer = self.buffer.split(b"\n", 1)
        return json.loads(line)

    def close(self) -> None:
        with contextlib.suppress(OSError, ValueError):
            self.requests.close()  # EOF: the server kills its child, if any, and exits
        try:
            self.process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        with contextlib.suppress(OSError, ValueError):
            self.replies.close()


class _ExitWaiter:
    """Wakes up as soon as the child exits (a Linux pidfd), else polls."""

    def __init__(self, process: subprocess.Popen) -> None:
        self.process = process
        self.fd: int | None = None
        with contextlib.suppress(AttributeError, OSError):
            self.fd = os.pidfd_open(process.pid)

    def wait(self, seconds: float) -> bool:
        if self.fd is not None:
            select.select([self.fd], [], [], max(0.0, seconds))
            return self.process.poll() is not None
        try:
            self.process.wait(timeout=max(0.0, seconds))
            return True
        except subprocess.TimeoutExpired:
            return False

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None


def _kill_session(process: subprocess.Popen) -> None:
    """SIGKILL the episode's session (it and anything it started). Only while the episode is not
    yet reaped: its id then still names its group and cannot have been reused."""
    if process.returncode is None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(process.pid, signal.SIGKILL)
    process.wait()


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    code_root = str(Path(__file__).resolve().parents[2])  # the checkout this worker runs: episodes run the same
    env["PYTHONPATH"] = os.pathsep.join(p for p in (code_root, env.get("PYTHONPATH", "")) if p)
    env["PYTHONHASHSEED"] = "0"  # set and dict orders of strings are the same in every episode process
    env[PARENT_ENV] = str(os.getpid())
    for name in SINGLE_THREADED:
        env.setdefault(name, "1")
    return env


def _result(episode: Episode, code: int | None, outcome: str | None, report_text: str | None, output: str,
            elapsed: float, timeout_s: float | None) -> EpisodeResult:
    def make(error: str | None, reason: str, report: str | None = None) -> EpisodeResult:
        return EpisodeResult(episode.id, code, report, error, reason, round(elapsed, 3),
                             output[-OUTPUT_TAIL:] if error else "")

    if outcome == "timeout":
        return make("timeout", f"timed out after {timeout_s:g} s wall time (episode killed)")
    if outcome == "interrupted":
        return make("interrupted", "the sweep was stopped")
    if outcome == "lost":
        return make("crash", "its episode server died twice while running it")
    if code is not None and code < 0:
        return make("killed", f"killed by {_signal_name(-code)}")
    if code == 2:
        return make("invalid", f"invalid input: {_first_line(output)}")
    if code in (0, 1) and report_text is not None:
        return make(None, "", report_text)
    if code is not None and code > 128 and report_text is not None:  # `bearings run` ended by a signal from
        return make("killed", f"{_report_reason(report_text)} (exit {code})")  # outside (130 SIGINT, 143 SIGTERM)
    return make("crash", f"exited with code {code} without a report: {_last_line(output)}")


def _report_reason(text: str) -> str:
    try:
        return str(json.loads(text).get("reason", "no reason in the report"))
    except (ValueError, AttributeError):
        return "an unreadable report"


def _signal_name(number: int) -> str:
    try:
        return signal.Signals(number).name
    except ValueError:
        return f"signal {number}"


def _first_line(text: str) -> str:
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[0] if lines else "(no output)"


def _last_line(text: str) -> str:
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else "(no output)"


_EVENT_CACHE: dict[str, tuple[float, bool]] = {}


def _dask_event_is_set(name: str) -> bool:
    """Ask the scheduler at most once a second (the answer is a network round trip)."""
    now = time.monotonic()
    last = _EVENT_CACHE.get(name)
    if last is not None and now - last[0] < 1.0:
        return last[1]
    try:
        from distributed import Event

        value = Event(name).is_set()
    except Exception:  # noqa: BLE001 - not on a Dask worker, or the scheduler is gone: not stopped
        value = False
    _EVENT_CACHE[name] = (now, value)
    return value
