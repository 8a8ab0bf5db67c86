"""Run many episodes on any ``concurrent.futures.Executor`` and record one row per episode.

:func:`run_sweep` is the one code path for ``bearings sweep`` and every ``bearings eval``: a local
``ProcessPoolExecutor`` and a Dask cluster (``distributed.Client(address).get_executor()``) are
both just an executor here. Each task runs :func:`experiments.sweep.worker.run_episode`, which isolates
the episode in its own process, so nothing an episode does can break the executor.
"""

from __future__ import annotations

import contextlib
import dataclasses
import fcntl
import functools
import multiprocessing
import os
import re
import shutil
import signal
import sys
import tempfile
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import BrokenExecutor, CancelledError, Executor, Future, ProcessPoolExecutor, as_completed
from concurrent.futures import wait as wait_futures
from pathlib import Path
from typing import Any, TextIO

from experiments.sweep.child import die_with_parent
from experiments.sweep.episode import Episode, SweepInputError
from experiments.sweep.table import LOGS, REPORTS, TABLE, Journal, latest_by_id, make_row, read_rows, write_sorted
from experiments.sweep.worker import START_METHODS, EpisodeResult, StopToken, run_episode
from maps.store import write_text_atomic

Row = dict[str, Any]

STOP_GRACE_S = 10.0
"""After Ctrl-C, how long the sweep waits for running episodes to be killed by their workers."""


class SweepError(RuntimeError):
    """Some episodes could not be run at all (the executor broke or lost them). ``rows`` holds every
    row that was recorded; ``lost`` the ids of the episodes to run again (``--resume`` does)."""

    def __init__(self, message: str, rows: list[Row], lost: list[str]) -> None:
        super().__init__(message)
        self.rows = rows
        self.lost = lost


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C (or SIGTERM) stopped the sweep; ``rows`` holds every row finished before it."""

    def __init__(self, rows: list[Row], total: int) -> None:
        super().__init__(f"interrupted with {len(rows)} of {total} episodes recorded")
        self.rows = rows
        self.total = total


def default_workers() -> int:
    """The cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:
        return max(1, os.cpu_count() or 1)


WORKER_BYTES = 256 * 1024 * 1024
"""Memory one local worker takes with its episode server and the episode it runs (about 170 MB
measured for the shipped worlds, rounded up): workers beyond what the machine's free memory holds
would only swap or be killed."""


def worker_limit() -> tuple[int, str]:
    """The most local workers this machine has room for, and why: its cores, or its free memory."""
    cores = default_workers()
    available = _available_memory()
    if available is not None and available // WORKER_BYTES < cores:
        return max(1, available // WORKER_BYTES), f"the free memory, {available / 2**30:.1f} GiB"
    return cores, "the cores this process may use"


def cap_workers(requested: int | None, command: str) -> int | None:
    """``--workers`` capped at :func:`worker_limit`, saying so on stderr (a worker and an episode
    server per requested worker would start, whatever the machine has)."""
    if requested is None:
        return None
    limit, why = worker_limit()
    if requested <= limit:
        return requested
    print(f"bearings {command}: --workers {requested} capped at {limit} ({why})", file=sys.stderr)
    return limit


def _available_memory() -> int | None:
    """MemAvailable of /proc/meminfo in bytes (Linux); None where it cannot be read."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def _start_worker(sweep: int) -> None:
    # A terminal's Ctrl-C reaches the whole process group; the sweep alone decides what to stop.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent(sweep)  # a killed sweep takes its workers (and so their servers and episodes) along


def local_executor(workers: int | None = None) -> ProcessPoolExecutor:
    """A process pool for sweeps on this machine. Workers start with ``spawn`` (no inherited
    threads or locks), ignore SIGINT (on Ctrl-C the sweep stops their episodes itself) and die
    with the sweep's process, however it ends (see :mod:`experiments.sweep.lifeline`)."""
    return ProcessPoolExecutor(max_workers=workers or default_workers(), initializer=_start_worker,
                               initargs=(os.getpid(),), mp_context=multiprocessing.get_context("spawn"))


CONNECT_TIMEOUT_S = 10.0
"""How long ``cluster_executor`` tries to reach the scheduler."""


@contextlib.contextmanager
def cluster_executor(address: str, *, connect_timeout_s: float | None = None) -> Iterator[Executor]:
    """An executor on a running Dask scheduler (``tcp://host:8786``); needs ``bearings[cluster]``.
    The workers must run this version of bearings and see the mission and world files."""
    from distributed import Client  # ImportError: the caller says how to install it

    client = Client(address, set_as_default=True, timeout=f"{connect_timeout_s or CONNECT_TIMEOUT_S}s")
    try:
        yield client.get_executor(pure=False)  # every submission runs: episodes have side effects
    finally:
        client.close()


@contextlib.contextmanager
def executor_for(workers: int | None, cluster: str | None) -> Iterator[Executor]:
    """The executor a command's ``--workers``/``--cluster`` ask for: a local process pool (its
    pending episodes cancelled on the way out) or a Dask scheduler. :class:`SweepInputError` with
    the one-line reason when the cluster cannot be used (no distributed package, no scheduler)."""
    if cluster is None:
        pool = local_executor(workers)
        try:
            yield pool
        except BaseException:  # Ctrl-C during a pre-flight check, say: do not wait for what runs (the
            pool.shutdown(wait=False, cancel_futures=True)  # command's lifeline ends it)
            raise
        pool.shutdown(wait=True, cancel_futures=True)
        return
    stack = contextlib.ExitStack()
    try:
        executor = stack.enter_context(cluster_executor(cluster))
    except ImportError:
        raise SweepInputError("--cluster needs Dask's distributed package: pip install 'bearings[cluster]'") from None
    except (OSError, TimeoutError, ValueError) as exc:
        raise SweepInputError(f"cannot reach the Dask scheduler at {cluster}: {exc}") from None
    with stack:
        yield executor


def prepare_results_folder(folder: str | os.PathLike) -> None:
    """Create a results folder (and its parents) and make sure files can be created in it;
    :class:`SweepInputError` in one line when it cannot be used (a file in the way, ``/proc``, a
    read-only disk). A file is created and removed rather than ``os.access`` asked: root passes
    every permission check and still cannot write to a read-only file system."""
    path = Path(folder)
    if path.exists() and not path.is_dir():
        raise SweepInputError(f"{path}: not a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError as exc:
        raise SweepInputError(f"{path}: cannot write results there ({exc.strerror or exc})") from None


def run_sweep(
    episodes: Sequence[Episode],
    *,
    executor: Executor | None = None,
    results_dir: str | os.PathLike | None = None,
    timeout_s: float | None = None,
    on_row: Callable[[Row], None] | None = None,
    resume: bool = False,
    retry_errors: bool = False,
    progress: TextIO | None = None,
    start_method: str = "fork",
) -> list[Row]:
    """Run ``episodes`` and return one row per episode, sorted by episode id.

    ``executor``: any ``concurrent.futures.Executor`` (default: a local process pool over all
    cores, shut down afterwards; a given executor is left running). ``results_dir``: where the
    table (``results.jsonl``), reports (``reports/<id>.json``) and output of failed episodes
    (``logs/<id>.log``) go; None keeps rows in memory only. ``timeout_s``: wall-clock limit per
    episode, after which it is killed and recorded as ERROR. ``on_row``: called in this process
    with each row as it is recorded. ``resume``: skip episodes the table already has (without it
    a folder that has results is an error); ``retry_errors``: with it, run the ERROR rows again
    (their new rows replace them). ``progress``: a stream for the progress line.
    ``start_method``: how each episode's process starts, ``fork`` (from a warm server per worker,
    the default) or ``spawn`` (a fresh interpreter); see :mod:`experiments.sweep.worker`.
    Episodes without an ``output_dir`` write their files (``--output-dir``) in ``results_dir``.

    Raises :class:`SweepInterrupted` on Ctrl-C (finished rows kept, running episodes killed) and
    :class:`SweepError` when the executor lost episodes; both carry the recorded rows.
    """
    if start_method not in START_METHODS:
        raise ValueError(f"start_method must be one of {', '.join(START_METHODS)}, not {start_method!r}")
    if results_dir is not None:
        folder = str(Path(results_dir).resolve())
        episodes = [e if e.output_dir is not None else dataclasses.replace(e, output_dir=folder) for e in episodes]
    unique = {episode.id: episode for episode in episodes}
    with _Workspace(results_dir, resume) as space:
        done = {i: row for i, row in space.existing.items()
                if i in unique and not (retry_errors and row.get("status") == "ERROR")}
        todo = [episode for i, episode in sorted(unique.items()) if i not in done]
        meter = Progress(len(unique), len(done), progress)
        stop = StopToken(str(space.stop_path), _dask_event_name(executor))
        stop.clear()
        owned = executor is None
        executor = executor or local_executor()
        finished = False
        try:
            task = functools.partial(run_episode, timeout_s=timeout_s, stop=stop, start_method=start_method)
            new_rows, lost = _execute(todo, executor, task, space, on_row, meter, stop)
            finished = True
        except KeyboardInterrupt:
            rows = sorted([*done.values(), *space.recorded], key=lambda r: r["id"])
            raise SweepInterrupted(rows, len(unique)) from None
        except OSError as exc:  # the results folder failed under the sweep (a full disk): stop, keep what is there
            rows = sorted([*done.values(), *space.recorded], key=lambda r: r["id"])
            recorded = {row["id"] for row in rows}
            raise SweepError(f"cannot record results in {space.folder}: {exc.strerror or exc}", rows,
                             [e.id for e in todo if e.id not in recorded]) from None
        finally:
            if owned:  # waits for the running tasks, which see the stop token and kill their episodes
                executor.shutdown(wait=True, cancel_futures=True)
            if finished or owned:
                stop.clear()
            else:  # tasks of a caller's executor may still be running (a Dask task cannot be
                space.keep_scratch = True  # interrupted, only told): the token stays set for them
            meter.finish()
    rows = sorted([*done.values(), *new_rows], key=lambda r: r["id"])
    if lost:
        first = lost[0][1]
        raise SweepError(f"{len(lost)} episode(s) could not be run ({type(first).__name__}: {first}); "
                         "run the sweep again with --resume", rows, [i for i, _ in lost])
    return rows


CHECK_TIME_S = 1e-9
"""The ``--max-time`` of a check run: the tree is built and set up, the world loaded, nothing ticks."""


def check_episodes(episodes: Sequence[Episode], executor: Executor, *, timeout_s: float | None = 120.0,
                   start_method: str = "fork") -> None:
    """Raise :class:`SweepInputError` (one line) if the run command rejects any mission, world or
    combination of inputs of ``episodes`` (its exit code 2). Each distinct mission x world and
    mission x inputs is checked once, by the run command itself on the executor's workers (so paths
    are checked where the episodes will run), with a time limit that lets nothing tick.
    ``timeout_s`` bounds each check (wall time; setting up is all it does, whatever the sweep's
    own per-run limit)."""
    checks: dict[tuple, Episode] = {}
    for e in episodes:
        probe = dataclasses.replace(e, max_time_s=CHECK_TIME_S)
        checks.setdefault(("world", e.mission, e.world), probe)
        checks.setdefault(("inputs", e.mission, tuple(e.input_text.items())), probe)
    probes = list(dict.fromkeys(checks.values()))
    futures = [executor.submit(run_episode, probe, timeout_s, None, start_method) for probe in probes]
    for probe, future in zip(probes, futures, strict=True):
        try:
            result = future.result()
        except Exception as exc:  # noqa: BLE001 - e.g. Dask workers without this version of bearings
            raise SweepInputError(f"the workers could not run the check ({type(exc).__name__}: {exc})") from None
        if result.error == "invalid":
            problems = [line.strip() for line in result.output.splitlines()
                        if line.strip() and not re.fullmatch(r"\d+ problems? found", line.strip())]
            raise SweepInputError("; ".join(problems) or result.reason)
        if result.error in ("timeout", "killed", "crash"):
            where = f"{probe.mission} in {probe.world}"
            raise SweepInputError(f"checking {where} before the sweep: {result.reason}")


def _execute(todo: list[Episode], executor: Executor, task: Callable[[Episode], EpisodeResult], space: _Workspace,
             on_row: Callable[[Row], None] | None, meter: Progress,
             stop: StopToken) -> tuple[list[Row], list[tuple[str, BaseException]]]:
    futures: dict[Future, Episode] = {}
    lost: list[tuple[str, BaseException]] = []
    try:
        for episode in todo:
            futures[executor.submit(task, episode)] = episode
        for future in as_completed(futures):
            episode = futures[future]
            try:
                result = future.result()
            except (BrokenExecutor, CancelledError, Exception) as exc:  # noqa: BLE001 - the executor lost it
                lost.append((episode.id, exc))
                meter.lose()
                continue
            row = space.record(episode, result)
            meter.add(row)
            if on_row is not None:
                on_row(row)
    except BaseException:  # Ctrl-C, or on_row raised: stop what runs, keep what finished
        _stop_running(futures, stop, space)
        raise
    return space.recorded, lost


def _stop_running(futures: dict[Future, Episode], stop: StopToken, space: _Workspace) -> None:
    """Cancel what has not started; running tasks see the token and kill their episodes. Episodes
    that finish on their own meanwhile are still recorded."""
    stop.set()
    for future in futures:
        future.cancel()
    running = [f for f in futures if not f.done()]
    with contextlib.suppress(KeyboardInterrupt):  # a second Ctrl-C: stop waiting
        wait_futures(running, timeout=STOP_GRACE_S)
        for future in running:
            if future.done() and not future.cancelled() and future.exception() is None:
                result = future.result()
                if not result.interrupted:
                    space.record(futures[future], result)


def _dask_event_name(executor: Executor | None) -> str | None:
    if executor is not None and type(executor).__module__.startswith("distributed"):
        return f"bearings-sweep-stop-{uuid.uuid4().hex}"
    return None


class _Workspace:
    """The results folder of one sweep: a lock, the journal, reports and logs."""

    def __init__(self, results_dir: str | os.PathLike | None, resume: bool) -> None:
        self.folder = Path(results_dir) if results_dir is not None else None
        self.resume = resume
        self.recorded: list[Row] = []
        self.existing: dict[str, Row] = {}
        self.journal: Journal | None = None
        self._lock_fd = -1
        self._scratch: str | None = None
        self.keep_scratch = False

    def __enter__(self) -> _Workspace:
        if self.folder is None:
            self._scratch = tempfile.mkdtemp(prefix="bearings-sweep-")
            self.stop_path = Path(self._scratch) / "stop"
            return self
        prepare_results_folder(self.folder)
        self._lock(self.folder)
        self.stop_path = self.folder / ".stop"
        self.existing = latest_by_id(read_rows(self.folder / TABLE))
        if self.existing and not self.resume:
            self._unlock()
            raise SweepInputError(f"{self.folder} already holds {len(self.existing)} results: add --resume to "
                                  "continue that sweep, or choose another folder")
        for sub in (REPORTS, LOGS):
            (self.folder / sub).mkdir(exist_ok=True)
        self.journal = Journal(self.folder / TABLE)
        return self

    def __exit__(self, *_exc: object) -> None:
        if self._scratch is not None and not self.keep_scratch:
            shutil.rmtree(self._scratch, ignore_errors=True)
        if self.journal is not None and self.folder is not None:
            self.journal.close()
            # the table holds what it held at the start (``existing``) and the rows appended since
            # (``recorded``): sorted from memory, not read again; if that fails (a full disk) the
            # journal keeps every row, unsorted
            with contextlib.suppress(OSError):
                write_sorted(self.folder / TABLE, latest_by_id([*self.existing.values(), *self.recorded]).values())
        self._unlock()

    def record(self, episode: Episode, result: EpisodeResult) -> Row:
        row = make_row(episode, result)
        if self.folder is not None and self.journal is not None:
            if result.report_text is not None and result.error is None:
                write_text_atomic(self.folder / REPORTS / f"{episode.id}.json", result.report_text)
            if result.error is not None:  # what it printed, possibly nothing
                write_text_atomic(self.folder / LOGS / f"{episode.id}.log", result.output)
            self.journal.append(row)
        self.recorded.append(row)
        return row

    def _lock(self, folder: Path) -> None:
        self._lock_fd = os.open(folder / ".lock", os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(self._lock_fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self._unlock()
            raise SweepInputError(f"{folder}: another sweep is writing there") from None

    def _unlock(self) -> None:
        if self._lock_fd >= 0:
            os.close(self._lock_fd)
            self._lock_fd = -1


class Progress:
    """``sweep: 12/64 done, 1 failed, elapsed 0:42, ETA 2:10`` on a stream (redrawn on a TTY)."""

    def __init__(self, total: int, resumed: int, stream: TextIO | None) -> None:
        self.total, self.resumed, self.stream = total, resumed, stream
        self.done = self.failed = self.lost = 0
        self.started = time.monotonic()
        self.tty = bool(stream is not None and stream.isatty())
        self._last = 0.0
        self._drawn = False

    def add(self, row: Row) -> None:
        self.done += 1
        self.failed += row.get("status") != "SUCCESS"
        self._draw()

    def lose(self) -> None:
        self.lost += 1
        self._draw()

    def finish(self) -> None:
        if self.tty and self._drawn and self.stream is not None:  # the last state, then leave the line
            self._draw(force=True)
            self.stream.write("\n")
            self.stream.flush()

    def line(self) -> str:
        elapsed = time.monotonic() - self.started
        finished = self.done + self.lost
        left = self.total - self.resumed - finished
        eta = _clock(elapsed / finished * left) if finished else "?"
        resumed = f" ({self.resumed} resumed)" if self.resumed else ""
        lost = f", {self.lost} lost" if self.lost else ""
        return (f"sweep: {self.resumed + finished}/{self.total} done{resumed}, {self.failed} failed{lost}, "
                f"elapsed {_clock(elapsed)}, ETA {eta}")

    def _draw(self, force: bool = False) -> None:
        if self.stream is None:
            return
        now = time.monotonic()
        if not force and self.tty and now - self._last < 0.2:
            return
        self._last = now
        self._drawn = True
        self.stream.write(("\r" + self.line().ljust(78)) if self.tty else self.line() + "\n")
        self.stream.flush()


def _clock(seconds: float) -> str:
    seconds = int(round(seconds))
    hours, rest = divmod(seconds, 3600)
    return f"{hours}:{rest // 60:02d}:{rest % 60:02d}" if hours else f"{rest // 60}:{rest % 60:02d}"


def progress_stream(force: bool) -> TextIO | None:
    """stderr when it is a terminal or when asked (``--progress``), else nothing."""
    return sys.stderr if force or sys.stderr.isatty() else None
