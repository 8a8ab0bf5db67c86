"""Held behind someone is not lost: AvoidObstacles round FollowRoute, as follow_route.yaml wires them.

A person stands close in front of the robot (every front transducer of the Pioneer 3-DX ring reads
0.2 m) and hides the view: no landmark matches. Told by the avoidance (``/robot/held``), route
following keeps the trail through the avoidance's wait (2 s), so a person who walks on within it
costs nothing; one who stays leaves no way round (boxed in), and the trail is lost ``lost_time``
after the wait, for the mission's recovery. Not told, the trail is lost ``lost_time`` after the
person stepped in, whatever they do.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.avoidance import AvoidObstacles
from behaviours.route import FollowRoute, RouteProgress
from behaviours.testing import BehaviourHarness
from drivers.interfaces import VelocityCommand
from drivers.pioneer_body import BODIES
from perception.geometry import Pose2D
from perception.observation import Observation
from perception.ranges import RangeScan
from tests.behaviours.routes import IdealBase, taught_map

TREE, PLACES = taught_map()
RING = BODIES["p3dx"].sensors()
WAIT, LOST_TIME = 2.0, 0.5


def close_person(stamp: float) -> RangeScan:
    ranges = np.full(len(RING), math.inf)
    ranges[:8] = 0.2  # the front transducers
    return RangeScan(RING, ranges, stamp)


def nothing_matches(stamp: float) -> Observation:
    return Observation(np.zeros((0, 3)), stamp, "bearings", ids=np.zeros(0, dtype=np.int64))


def following(told: bool) -> tuple[BehaviourHarness, FollowRoute, IdealBase]:
    """Following towards viewframe 3, 0.4 m short of it, the way clear."""
    wiring = {"held": "{/robot/held}"} if told else {}
    follow = FollowRoute(k=1, lost_time=LOST_TIME, **wiring)
    node = AvoidObstacles(name="avoid", child=follow, wait=WAIT)
    harness = BehaviourHarness(node, blackboard={
        "/map/ltmap": TREE, "/map/route_progress": RouteProgress(1, 3, TREE.viewframe_count, 0.0),
        "/robot/ranges": RangeScan(RING, np.full(len(RING), math.inf), 0.0)})
    base = IdealBase(harness, Pose2D(PLACES[3].x - 0.4, 0.0, 0.0))
    assert harness.tick() == Status.RUNNING and harness.read("/robot/command").v > 0
    harness.clock.advance(0.1)
    return harness, follow, base


def person_in_front(h: BehaviourHarness) -> None:
    """What the sensing branch writes for the next tick: the ring's echoes, a view with no match."""
    stamp = h.clock.now()
    h.write("/robot/ranges", close_person(stamp))
    h.write("/perception/observation", nothing_matches(stamp))


@pytest.mark.parametrize("told", [True, False])
def test_a_person_who_walks_on_within_the_wait_costs_no_lost_trail_when_told(told):
    harness, follow, base = following(told)
    statuses = []
    while harness.clock.now() < 1.55:  # stands in front for 1.5 s, hiding the view
        person_in_front(harness)
        statuses.append(harness.tick())
        harness.clock.advance(0.1)
    if not told:  # lost after lost_time, the person still there
        assert Status.FAILURE in statuses and follow.feedback_message.startswith("lost: 0 landmarks")
        return
    assert set(statuses) == {Status.RUNNING} and harness.read("/robot/held") is True
    assert harness.read("/robot/command") == VelocityCommand(0.0, 0.0)  # held
    clear = RangeScan(RING, np.full(len(RING), math.inf), 0.0)
    while harness.clock.now() < 4.0:  # walked on: the view back, the way clear once its echoes are forgotten
        harness.write("/robot/ranges", replace(clear, stamp=harness.clock.now()))
        base.sense()
        assert harness.tick() == Status.RUNNING
        base(harness)
        harness.clock.advance(0.1)
    assert harness.read("/robot/command").v > 0 and base.pose.x > PLACES[3].x - 0.4  # following on


def test_one_who_stays_leaves_the_trail_lost_after_the_wait():
    harness, follow, _ = following(True)
    person_in_front(harness)
    status = harness.tick_until(between=person_in_front)
    assert status == Status.FAILURE and follow.feedback_message.startswith("lost: 0 landmarks")
    # stepped in at 0.1 s, held for the wait, then lost for lost_time, told a tick after the avoidance judged
    assert harness.clock.now() == pytest.approx(0.1 + WAIT + 0.1 + LOST_TIME, abs=0.01)
    assert harness.read("/robot/command").v == 0.0 and harness.read("/robot/held") is False
