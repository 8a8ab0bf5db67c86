"""Helpers for the LT-map behaviour tests: a synthetic corridor, a taught map, an ideal base."""

from __future__ import annotations

import math

import numpy as np

from behaviours.testing import BehaviourHarness
from drivers.interfaces import STOP
from maps.ltmap.learner import LearnConfig, RouteLearner
from perception.geometry import Pose2D
from perception.synthetic_route import make_route_world, observe_route, straight_route

WORLD = make_route_world(0, length=3.0, n_far=60, n_near=400)


def taught_map(length: float = 3.0, kind: str = "ids"):
    """An LT-map taught along x from the origin (ideal ids, light noise) and where its viewframes are."""
    rng = np.random.default_rng(1)
    learner, places = RouteLearner(LearnConfig()), []
    for pose in straight_route(length, 0.05):
        if learner.observe(observe_route(WORLD, pose, rng, kind=kind, noise_deg=0.1), pose.theta,
                           (pose.x, pose.y)).created:
            places.append(pose)
    if learner.finish().created:
        places.append(pose)
    return learner.tree, places


class IdealBase:
    """Moves a true pose by the command each step and writes odometry (= truth) and an observation."""

    def __init__(self, harness: BehaviourHarness, pose: Pose2D, *, seed: int = 2, dt: float = 0.1) -> None:
        self.harness, self.pose, self.dt = harness, pose, dt
        self.rng = np.random.default_rng(seed)
        self.trail = [pose]
        self.sense()

    def sense(self, ahead: float = 0.0) -> None:
        stamp = self.harness.clock.now() + ahead
        pose = Pose2D(self.pose.x, self.pose.y, self.pose.theta, stamp)
        self.harness.write("/robot/odometry", pose)
        self.harness.write("/perception/observation", observe_route(WORLD, pose, self.rng, noise_deg=0.1))

    def __call__(self, harness: BehaviourHarness) -> None:
        cmd = harness.read("/robot/command") or STOP
        p = self.pose
        theta = p.theta + cmd.w * self.dt
        self.pose = Pose2D(p.x + cmd.v * self.dt * math.cos(p.theta), p.y + cmd.v * self.dt * math.sin(p.theta), theta)
        self.trail.append(self.pose)
        self.sense(self.dt)  # tick_until advances the clock after this call
