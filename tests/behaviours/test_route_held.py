"""Held behind someone is not lost: AvoidObstacles round FollowRoute, as follow_route.yaml wires them.

A person stands close in front of the robot (every front transducer of the Pioneer 3-DX ring reads
0.2 m) and hides the view: no landmark matches. Told by the avoidance (``/robot/held``), route
following keeps the trail while the robot is held, and the avoidance's timeout ends the hold with
its own reason (the mission then skips viewframes past the person); not told, route following
fails after ``lost_time`` with a lost trail (the mission then searches).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.avoidance import AvoidObstacles
from behaviours.route import FollowRoute, RouteProgress
from behaviours.testing import BehaviourHarness
from drivers.pioneer_body import BODIES
from perception.geometry import Pose2D
from perception.observation import Observation
from perception.ranges import RangeScan
from tests.behaviours.routes import IdealBase, taught_map

TREE, PLACES = taught_map()
RING = BODIES["p3dx"].sensors()
TIMEOUT, LOST_TIME = 3.0, 0.5


def close_person(stamp: float) -> RangeScan:
    ranges = np.full(len(RING), math.inf)
    ranges[:8] = 0.2  # the front transducers
    return RangeScan(RING, ranges, stamp)


def nothing_matches(stamp: float) -> Observation:
    return Observation(np.zeros((0, 3)), stamp, "bearings", ids=np.zeros(0, dtype=np.int64))


@pytest.mark.parametrize("told", [True, False])
def test_held_behind_a_person_the_avoidance_ends_the_hold_not_a_lost_trail(told):
    wiring = {"held": "{/robot/held}"} if told else {}
    follow = FollowRoute(k=1, lost_time=LOST_TIME, **wiring)
    node = AvoidObstacles(name="avoid", child=follow, timeout=TIMEOUT)
    harness = BehaviourHarness(node, blackboard={
        "/map/ltmap": TREE, "/map/route_progress": RouteProgress(1, 3, TREE.viewframe_count, 0.0),
        "/robot/ranges": RangeScan(RING, np.full(len(RING), math.inf), 0.0)})
    IdealBase(harness, Pose2D(PLACES[3].x - 0.4, 0.0, 0.0))
    assert harness.tick() == Status.RUNNING and harness.read("/robot/command").v > 0  # following

    def person_steps_in(h: BehaviourHarness) -> None:
        stamp = h.clock.now() + 0.1  # the tick after the clock's advance
        h.write("/robot/ranges", close_person(stamp))
        h.write("/perception/observation", nothing_matches(stamp))

    person_steps_in(harness)
    harness.clock.advance(0.1)
    status = harness.tick_until(between=person_steps_in)
    assert status == Status.FAILURE
    if told:  # held until the avoidance's timeout, with its reason
        assert harness.clock.now() == pytest.approx(0.1 + TIMEOUT, abs=0.11)
        assert node.feedback_message.startswith(f"blocked for {TIMEOUT:.0f} s by an obstacle")
    else:  # the trail "lost" after lost_time (the first tick held, lost since)
        assert harness.clock.now() == pytest.approx(0.1 + LOST_TIME, abs=0.11)
        assert follow.feedback_message.startswith("lost: 0 landmarks")
    assert harness.read("/robot/command").v == 0.0 and harness.read("/robot/held") is False
