"""The process of one episode: ``python -m experiments.sweep.child run ...`` is ``bearings run ...``
that also dies when the process that started it dies.

The sweep's task function starts this in its own session (so a terminal's Ctrl-C reaches the
sweep, which decides what to stop) and waits for it. Should the waiting worker itself be killed
(a Dask nanny restarting it, the OOM killer), Linux's parent-death signal takes the episode down
with it instead of leaving an orphan simulating on.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys

PARENT_ENV = "BEARINGS_SWEEP_PARENT"
PR_SET_PDEATHSIG = 1


def die_with_parent(parent: int | None = None) -> None:
    """Ask the kernel for SIGKILL when the parent goes; exit now if it has already gone.
    ``parent``: the expected parent's id (default: ``$BEARINGS_SWEEP_PARENT``)."""
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            import ctypes

            ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    expected = str(parent) if parent is not None else os.environ.get(PARENT_ENV, "")
    if expected.isdigit() and os.getppid() != int(expected):
        os._exit(70)  # the parent died before the signal was armed


def main() -> None:
    die_with_parent()
    from missions.cli import console

    console(sys.argv[1:])  # ends the process after the run, whatever threads a plugin left


if __name__ == "__main__":
    main()
