"""What a ``bearings run`` costs beyond its mission (``bearings bench run --json``): the free speed.

Two figures, each a ratio of two runs measured in the same bench, as ``bearings run`` processes:

- BLAS threads: the CPU seconds of the same ``explore`` run (world ``rooms``, seed 0, a fixed
  simulated time) with numpy's thread pools pinned to one thread, as every ``bearings`` command
  pins them (:mod:`missions.threads`), and with one thread per core, numpy's default
  (``blas_cpu_ratio`` = unpinned / pinned CPU seconds; ``blas_wall_ratio`` likewise). On one core
  both are the same run and the ratio is about 1.
- Unused cameras: the ``square`` mission in the lab grabbing only what it reads (no camera, as
  the loader infers from the data flow) and grabbing every camera of the world
  (``cameras_wall_ratio``: wall seconds with / without; ``cameras_recording_ratio``: the size of
  the ``--save`` recording with / without).

CPU seconds are the child process's user + system time (all its threads), from ``wait4``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from missions.threads import THREAD_POOLS

EXPLORE_TIME_S = 30.0
"""Simulated seconds of the explore run (150 ticks at its 5 Hz): a survey and the first goals."""

SQUARE = """mission: square_{name}
cameras: {cameras}
tree:
  Sequence:
    children:
      - Repeat:
          num_cycles: 4
          child:
            Sequence:
              children:
                - Drive: {{distance: 1.0, speed: 0.3}}
                - Rotate: {{angle: 90, speed: 45}}
      - Stop
"""


@dataclass(frozen=True)
class Cost:
    """What one ``bearings run`` process cost: CPU seconds (all threads), wall seconds, exit code."""

    cpu_s: float
    wall_s: float
    exit_code: int


def bearings_run(arguments: list[str], *, threads: int) -> Cost:
    """Run ``bearings run ARGUMENTS`` in a child process with every numeric pool at ``threads``."""
    env = {**os.environ, **{name: str(threads) for name in THREAD_POOLS}}
    command = [sys.executable, "-c", "import sys; from missions.cli import main; sys.exit(main(sys.argv[1:]))",
               "run", *arguments, "--quiet"]
    start = time.perf_counter()
    process = subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(process.pid, 0)
    wall = time.perf_counter() - start
    process.returncode = os.waitstatus_to_exitcode(status)
    code = process.returncode
    if code not in (0, 1):  # 1: the time limit of a cut-short run
        said = process.stderr.read().decode(errors="replace").strip() if process.stderr else ""
        raise RuntimeError(f"bench run {' '.join(arguments)} exited {code}: {said[-500:]}")
    if process.stderr:
        process.stderr.close()
    return Cost(usage.ru_utime + usage.ru_stime, wall, code)


def _blas(quick: bool, repeats: int) -> dict:
    cores = os.cpu_count() or 1
    seconds = EXPLORE_TIME_S / 3 if quick else EXPLORE_TIME_S
    arguments = ["explore", "--sim", "rooms", "--seed", "0", "--max-time", f"{seconds:g}"]
    pinned, unpinned = [], []
    for _ in range(repeats):  # interleaved, so that other jobs' load hits both alike
        pinned.append(bearings_run(arguments, threads=1))
        unpinned.append(bearings_run(arguments, threads=cores))
    best_pinned = min(pinned, key=lambda c: c.cpu_s)
    best_unpinned = min(unpinned, key=lambda c: c.cpu_s)
    return {
        "cores": cores,
        "explore_sim_time_s": seconds,
        "blas_pinned_cpu_s": round(best_pinned.cpu_s, 3),
        "blas_unpinned_cpu_s": round(best_unpinned.cpu_s, 3),
        "blas_cpu_ratio": round(best_unpinned.cpu_s / best_pinned.cpu_s, 3),
        "blas_pinned_wall_s": round(min(c.wall_s for c in pinned), 3),
        "blas_unpinned_wall_s": round(min(c.wall_s for c in unpinned), 3),
        "blas_wall_ratio": round(min(c.wall_s for c in unpinned) / min(c.wall_s for c in pinned), 3),
    }


def _cameras(repeats: int) -> dict:
    from drivers.sim.world import load_world

    every = [camera.name for camera in load_world("lab").cameras]
    walls: dict[str, float] = {}
    sizes: dict[str, int] = {}
    with tempfile.TemporaryDirectory() as folder:
        for name, cameras in (("read", None), ("all", every)):
            mission = Path(folder) / f"square_{name}.yaml"
            listed = "[" + ", ".join(cameras) + "]" if cameras is not None else "null"
            text = SQUARE.format(name=name, cameras=listed)
            mission.write_text(text if cameras is not None else text.replace("cameras: null\n", ""))
            recording = Path(folder) / f"{name}.rrd"
            arguments = [str(mission), "--sim", "lab", "--save", str(recording)]
            walls[name] = min(bearings_run(arguments, threads=1).wall_s for _ in range(repeats))
            sizes[name] = recording.stat().st_size
    return {
        "cameras_in_world": len(every),
        "cameras_read_wall_s": round(walls["read"], 3),
        "cameras_all_wall_s": round(walls["all"], 3),
        "cameras_wall_ratio": round(walls["all"] / walls["read"], 3),
        "cameras_read_recording_bytes": sizes["read"],
        "cameras_all_recording_bytes": sizes["all"],
        "cameras_recording_ratio": round(sizes["all"] / sizes["read"], 3),
    }


def run(quick: bool = False) -> dict:
    repeats = 1 if quick else 3
    return {**_blas(quick, repeats), **_cameras(repeats)}
