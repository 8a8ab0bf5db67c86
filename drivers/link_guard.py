"""A stop that outlives the process: a guard holding a copy of the robot's link.

Everything the runner does to stop the robot runs in the mission's process. When that process
ends without running it (a plugin calls ``os._exit``, a ``kill -9``, the OOM killer, a crash in C
code), the robot would go on at its last commanded speed until its firmware watchdog stops it:
the config packet's Watchdog, 2 s by default (docs/protocols.md), a firmware parameter that no
client command of ARIA's ``ArCommands.h`` sets. So the driver starts a guard when a session opens:
a small process, in a session of its own, that holds a duplicate of the link's file descriptor
and a pipe from the driver's process. When the driver releases the link it tells the guard,
which exits quietly; when the pipe closes without that word (the driver's process is gone,
however it ended), the guard writes the farewell the driver gave it (STOP, VEL 0, RVEL 0,
ENABLE 0, CLOSE) on the link and exits. The robot is then stopped within milliseconds, not the
watchdog's seconds; the firmware watchdog remains the net for a link that is itself gone.

The guard runs this file by path and imports the standard library only (it starts in tens of
milliseconds); on a system where it cannot start, the driver logs why and goes on.
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import subprocess
import sys
from pathlib import Path

log = logging.getLogger(__name__)

DONE = b"done"
"""What the driver writes to the guard's pipe when it releases the link itself."""


class LinkGuard:
    """The guard of one open link (see the module doc); :meth:`release` before the link closes."""

    def __init__(self, process: subprocess.Popen, pipe: int) -> None:
        self.process = process
        self._pipe = pipe

    @classmethod
    def start(cls, fd: int, farewell: bytes) -> LinkGuard | None:
        """A guard that writes ``farewell`` on ``fd`` if this process dies; None when it cannot start."""
        read, write = os.pipe()  # not inheritable: only this process holds the write end
        try:
            process = subprocess.Popen(
                [sys.executable, "-S", str(Path(__file__).resolve()), str(fd), farewell.hex()],
                stdin=read, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, pass_fds=(fd,),
                start_new_session=True, env={"PATH": os.environ.get("PATH", "")},
            )
        except OSError as exc:
            os.close(write)
            log.warning("no link guard (the robot stops by its own watchdog if this process dies): %s", exc)
            return None
        finally:
            os.close(read)
        return cls(process, write)

    def release(self) -> None:
        """The driver stops and closes the link itself: the guard exits without writing."""
        with contextlib.suppress(OSError):
            os.write(self._pipe, DONE)
        with contextlib.suppress(OSError):
            os.close(self._pipe)
        try:
            self.process.wait(timeout=2.0)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


def guard(fd: int, farewell: bytes) -> int:
    """The guard's life: wait for the driver's word or for its process to be gone."""
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):  # a terminal's or a job's signal is
        signal.signal(sig, signal.SIG_IGN)  # for the mission's process; the guard ends with it
    heard = b""
    with contextlib.suppress(OSError):
        while chunk := os.read(0, 64):
            heard += chunk
    if heard.startswith(DONE):
        return 0
    sent = 0
    with contextlib.suppress(OSError):
        while sent < len(farewell):
            sent += os.write(fd, farewell[sent:])
    return 0 if sent == len(farewell) else 1


if __name__ == "__main__":
    sys.exit(guard(int(sys.argv[1]), bytes.fromhex(sys.argv[2])))
