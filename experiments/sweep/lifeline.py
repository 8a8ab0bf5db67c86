"""Everything a command starts dies with it, and its temporary folders go with it.

``bearings sweep`` and ``bearings eval`` start many processes: pool workers (and multiprocessing's
resource tracker), an episode server per worker, an episode per run. Ctrl-C and SIGTERM are
handled (the sweep stops what runs and keeps its rows), but a SIGKILL, the OOM killer or a crash
gives the command no chance to clean up, and its children would go on (a worker even starting
the next episode) and leave their folders behind. Three things make that impossible:

- **parent-death signals**: pool workers, episode servers and episodes ask the kernel for SIGKILL
  when their parent dies (``PR_SET_PDEATHSIG``, :func:`experiments.sweep.child.die_with_parent`),
  so the tree of processes falls with its root;
- **one private temporary folder**: the command and everything it starts put their temporary
  folders under it (``TMPDIR``);
- **a reaper**: a small process in a session of its own (a terminal's signals and a ``kill`` of
  the command's process group do not reach it) that waits for the command to end, however it
  ends (its pipe from the command closes, even on SIGKILL), then SIGKILLs every process still
  carrying the command's token in its environment (each one the command started, by its id, and
  nothing else) and removes the private folder. It runs this file by path and imports the
  standard library only, so it starts in a few tens of milliseconds.

On systems without ``/proc`` the reaper still removes the folder; the parent-death signal is
Linux's (elsewhere the sweep's own Ctrl-C handling is what stops its episodes).
"""

from __future__ import annotations

import contextlib
import multiprocessing.resource_tracker
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

TOKEN_ENV = "BEARINGS_LIFELINE"
"""The environment variable every process a command starts inherits: the command's token."""

REAP_ROUNDS = 40
"""How many times the reaper looks again (a worker may fork a server while it is being killed)."""


@contextlib.contextmanager
def lifeline(command: str) -> Iterator[Path]:
    """Run the body with a reaper watching this process (see the module doc) and SIGTERM raising
    ``KeyboardInterrupt`` (a batch system ending the job stops it as Ctrl-C does); yields the
    private temporary folder. On the way out (normally, by exception, or not at all when the
    process is killed) the reaper ends what is left and removes the folder."""
    if sys.platform != "win32":  # started before the token: the tracker ends by itself when its users do
        multiprocessing.resource_tracker.ensure_running()
    folder = Path(tempfile.mkdtemp(prefix=f"bearings-{command}-"))
    token = uuid.uuid4().hex
    read, write = os.pipe()  # not inheritable: only this process holds the write end
    try:
        reaper = subprocess.Popen([sys.executable, "-S", str(Path(__file__).resolve()), token, str(folder),
                                   str(os.getpid())], stdin=read, stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL, start_new_session=True, close_fds=True,
                                  env={k: v for k, v in os.environ.items() if k != TOKEN_ENV})
    finally:
        os.close(read)
    saved = {name: os.environ.get(name) for name in (TOKEN_ENV, "TMPDIR")}
    saved_tempdir = tempfile.tempdir
    os.environ[TOKEN_ENV], os.environ["TMPDIR"], tempfile.tempdir = token, str(folder), str(folder)
    try:
        with _sigterm_as_interrupt():
            yield folder
    finally:
        tempfile.tempdir = saved_tempdir
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value
        os.close(write)  # the reaper's signal: the command is done
        with contextlib.suppress(subprocess.TimeoutExpired):
            reaper.wait(timeout=10)
        shutil.rmtree(folder, ignore_errors=True)


@contextlib.contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(_signum: int, _frame: object) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def carrying(token: str) -> set[int]:
    """The processes whose environment holds ``token`` (readable ones: this user's)."""
    needle = f"{TOKEN_ENV}={token}".encode()
    found = set()
    with contextlib.suppress(OSError):
        for entry in os.scandir("/proc"):
            if entry.name.isdigit():
                with contextlib.suppress(OSError):
                    if needle in Path(entry.path, "environ").read_bytes().split(b"\0"):
                        found.add(int(entry.name))
    return found


def reap(token: str, folder: str, spare: set[int]) -> None:
    """SIGKILL every process carrying ``token`` (but ``spare``), until none is left; remove ``folder``."""
    for _ in range(REAP_ROUNDS):
        left = carrying(token) - spare
        if not left:
            break
        for pid in left:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        time.sleep(0.05)
    shutil.rmtree(folder, ignore_errors=True)


def main(argv: list[str]) -> int:
    token, folder, command = argv[0], argv[1], int(argv[2])
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # only the end of the command ends the reaper
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    with contextlib.suppress(OSError):
        while os.read(0, 4096):  # nothing is written: EOF comes when the command is gone or done
            pass
    reap(token, folder, {os.getpid(), command})
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
