"""A text trace of a run (``bearings run --trace S``): what the robot did, every S seconds of run time.

The rerun recording (``--save``) holds everything; a trace is what a terminal or a CI log holds.
Every ``period`` seconds of the run's clock (simulated time in the simulator) one line: the time,
the command sent to the base, the collision monitor's state, the phase of every running
``AvoidObstacles`` (clear, waiting, detour, backoff) and the feedback of every running leaf. In
the simulator also the robot's true pose and the two nearest people within 2 m (the evaluation's
view: no behaviour reads them), and a line of its own whenever the robot comes nearer to anything
than it has so far, once that is under :data:`NEAR_M` (a contact in the making). This is how the
traces in docs/obstacles-measured.md were taken: a stand-off, a detour round the wrong side, a lost trail
read off a few hundred lines.
"""

from __future__ import annotations

import math
from typing import Any, Protocol, TextIO

import numpy as np
from py_trees.common import Status

from behaviours.avoidance import AvoidObstacles
from perception.geometry import Pose2D

NEAR_M = 0.05  # m: closer than this to anything (the simulator's clearance), every new minimum is a line
PEOPLE_WITHIN_M = 2.0  # m: people nearer than this are named on a line
PEOPLE_NAMED = 2  # the nearest this many


class Truth(Protocol):
    """What the simulator knows and a robot does not (:class:`drivers.sim.simulation.Simulation`)."""

    min_clearance: float

    def true_pose(self) -> Pose2D: ...

    def people_xy(self) -> np.ndarray: ...


class Trace:
    """Called after every tick (the runner's ``on_tick``): a line every ``period`` s of run time."""

    def __init__(self, period: float, stream: TextIO) -> None:
        self.period = period
        self.stream = stream
        self._next = 0.0
        self._nearest = NEAR_M

    def __call__(self, runner: Any) -> None:
        now = runner.clock.now()
        truth = _truth(runner)
        if truth is not None and truth.min_clearance < self._nearest - 1e-4:
            self._nearest = truth.min_clearance
            self._write(f"t={now:7.1f} ** {truth.min_clearance:.3f} m from something, the nearest yet")
        if now + 1e-9 < self._next:
            return
        self._next = now + self.period
        self._write(line(runner, now, truth))

    def _write(self, text: str) -> None:
        self.stream.write(text + "\n")
        self.stream.flush()


def line(runner: Any, now: float, truth: Truth | None) -> str:
    """One trace line (module docstring)."""
    command = runner.last_command
    parts = [f"t={now:7.1f}"]
    pose = None if truth is None else truth.true_pose()
    if pose is not None:
        parts.append(f"true=({pose.x:.2f},{pose.y:.2f},{math.degrees(pose.theta):4.0f}deg)")
    parts.append(f"cmd=({command.v:.2f},{command.w:.2f})")
    parts.append(f"safety={runner.guard.state.state}")
    running = [node for node in runner.root.iterate() if node.status == Status.RUNNING]
    phases = [node.avoidance.phase for node in running if isinstance(node, AvoidObstacles)]
    if phases:
        parts.append("avoid=" + ",".join(phases))
    if truth is not None and pose is not None:
        parts.extend(_people(truth, pose))
    leaves = [node for node in running if not node.children]
    said = [f"{node.name}: {node.feedback_message}" for node in leaves if node.feedback_message]
    return " ".join(parts) + (" | " + "; ".join(said) if said else "")


def _people(truth: Truth, pose: Pose2D) -> list[str]:
    people = np.asarray(truth.people_xy(), dtype=float).reshape(-1, 2)
    if not len(people):
        return []
    gaps = np.hypot(people[:, 0] - pose.x, people[:, 1] - pose.y)
    nearest = [i for i in np.argsort(gaps)[:PEOPLE_NAMED] if gaps[i] < PEOPLE_WITHIN_M]
    return [f"person{i}=({people[i, 0]:.2f},{people[i, 1]:.2f}) {gaps[i]:.2f}m" for i in nearest]


def _truth(runner: Any) -> Truth | None:
    """The simulation among the run's observers, if the run is simulated."""
    for observer in runner.observers:
        if hasattr(observer, "true_pose") and hasattr(observer, "people_xy"):
            return observer
    return None
