"""AvoidObstacles around a Drive, with a hand-set Pioneer 3-DX sonar ring and a manual clock.

A person 0.6 m ahead: the front transducers 3 and 4 (at (0.166, +-0.027), facing +-10 deg) read
0.45 m, echoes at (0.609, +-0.105). The simulator's 0.26 m disc grown by the 0.1 m clearance
meets them after 0.609 - sqrt(0.36^2 - 0.105^2) = 0.265 m, short of the 0.33 m a 0.3 m/s Drive
needs (0.3^2 / 0.5 + 0.3 * 0.5): the way is blocked.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from py_trees.common import Status

from behaviours.avoidance import AvoidObstacles
from behaviours.motion import Drive
from behaviours.telemetry import Event, Lines, Plot, report_sections
from behaviours.testing import BehaviourHarness
from drivers.interfaces import VelocityCommand
from drivers.pioneer_body import BODIES
from perception.collision_monitor import SafetyState
from perception.geometry import Pose2D
from perception.polygons import disc
from perception.ranges import RangeScan

RING = BODIES["p3dx"].sensors()
PERSON_AHEAD = {3: 0.45, 4: 0.45}
BOXED_IN = {i: 0.2 for i in range(len(RING))}  # every transducer 0.2 m from something: no way round


def scan(echoes: dict[int, float], stamp: float) -> RangeScan:
    ranges = np.full(len(RING), math.inf)
    for i, r in echoes.items():
        ranges[i] = r
    return RangeScan(RING, ranges, stamp)


def harness(echoes: dict[int, float], **ports: object) -> BehaviourHarness:
    node = AvoidObstacles(name="avoid", child=Drive(distance=5.0), **ports)
    return BehaviourHarness(node, blackboard={"/robot/odometry": Pose2D(), "/robot/ranges": scan(echoes, 0.0)})


def sense(h: BehaviourHarness, echoes: dict[int, float], pose: Pose2D | None = None) -> None:
    """What the sensing branch writes before a tick: the ring read now, the odometry."""
    h.write("/robot/ranges", scan(echoes, h.clock.now()))
    if pose is not None:
        h.write("/robot/odometry", pose)


def command(h: BehaviourHarness) -> tuple[float, float]:
    c = h.read("/robot/command")
    return (c.v, c.w) if c is not None else (math.nan, math.nan)


def test_a_clear_way_passes_the_childs_command_unchanged():
    h = harness({})
    assert h.tick() == Status.RUNNING
    assert command(h) == (0.3, 0.0)  # Drive's own, at its top speed
    assert report_sections(h.behaviour)["avoidance"]["avoid"]["waits"] == 0


def test_the_way_is_judged_for_the_robots_own_footprint_unless_a_radius_is_given():
    # Something 1 m ahead: transducers 3 and 4 read 0.85 m, echoes at (1.003, +-0.175). The 0.26 m disc
    # grown by 0.1 m meets them after 1.003 - sqrt(0.36^2 - 0.175^2) = 0.688 m, past the 0.33 m a 0.3 m/s
    # Drive needs; a robot of 0.65 m (grown: 0.75 m) after 1.003 - sqrt(0.75^2 - 0.175^2) = 0.274 m: blocked.
    ahead = {3: 0.85, 4: 0.85}
    small = harness(ahead)  # no footprint published (no runner): a P3-DX's 0.26 m disc
    assert small.tick() == Status.RUNNING and command(small) == (0.3, 0.0)
    big = harness(ahead)
    big.write("/robot/footprint", disc(0.65))  # what the runner publishes: the collision monitor's footprint
    assert big.tick() == Status.RUNNING and command(big) == (0.0, 0.0)
    assert big.behaviour.feedback_message.startswith("the way is blocked")
    told = harness(ahead, robot_radius=0.26)  # a radius given in the mission wins
    told.write("/robot/footprint", disc(0.65))
    assert told.tick() == Status.RUNNING and command(told) == (0.3, 0.0)


def test_a_person_walking_across_is_waited_for_and_the_child_drives_on():
    h = harness(PERSON_AHEAD)
    assert h.tick() == Status.RUNNING and command(h) == (0.0, 0.0)
    assert h.behaviour.feedback_message.startswith("the way is blocked 0.3")
    for _ in range(10):  # a second: they walk past
        h.clock.advance(0.1)
        sense(h, PERSON_AHEAD)
        h.tick()
        assert command(h) == (0.0, 0.0)
    h.clock.advance(1.0)  # the echoes of the last second are forgotten
    sense(h, {})
    assert h.tick() == Status.RUNNING and command(h) == (0.3, 0.0)
    h.clock.advance(1.0)
    sense(h, {})
    h.tick()
    figures = report_sections(h.behaviour)["avoidance"]["avoid"]
    assert (figures["waits"], figures["waits_cleared"], figures["detours"]) == (1, 1, 0)
    assert figures["wait_time_s"] == pytest.approx(2.0)


def test_what_stays_in_the_way_is_driven_round_after_the_wait():
    h = harness(PERSON_AHEAD, wait=2.0)
    status = h.tick_until(lambda s: h.behaviour.decision.phase == "detour", between=lambda h: sense(h, PERSON_AHEAD))
    assert status == Status.RUNNING and h.clock.now() == pytest.approx(2.0)
    v, w = command(h)
    assert (v, w) != (0.0, 0.0) and w != 0.0  # turning away from the person (on the spot, or along an arc)
    drawn = list(h.behaviour.drawings())
    assert Event("avoidance/events", "the way is blocked 0.37 m ahead: waiting") in drawn
    assert any(isinstance(d, Event) and d.text.startswith("detour to the ") for d in drawn)
    histogram = next(d for d in drawn if isinstance(d, Lines) and d.entity == "avoidance/robot_frame/histogram")
    assert len(histogram.strips) == 25 and Plot("avoidance/phase", 2.0) in drawn
    assert report_sections(h.behaviour)["avoidance"]["avoid"]["detours"] == 1


def test_boxed_in_it_gives_up_after_the_timeout_and_halts_the_child():
    h = harness(BOXED_IN, timeout=5.0)
    status = h.tick_until(between=lambda h: sense(h, BOXED_IN))
    assert status == Status.FAILURE and h.clock.now() == pytest.approx(5.0, abs=0.11)
    assert h.behaviour.feedback_message.startswith("blocked for 5 s by an obstacle 0.1")
    assert h.behaviour.feedback_message.endswith(" m ahead")
    assert command(h) == (0.0, 0.0) and h.behaviour.decorated.status == Status.INVALID
    figures = report_sections(h.behaviour)["avoidance"]["avoid"]
    assert figures["give_ups"] == 1 and figures["reasons"] == [h.behaviour.feedback_message]


def test_a_detour_that_would_stray_too_far_from_the_path_gives_up_saying_so():
    # held at the origin heading +x; then 0.95 m to the left of that line with the way ahead and to
    # the right blocked: the free directions all lead more than max_stray (1 m) from it
    h = harness(PERSON_AHEAD, wait=0.0, timeout=3.0, max_stray=1.0)
    h.tick()
    blocked = {2: 0.3, 3: 0.3, 4: 0.3, 5: 0.3, 6: 0.3, 7: 0.3}
    aside = Pose2D(0.6, 0.95, 0.0)
    status = h.tick_until(between=lambda h: sense(h, blocked, aside))
    assert status == Status.FAILURE
    assert h.behaviour.feedback_message.endswith("; no way around within 1 m of the path")


def test_it_tells_the_child_while_it_waits_for_the_way_to_clear_and_not_after():
    h = harness({})
    h.tick()
    assert h.read("/robot/held") is False  # a clear way
    told = []  # (phase, what the child is told) after each tick
    h.tick_until(lambda s: h.behaviour.decision.phase == "detour",
                 between=lambda h: (told.append((h.behaviour.decision.phase, h.read("/robot/held"))),
                                    sense(h, PERSON_AHEAD)))
    assert {phase for phase, _ in told} == {"clear", "waiting"}
    assert all(held == (phase == "waiting") for phase, held in told)
    assert h.read("/robot/held") is False and command(h) != (0.0, 0.0)  # on a detour: not held
    boxed = harness(BOXED_IN, wait=1.0, timeout=3.0)
    held = {}  # tick time: what the child is told
    status = boxed.tick_until(between=lambda h: (held.update({round(h.clock.now(), 1): h.read("/robot/held")}),
                                                 sense(h, BOXED_IN)))
    assert status == Status.FAILURE and boxed.clock.now() == pytest.approx(3.0)
    assert all(held[t] for t in held if t < 0.95)  # the wait
    assert not any(held[t] for t in held if t > 1.05)  # still held after it, with no way round: not told
    assert command(boxed) == (0.0, 0.0) and boxed.read("/robot/held") is False  # gave up


def test_boxed_in_at_the_front_only_it_turns_to_a_way_round_behind_and_draws_it():
    front = {i: 0.2 for i in range(8)}  # the front transducers 0.2 m from something, nothing heard behind
    h = harness(front, wait=1.0)
    h.tick_until(lambda s: h.behaviour.decision.phase == "detour", between=lambda h: sense(h, front))
    v, w = command(h)
    assert v == 0.0 and abs(w) == pytest.approx(math.radians(45.0))  # the way starts behind: turning to it
    message = h.behaviour.feedback_message
    assert message.startswith("no direction will do after ") and ": a way round of " in message
    assert 2.0 <= float(message.split(" after ")[1].split(" s:")[0]) <= 2.1  # a second after the wait
    way = [d for d in h.behaviour.drawings() if isinstance(d, Lines) and d.entity == "odometry_frame/avoidance/way"]
    assert len(way) == 1 and len(way[0].strips) == 1 and way[0].strips[0][-1][0] >= 1.0  # a metre on (odometry)
    figures = report_sections(h.behaviour)["avoidance"]["avoid"]
    assert figures["ways"] == 1 and figures["give_ups"] == 0
    off = harness(front, wait=1.0, timeout=3.0, plan=False)  # without planning: held until the timeout
    assert off.tick_until(between=lambda h: sense(h, front)) == Status.FAILURE
    assert off.clock.now() == pytest.approx(3.0, abs=0.11)
    assert report_sections(off.behaviour)["avoidance"]["avoid"]["ways"] == 0


def test_a_stop_of_the_collision_monitor_holds_the_child_too():
    h = harness({})
    h.write("/robot/safety", SafetyState(state="stopped", action="bumper", zone="front bumper"))
    h.tick()
    assert command(h) == (0.0, 0.0)
    assert h.behaviour.feedback_message == "the way is blocked (the collision monitor stopped it): waiting"


def test_disabled_or_blind_it_passes_every_command():
    disabled = harness(BOXED_IN, enabled=False)
    assert disabled.tick() == Status.RUNNING and command(disabled) == (0.3, 0.0)
    blind = BehaviourHarness(AvoidObstacles(name="avoid", child=Drive(distance=5.0)),
                             blackboard={"/robot/odometry": Pose2D()})  # no /robot/ranges: no range sensors
    assert blind.tick() == Status.RUNNING and command(blind) == (0.3, 0.0)


def test_its_status_is_the_childs():
    h = harness({})
    assert h.tick() == Status.RUNNING
    h.write("/robot/odometry", Pose2D(5.0, 0.0, 0.0))  # Drive got there
    assert h.tick() == Status.SUCCESS
    assert h.read("/robot/command") == VelocityCommand(0.0, 0.0)


def test_a_child_that_stops_short_of_the_person_passes():
    """A Drive of 0.3 m: its command says so (``reach``), and the disc meets the echoes only after
    0.609 - sqrt(0.26^2 - 0.105^2) = 0.371 m: it stops short of the person, the avoidance lets it."""
    node = AvoidObstacles(name="avoid", child=Drive(distance=0.3))
    h = BehaviourHarness(node, blackboard={"/robot/odometry": Pose2D(), "/robot/ranges": scan(PERSON_AHEAD, 0.0)})
    assert h.tick() == Status.RUNNING and command(h) == (0.3, 0.0)
    assert h.read("/robot/command").reach == pytest.approx(0.3)
    assert report_sections(h.behaviour)["avoidance"]["avoid"]["waits"] == 0
