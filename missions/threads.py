"""One thread per numeric thread pool for every ``bearings`` command, set before numpy loads.

A tick multiplies matrices of a few dozen rows; BLAS's worker threads (one per core by default)
cost more to wake and spin than the work they share, so a run with them burns two to five times
the CPU of a run without (``bearings bench run``: ``blas_cpu_ratio``), and on a busy machine its
wall time grows the same way. OpenBLAS, MKL and OpenMP read their thread counts from the
environment once, when the library loads: :func:`pin_thread_pools` must run before the first
``import numpy`` (``missions.cli.main`` calls it first). A count the user set in the environment
is kept, so ``OPENBLAS_NUM_THREADS=4 bearings run ...`` still gives four threads. The sweep pins the
same variables for its episodes (:mod:`experiments.sweep.worker`); child processes inherit them.
"""

from __future__ import annotations

import os
from collections.abc import MutableMapping

THREAD_POOLS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
"""The environment variables of the BLAS/OpenMP thread pools numpy and scipy may load."""


def pin_thread_pools(environ: MutableMapping[str, str] | None = None) -> dict[str, str]:
    """Set every pool in :data:`THREAD_POOLS` to one thread unless the environment already says;
    the variables set (name: value)."""
    env = os.environ if environ is None else environ
    pinned = {}
    for name in THREAD_POOLS:
        if not env.get(name, "").strip():
            env[name] = "1"
            pinned[name] = "1"
    return pinned
