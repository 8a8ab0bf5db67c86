"""Simulator figures for ``bearings bench sim --json``.

- ``panoramas_per_s_<world>``: rendered 720 x 172 panoramas (walls, floor, ceiling or sky and
  landmarks) per second in ``lab`` and ``outdoor``, along a path of poses, on one core
  (``cv2.setNumThreads(1)`` for the measurement); ``lab_people``: ``lab`` with four people walking
  across it (they step between frames), the cost of rendering people.
- ``remap_reference_ms``: one bare ``cv2.remap`` of a 720 x 172 image with float maps, measured in
  the same run; ``panorama_cost_ratio_<world>`` = one panorama / that reference.
- ``steps_per_s_bearings``: simulated steps per second in bearings mode (``lab``: command the
  base, step 50 ms, grab the ``landmarks`` sensor), the fast mode for large experiments.
- ``sonar_read_ms``: one read of the sonar ring and bumpers after a 100 ms step (``lab``: about
  three transducers per ring fire), what the runner's sensing branch adds to every tick.
- ``other_cameras_ms``: per-frame times of the other rendered cameras in ``lab`` (after their
  lookup tables are built).
- ``render_bytes_per_pixel``: the renderer's peak memory per pixel (``pinhole``: through lookup
  tables, as every camera but a level panorama; ``level_panorama``: ray-cast directly), the
  growth of a fresh process's peak resident memory between two sizes of one camera, divided by
  the pixels added; ``render_bytes_per_pixel_budgeted``: the figures the world loader budgets
  cameras with (``drivers.sim.world_file``), which must not be below the measured ones.
"""

from __future__ import annotations

import functools
import json
import math
import os
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from drivers.sim.simulation import Simulation
from drivers.sim.world import load_world
from drivers.sim.world_file import LEVEL_PANORAMA_BYTES_PER_PIXEL, RENDER_BYTES_PER_PIXEL
from drivers.sim.world_values import Person, TextureSpec
from perception.geometry import Pose2D

WALKERS = (((1.0, 4.0), (7.0, 4.0)), ((3.5, 1.0), (3.5, 5.0)), ((6.5, 1.2), (6.5, 4.8)), ((1.0, 1.0), (6.0, 5.0)))
"""Four people walking across the lab (bench ``lab_people``)."""


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
    for world in ("lab", "outdoor", "lab_people"):
        sim = _lab_with_people() if world == "lab_people" else Simulation.load(world, seed=0)
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
    ranges = sim.robot.ranges
    assert ranges is not None, "the lab's robot has the default sonar ring"

    def sonar_step(i: int) -> None:
        sim.step(0.1)
        ranges.read()

    step_rate = _rate(lambda i: sim.step(0.1), n)
    figures["sonar_read_ms"] = round(max(0.0, 1e3 / _rate(sonar_step, n) - 1e3 / step_rate), 4)

    sim = Simulation.load("lab", seed=0)
    start = sim.world.start
    others = {}
    for name in ("omni", "front", "stereo"):
        sim.snapshot(start, name)
        others[name] = round(1e3 / _rate(functools.partial(_snapshot_at, sim, start, name), max(5, n // 20)), 3)
    figures["other_cameras_ms"] = others
    figures["render_bytes_per_pixel"] = render_bytes_per_pixel(quick)
    figures["render_bytes_per_pixel_budgeted"] = {"pinhole": RENDER_BYTES_PER_PIXEL,
                                                  "level_panorama": LEVEL_PANORAMA_BYTES_PER_PIXEL}
    return figures


def _lab_with_people() -> Simulation:
    lab = load_world("lab")
    people = tuple(Person(path, 0.25, 1.75, TextureSpec(seed=500 + i, feature_size=0.1, brightness=90.0))
                   for i, path in enumerate(WALKERS))
    return Simulation(replace(lab, people=people, name="lab_people"), seed=0)
_PEAK_RSS = """
import json, sys, tempfile
from drivers.sim.simulation import Simulation
from maps.store import dump_yaml, load_yaml

def peak():  # this process's own high-water mark (getrusage's can start at the parent's, from the fork)
    status = open("/proc/self/status").read().split("VmHWM:")[1]
    return int(status.split()[0]) * 1024

world = dict(load_yaml(sys.argv[1]))
camera = {"name": "measured", "kind": sys.argv[2], "mount": "base", "pose": {"z": 0.9},
          "model": json.loads(sys.argv[3])}
warm = {"name": "warm", "kind": "pinhole", "mount": "base", "pose": {"z": 0.9},
        "model": {"width": 32, "height": 24, "fx": 25.0, "fy": 25.0, "cx": 15.5, "cy": 11.5}}
world["cameras"] = [camera, warm]
with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as handle:
    handle.write(dump_yaml(world))
sim = Simulation.load(handle.name, seed=0)
sim.snapshot(sim.world.start, "warm")  # textures and the process's own growth, before the measurement
before = peak()
sim.snapshot(sim.world.start, "measured")
print(peak() - before)
"""


def render_bytes_per_pixel(quick: bool) -> dict[str, int]:
    """Per way of rendering, the peak memory per pixel (see the module doc): each size measured in a
    fresh process, since a process's peak never comes down."""
    scale = 1 if quick else 2
    sizes = {"pinhole": ("pinhole", [(320 * scale * k, 240 * scale * k) for k in (1, 2)]),
             "level_panorama": ("panorama", [(720 * scale * k, 172 * scale * k) for k in (1, 2)])}
    figures = {}
    for name, (kind, (small, large)) in sizes.items():
        peaks = [(w * h, _peak_rss(kind, _model(kind, w, h))) for w, h in (small, large)]
        figures[name] = round((peaks[1][1] - peaks[0][1]) / (peaks[1][0] - peaks[0][0]))
    return figures


def _model(kind: str, width: int, height: int) -> dict:
    if kind == "pinhole":
        return {"width": width, "height": height, "fx": 0.8 * width, "fy": 0.8 * width, "cx": width / 2 - 0.5,
                "cy": height / 2 - 0.5}
    return {"width": width, "height": height, "deg_per_px": 360.0 / width, "horizon_row": height // 3}


def _peak_rss(kind: str, model: dict) -> int:
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (str(root), os.environ.get("PYTHONPATH")) if p)}
    done = subprocess.run([sys.executable, "-c", _PEAK_RSS, str(root / "drivers" / "worlds" / "lab.yaml"), kind,
                           json.dumps(model)], capture_output=True, text=True, check=True, env=env, timeout=600)
    return int(done.stdout.split()[-1])


def _snapshot_on_path(sim: Simulation, poses: list[Pose2D], i: int) -> object:
    if sim.world.people:  # the people walk on between frames (the robot far away: nobody waits)
        sim.crowd.step(0.1, (1e6, 1e6), sim.world.robot_radius)
        sim.scene.move_people(sim.crowd.xy)
    return sim.snapshot(poses[i % len(poses)])


def _snapshot_at(sim: Simulation, pose: Pose2D, camera: str, _i: int) -> object:
    return sim.snapshot(pose, camera)
