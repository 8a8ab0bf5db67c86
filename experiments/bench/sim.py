"""Simulator figures for ``bearings bench sim --json``.

- ``panoramas_per_s_<world>``: rendered 720 x 172 panoramas (walls, floor, ceiling or sky and
  landmarks) per second in ``lab`` and ``outdoor``, along a path of poses, on one core
  (``cv2.setNumThreads(1)`` for the measurement).
- ``remap_reference_ms``: one bare ``cv2.remap`` of a 720 x 172 image with float maps, measured in
  the same run; ``panorama_cost_ratio_<world>`` = one panorama / that reference.
- ``steps_per_s_bearings``: simulated steps per second in bearings mode (``lab``: command the
  base, step 50 ms, grab the ``landmarks`` sensor), the fast mode for large experiments.
- ``other_cameras_ms``: per-frame times of the other rendered cameras in ``lab`` (after their
  lookup tables are built).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable

import cv2
import numpy as np

from drivers.sim.simulation import Simulation
from perception.geometry import Pose2D


def _rate(fn: Callable[[int], object], count: int, repeats: int = 3) -> float:
    """Best-of-``repeats`` calls per second of ``fn(i)`` over ``count`` calls."""
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for i in range(count):
            fn(i)
        best = min(best, time.perf_counter() - start)
    return count / best


def _path(sim: Simulation, count: int) -> list[Pose2D]:
    """Poses on a loop around the world's start (turning as it goes), away from obstacles."""
    s = sim.world.start
    poses = []
    for i in range(count):
        a = 2.0 * math.pi * i / count
        p = Pose2D(s.x + 0.5 * math.cos(a), s.y + 0.5 * math.sin(a), s.theta + a)
        poses.append(p if sim.scene.clearance(p.x, p.y) > 0.3 else s)
    return poses


def run(quick: bool = False) -> dict:
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        return _measure(quick)
    finally:
        cv2.setNumThreads(threads)


def _measure(quick: bool) -> dict:
    n = 100 if quick else 1000
    figures: dict = {"threads": 1}
    rng = np.random.default_rng(0)
    image = rng.integers(0, 256, (172, 720), dtype=np.uint8)
    u, v = np.meshgrid(np.arange(720, dtype=np.float32), np.arange(172, dtype=np.float32))
    map_u, map_v = (u * 0.97 + 5.0).astype(np.float32), (v * 0.95 + 3.0).astype(np.float32)
    remap_rate = _rate(lambda i: cv2.remap(image, map_u, map_v, cv2.INTER_LINEAR), n)
    figures["remap_reference_ms"] = round(1e3 / remap_rate, 4)
    for world in ("lab", "outdoor"):
        sim = Simulation.load(world, seed=0)
        poses = _path(sim, 64)
        sim.snapshot(poses[0])  # textures and lookup tables are built once, outside the timing
        rate = _rate(functools.partial(_snapshot_on_path, sim, poses), n)
        figures[f"panoramas_per_s_{world}"] = round(rate, 1)
        figures[f"panorama_cost_ratio_{world}"] = round(remap_rate / rate, 3)
    sim = Simulation.load("lab", seed=0, start=Pose2D(4.3, 2.3, 0.0))  # a 1.5 m circle clear of obstacles
    sensor = sim.robot.cameras["landmarks"]

    def bearings_step(i: int) -> None:
        sim.robot.base.drive(0.3, 0.4)
        sim.step(0.05)
        sensor.grab()

    figures["steps_per_s_bearings"] = round(_rate(bearings_step, n, repeats=1), 1)

    sim = Simulation.load("lab", seed=0)
    start = sim.world.start
    others = {}
    for name in ("omni", "front", "stereo"):
        sim.snapshot(start, name)
        others[name] = round(1e3 / _rate(functools.partial(_snapshot_at, sim, start, name), max(5, n // 20)), 3)
    figures["other_cameras_ms"] = others
    return figures


def _snapshot_on_path(sim: Simulation, poses: list[Pose2D], i: int) -> object:
    return sim.snapshot(poses[i % len(poses)])


def _snapshot_at(sim: Simulation, pose: Pose2D, camera: str, _i: int) -> object:
    return sim.snapshot(pose, camera)
