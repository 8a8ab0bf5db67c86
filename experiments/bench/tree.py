"""Tick overhead of the runner on a 30-node tree, next to bare py_trees ticking the same tree.

Figures: microseconds per tick for (a) py_trees ``tick_once`` of the task tree alone, (b) the
runner's whole tick (sense branch, task tree, command clearing and dispatch) without the
simulator, and (c) the same with the empty-world simulator stepped each tick; ratios b/a and c/a.
And (d) one check of the collision monitor, which the runner makes every tick on a robot with
range sensors: a Pioneer 3-DX's 16 sonar readings against its box footprint and default zones,
an arc command; ratio d/a.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np
import py_trees

from behaviours.clock import ManualClock
from drivers.fake import fake_robot
from drivers.pioneer_body import BODIES
from drivers.safety.settings import monitor_config
from drivers.sim.simulation import Simulation
from missions.builder import build_node
from missions.loader import load_mission
from missions.runner import Runner, RunOptions
from perception.collision_monitor import CollisionMonitor
from perception.ranges import RangeScan

BRANCH = """
      - Sequence:
          memory: false
          children:
            - CheckBlackboard: {key: /robot/stalled, op: "==", value: false}
            - Wait: {duration: 1.0e9}"""
HEAD = "mission: bench-30\ncameras: []  # rendering is measured by 'bearings bench sim'\n"
MISSION = HEAD + "tree:\n  Parallel:\n    policy: all\n    synchronise: false\n    children:" + BRANCH * 9 + """
      - Drive: {distance: 1000.0, speed: 0.01}
      - Rotate: {angle: 100000.0, speed: 1.0}
"""


def _mission():
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "bench.yaml"
        path.write_text(MISSION)
        return load_mission(path)


def _time_runner(mission, ticks: int, *, simulate: bool) -> float:
    if simulate:
        simulation = Simulation.load(None, seed=0)
        robot = simulation.robot
    else:
        simulation, robot = None, fake_robot()
    options = RunOptions(max_time_s=ticks / mission.rate_hz)
    if simulation is not None:
        runner = Runner(mission, robot, clock=simulation.clock(), observers=[simulation], options=options)
    else:  # no world to step: a manual clock jumps from tick to tick, no sleeping
        runner = Runner(mission, robot, clock=ManualClock(), options=options)
    start = time.perf_counter()
    result = runner.run()
    elapsed = time.perf_counter() - start
    assert result.ticks == ticks, (result.ticks, result.reason)
    return elapsed / ticks * 1e6


def _time_bare(mission, ticks: int) -> float:
    py_trees.blackboard.Blackboard.clear()
    task = build_node(mission.tree, mission.registry)
    clock = ManualClock()
    for node in task.iterate():
        node.setup(clock=clock)
    py_trees.blackboard.Blackboard.set("/robot/stalled", False)
    from perception.geometry import Pose2D

    py_trees.blackboard.Blackboard.set("/robot/odometry", Pose2D())
    start = time.perf_counter()
    for i in range(ticks):
        task.tick_once()
        clock.set((i + 1) * 0.1)
    return (time.perf_counter() - start) / ticks * 1e6


def _time_monitor(checks: int) -> float:
    body = BODIES["p3dx"]
    monitor = CollisionMonitor(monitor_config(None, body.footprint))
    scan = RangeScan(body.sensors(), np.random.default_rng(0).uniform(0.2, 3.0, len(body.sonar)), 0.0)
    start = time.perf_counter()
    for _ in range(checks):
        monitor.check(0.3, 0.4, scan, 0.0)
    return (time.perf_counter() - start) / checks * 1e6


def run(quick: bool = False) -> dict:
    mission = _mission()
    nodes = sum(1 for _ in mission.tree.walk())
    ticks = 300 if quick else 3000
    best = {"bare": float("inf"), "runner": float("inf"), "runner_sim": float("inf"), "monitor": float("inf")}
    for _ in range(1 if quick else 3):
        best["bare"] = min(best["bare"], _time_bare(mission, ticks))
        best["runner"] = min(best["runner"], _time_runner(mission, ticks, simulate=False))
        best["runner_sim"] = min(best["runner_sim"], _time_runner(mission, ticks, simulate=True))
        best["monitor"] = min(best["monitor"], _time_monitor(ticks))
    return {
        "task_tree_nodes": nodes,
        "ticks": ticks,
        "py_trees_tick_us": round(best["bare"], 2),
        "runner_tick_us": round(best["runner"], 2),
        "runner_tick_with_sim_us": round(best["runner_sim"], 2),
        "runner_overhead_ratio": round(best["runner"] / best["bare"], 3),
        "runner_with_sim_ratio": round(best["runner_sim"] / best["bare"], 3),
        "monitor_check_us": round(best["monitor"], 2),
        "monitor_check_ratio": round(best["monitor"] / best["bare"], 3),
        "max_tick_rate_hz": round(1e6 / best["runner_sim"]),
    }
