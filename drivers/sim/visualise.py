"""Logging a simulation to rerun: the world from above, trajectories, pan-tilt view.

The simulation calls :meth:`RerunLogger.log` once per recorded tick, handing itself in as the
:class:`Simulated` it is (this module does not know the simulation, only what it reads of it).
The world is logged once (static); poses are two points per tick, the people (they move) a point
each; the trajectories are re-logged as line strips only every ``trail_every`` ticks (decimated).
Camera images are not the simulator's to log: the recorder logs the frames the mission grabbed,
on a robot as here (``missions/images.py``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Protocol

import numpy as np

from drivers.sim.cameras import SimCamera
from drivers.sim.ptu import SimPanTilt
from drivers.sim.world_values import World
from perception.geometry import Pose2D

WALL_COLOUR = (200, 200, 200)
TRUE_COLOUR = (60, 200, 60)
ODOM_COLOUR = (230, 120, 40)
LANDMARK_COLOUR = (80, 140, 255)
PERSON_COLOUR = (230, 60, 160)


class Simulated(Protocol):
    """What the logger reads of a simulation (:class:`drivers.sim.simulation.Simulation` is one)."""

    @property
    def world(self) -> World: ...

    @property
    def ptu(self) -> SimPanTilt | None: ...

    @property
    def cameras(self) -> Mapping[str, SimCamera]: ...

    def true_pose(self) -> Pose2D: ...

    def odometry_in_world(self) -> np.ndarray: ...

    def true_trajectory(self) -> np.ndarray: ...

    def odometry_trajectory_in_world(self) -> np.ndarray: ...

    def people_xy(self) -> np.ndarray: ...


class RerunLogger:
    """Per-simulation rerun logging state (what was logged already, tick counter)."""

    def __init__(self, *, trail_every: int = 20, max_trail: int = 2000) -> None:
        self.trail_every = max(1, int(trail_every))
        self.max_trail = max_trail
        self._ticks = 0
        self._world_logged = False

    def log(self, sim: Simulated, rec: Any) -> None:
        """Log this tick; ``rec`` is the ``rerun`` module or a ``rerun.RecordingStream``."""
        import rerun as rr

        if not self._world_logged:
            self._log_world(sim, rec, rr)
            self._world_logged = True
        self._log_poses(sim, rec, rr)
        if self._ticks % self.trail_every == 0:
            for name, rows, colour in (
                ("true", sim.true_trajectory(), TRUE_COLOUR),
                ("odometry", sim.odometry_trajectory_in_world(), ODOM_COLOUR),
            ):
                if len(rows) > self.max_trail:
                    rows = rows[np.linspace(0, len(rows) - 1, self.max_trail).round().astype(int)]
                rec.log(f"world/ground_truth/trajectory_{name}", rr.LineStrips2D([rows], colors=[colour], radii=0.02))
        self._ticks += 1

    @staticmethod
    def _log_poses(sim: Simulated, rec: Any, rr: Any) -> None:
        """The true and odometry poses, the heading, the people and the pan-tilt view direction."""
        true, odom = sim.true_pose(), sim.odometry_in_world()
        rec.log("world/ground_truth/robot", rr.Points2D([[true.x, true.y]], radii=0.1, colors=[TRUE_COLOUR]))
        rec.log("world/ground_truth/odometry", rr.Points2D([[odom[0], odom[1]]], radii=0.06, colors=[ODOM_COLOUR]))
        heading = [[0.4 * math.cos(true.theta), 0.4 * math.sin(true.theta)]]
        rec.log(
            "world/ground_truth/heading", rr.Arrows2D(vectors=heading, origins=[[true.x, true.y]], colors=[TRUE_COLOUR])
        )
        if sim.world.people:
            radii = [person.radius for person in sim.world.people]
            rec.log("world/people", rr.Points2D(sim.people_xy(), radii=radii, colors=[PERSON_COLOUR]))
        if sim.ptu is not None:
            state = sim.ptu.state()
            direction = true.theta + state.pan
            reach = 1.5 * math.cos(state.tilt)
            rec.log(
                "world/ground_truth/ptu_view",
                rr.Arrows2D(
                    vectors=[[reach * math.cos(direction), reach * math.sin(direction)]],
                    origins=[[true.x, true.y]],
                    colors=[(255, 220, 0)],
                ),
            )

    @staticmethod
    def _log_world(sim: Simulated, rec: Any, rr: Any) -> None:
        world = sim.world
        strips = [np.asarray(w.points) for w in world.walls]
        for p in world.pillars:
            a = np.linspace(0.0, 2.0 * math.pi, 25)
            strips.append(np.column_stack([p.x + p.radius * np.cos(a), p.y + p.radius * np.sin(a)]))
        if strips:
            rec.log("world/walls", rr.LineStrips2D(strips, colors=[WALL_COLOUR], radii=0.03), static=True)
        if world.landmarks:
            xy = [[lm.x, lm.y] for lm in world.landmarks]
            labels = [str(lm.id) for lm in world.landmarks]
            rec.log(
                "world/landmarks", rr.Points2D(xy, radii=0.06, colors=[LANDMARK_COLOUR], labels=labels), static=True
            )
        if world.poses:
            xy = [[p.x, p.y] for p in world.poses.values()]
            rec.log("world/poses", rr.Points2D(xy, radii=0.05, labels=list(world.poses)), static=True)
