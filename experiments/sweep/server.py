"""The warm episode server: imports the run command once, then forks one child per episode.

A fresh interpreter spends ~0.3 s importing numpy, OpenCV, py_trees and the bearings stack before
its episode starts; for short episodes that is most of the cost. The server pays it once per
worker: ``python -m experiments.sweep.server`` imports what ``bearings run`` needs and then, for each
request, forks a child that runs ``missions.cli.main(argv)`` and exits. Every child starts from
the same freshly imported state, so an episode still depends on its arguments only.

Forking is only safe from a single-threaded process: the server is started with the numeric
libraries pinned to one thread, checks that it has one thread after its imports, and otherwise
declines (the worker then starts a fresh interpreter per episode instead).

Protocol (JSON lines; requests on stdin, replies on stdout): the server says ``{"ready": true}``
(or ``{"ready": false, "reason": ...}``); a request ``{"argv": [...], "output": FILE}`` is
answered ``{"pid": N}`` when the child runs and ``{"exit": CODE}`` when it has ended (negative:
killed by that signal); ``{"kill": true}`` while a child runs kills its session. EOF on stdin
ends the server and its child. The server reaps its children itself, so a kill can never reach a
reused process id.
"""

from __future__ import annotations

import contextlib
import gc
import importlib
import json
import os
import select
import signal
import sys
import traceback

from experiments.sweep.child import die_with_parent

PRELOAD = ("missions.cli", "missions.commands.run", "missions.runner", "drivers.sim.simulation", "numpy.random")
"""Modules ``bearings run`` imports; a missing one is skipped (the child imports what it needs)."""

WARM_UP = ("run", "square", "--max-time", "1e-9", "--quiet")
"""A run that loads a shipped mission and sets it up in the empty world, then stops before its
first tick: it imports what loading and running import lazily (the built-in behaviours, say).
Nothing it leaves behind changes an episode: each one builds its own registry, tree and world
(the tests compare forked and freshly spawned episodes). If it fails, the server goes on without it."""


class _Lines:
    """Whole JSON lines from a raw file descriptor, usable with select()."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self.buffer = b""

    def pending(self) -> bool:
        return b"\n" in self.buffer

    def read(self) -> dict | None:
        """The next message, or None at EOF (blocks until a whole line is there)."""
        while b"\n" not in self.buffer:
            chunk = os.read(self.fd, 65536)
            if not chunk:
                return None
            self.buffer += chunk
        line, self.buffer = self.buffer.split(b"\n", 1)
        return json.loads(line)


def _send(fd: int, message: dict) -> None:
    os.write(fd, (json.dumps(message) + "\n").encode("utf-8"))


def preload() -> None:
    for name in PRELOAD:
        with contextlib.suppress(ImportError):
            module = importlib.import_module(name)
            if name == "missions.cli":
                module.build_parser()  # imports every command module
    with contextlib.suppress(Exception, SystemExit):
        from missions.cli import main as cli_main

        cli_main(list(WARM_UP))  # prints go to stderr (see main)
    gc.collect()
    gc.freeze()  # children's collections leave the preloaded objects alone: fewer copy-on-write pages


def thread_count() -> int:
    try:
        return len(os.listdir("/proc/self/task"))
    except OSError:
        import threading

        return threading.active_count()


def main() -> int:
    die_with_parent()
    requests = _Lines(0)
    replies = os.dup(1)
    os.dup2(2, 1)  # anything printed by an import goes to stderr, not into the protocol
    preload()
    if not hasattr(os, "fork") or not hasattr(os, "pidfd_open") or thread_count() != 1:
        _send(replies, {"ready": False, "reason": f"cannot fork safely ({thread_count()} threads)"})
        return 0
    _send(replies, {"ready": True})
    while True:
        request = requests.read()
        if request is None:
            return 0
        if "argv" not in request:
            continue
        server = os.getpid()
        pid = os.fork()
        if pid == 0:
            _child(request, requests.fd, replies, server)
        _send(replies, {"pid": pid})
        code = _supervise(pid, requests)
        if code is None:  # stdin closed while the child ran: the worker is gone
            return 0
        _send(replies, {"exit": code})


def _supervise(pid: int, requests: _Lines) -> int | None:
    """Wait for the child; kill its session on request. Its exit code, or None at EOF."""
    pidfd = os.pidfd_open(pid)
    try:
        while True:
            if requests.pending():  # a whole line already read: handle it without waiting
                readable = [requests.fd]
            else:
                readable, _, _ = select.select([pidfd, requests.fd], [], [])
            if pidfd in readable:
                _, status = os.waitpid(pid, 0)
                return os.waitstatus_to_exitcode(status)
            message = requests.read()
            if message is None or message.get("kill"):
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.killpg(pid, signal.SIGKILL)  # not reaped yet: the id is still this child's
                if message is None:
                    os.waitpid(pid, 0)
                    return None
    finally:
        os.close(pidfd)


def _child(request: dict, requests_fd: int, replies_fd: int, server: int) -> None:
    """In the forked child: become an episode process and never return."""
    code = 1
    try:
        os.setsid()
        die_with_parent(server)
        output = os.open(request["output"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        devnull = os.open(os.devnull, os.O_RDONLY)
        os.dup2(devnull, 0)
        os.dup2(output, 1)
        os.dup2(output, 2)
        for fd in (output, devnull, requests_fd, replies_fd):
            if fd > 2:
                os.close(fd)
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGCHLD):
            signal.signal(sig, signal.SIG_DFL)
        from missions.cli import main as cli_main

        code = cli_main(list(request["argv"]))
    except SystemExit as exc:  # argparse errors
        code = exc.code if isinstance(exc.code, int) else 1
    except BaseException:  # noqa: BLE001 - the child's last act is to say why
        traceback.print_exc()
        code = 1
    finally:
        with contextlib.suppress(Exception):
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(code if isinstance(code, int) else 1)


if __name__ == "__main__":
    sys.exit(main())
