"""The avoidance's phases on a hand-set clock: pass, wait for a person to pass, detour, give up.

The robot is the simulator's 0.26 m disc; a person straight ahead is a point 0.6 m from its centre:
0.34 m from the disc, 0.24 m from the disc grown by the 0.1 m clearance, short of what a 0.3 m/s
wish needs (0.3^2 / 0.5 + 0.3 * 0.5 = 0.33 m).
"""

from __future__ import annotations

import numpy as np
import pytest

from maps.avoidance.detour import Avoidance
from maps.avoidance.state import DetourSettings
from maps.avoidance.sweep import AvoidSettings
from perception.echo_map import EchoMap
from perception.geometry import Pose2D
from perception.polygons import disc

NOTHING = np.zeros((0, 2))
PERSON = np.array([[0.6, 0.0]])
BOXED_IN = np.array([[0.45 * np.cos(a), 0.45 * np.sin(a)] for a in np.linspace(-np.pi / 2, np.pi / 2, 13)])
HERE = Pose2D()
KEPT = EchoMap(points=BOXED_IN, stamps=np.zeros(len(BOXED_IN)))  # the same echoes kept longer (HERE: odometry = base)


def avoidance(**detour: float | bool) -> Avoidance:
    return Avoidance(AvoidSettings(disc(0.26)), DetourSettings(**detour))


def test_a_free_way_and_anything_but_driving_forwards_pass_unchanged():
    a = avoidance()
    assert a.step(0.3, 0.1, NOTHING, HERE, 0.0).passed
    assert a.step(0.3, 0.1, np.array([[2.0, 0.0]]), HERE, 0.1).passed  # 1.64 m away: free for far more than 0.33
    turn = a.step(0.0, 0.5, BOXED_IN, HERE, 0.2)  # turning on the spot and backing: the monitor's to judge
    back = a.step(-0.1, 0.0, BOXED_IN, HERE, 0.3)
    assert turn.passed and back.passed and a.tally.waits == 0


def test_a_person_walking_across_is_waited_for():
    a = avoidance()
    held = a.step(0.3, 0.0, PERSON, HERE, 0.0)
    assert (held.v, held.w, held.phase, held.passed) == (0.0, 0.0, "waiting", False)
    assert held.event == "the way is blocked 0.34 m ahead: waiting"
    assert a.step(0.3, 0.0, PERSON, HERE, 0.5).phase == "waiting"
    gone = a.step(0.3, 0.0, NOTHING, HERE, 1.2)  # they walked on
    assert gone.passed and gone.event == "the way cleared after 1.2 s"
    assert a.tally.waits == 1 and a.tally.waits_cleared == 0  # counted once the way has stayed clear ...
    a.step(0.3, 0.0, NOTHING, HERE, 2.2)
    assert (a.tally.waits_cleared, a.tally.wait_time, a.tally.detours) == (1, pytest.approx(1.2), 0)


def test_a_way_blocked_again_at_once_resumes_the_same_wait():
    a = avoidance(wait=2.0)
    a.step(0.3, 0.0, PERSON, HERE, 0.0)
    a.step(0.3, 0.0, NOTHING, HERE, 0.5)  # a missed echo
    again = a.step(0.3, 0.0, PERSON, HERE, 0.6)
    assert again.phase == "waiting" and again.event == "" and a.tally.waits == 1
    assert a.step(0.3, 0.0, PERSON, HERE, 2.0).phase == "detour"  # 2 s after the first hold, not the second


def test_a_person_standing_still_is_driven_around_after_the_wait():
    a = avoidance(wait=2.0)
    for t in np.arange(0.0, 2.0, 0.1):
        assert a.step(0.3, 0.0, PERSON, HERE, float(t)).phase == "waiting"
    detour = a.step(0.3, 0.0, PERSON, HERE, 2.0)
    assert detour.phase == "detour" and detour.choice is not None and detour.choice.direction is not None
    side = np.sign(detour.choice.direction.angle)
    assert detour.w == pytest.approx(side * np.radians(45.0))  # more than 30 deg off the heading: turn first
    assert detour.v == 0.0 and detour.event == f"detour to the {'left' if side > 0 else 'right'} after 2.0 s"
    # the person left behind: the wish's own arc is free again, it passes, and after clear_time the detour ends
    past = Pose2D(0.8, 0.3 * side, 0.0)
    assert a.step(0.3, 0.0, NOTHING, past, 2.5).passed
    end = a.step(0.3, 0.0, NOTHING, past, 3.5)
    assert end.phase == "clear" and end.event.startswith("past the obstacle: a detour of 0.85 m")
    assert (a.tally.detours, a.tally.detour_length, a.tally.detour_time) == (1, pytest.approx(0.854, abs=1e-3),
                                                                             pytest.approx(1.5))
    assert a.tally.wait_time == pytest.approx(2.0)


def test_boxed_in_it_gives_up_after_the_timeout_with_the_reason():
    a = avoidance(wait=2.0, timeout=20.0)
    for t in np.arange(0.0, 20.0, 0.5):
        decision = a.step(0.3, 0.0, BOXED_IN, HERE, float(t))
        assert decision.phase == "waiting" and not decision.gave_up
    gave_up = a.step(0.3, 0.0, BOXED_IN, HERE, 20.0)
    assert (gave_up.v, gave_up.w) == (0.0, 0.0)
    assert gave_up.gave_up == "blocked for 20 s by an obstacle 0.19 m ahead"
    assert a.tally.give_ups == 1 and a.tally.reasons == [gave_up.gave_up] and a.phase == "clear"


def test_a_hold_cut_short_by_the_nodes_ending_goes_on_counting_where_the_robot_stood():
    # a route follower that loses the trail for a moment in front of a person ends and starts again
    a = avoidance(wait=2.0, timeout=5.0)
    a.step(0.3, 0.0, BOXED_IN, HERE, 0.0)
    a.reset(1.5)
    assert a.step(0.3, 0.0, BOXED_IN, HERE, 1.7).event == "the way is blocked 0.19 m ahead: waiting"
    assert a.step(0.3, 0.0, BOXED_IN, HERE, 4.9).gave_up == ""
    assert a.step(0.3, 0.0, BOXED_IN, HERE, 5.0).gave_up.startswith("blocked for 5 s by an obstacle")
    assert a.tally.waits == 2 and a.tally.wait_time == pytest.approx(1.5 + 3.3)  # each hold once
    b = avoidance(wait=2.0, timeout=5.0)  # held again elsewhere, or later: a new hold
    b.step(0.3, 0.0, BOXED_IN, HERE, 0.0)
    b.reset(1.5)
    b.step(0.3, 0.0, BOXED_IN, Pose2D(0.1, 0.0, 0.0), 1.7)
    assert b.step(0.3, 0.0, BOXED_IN, Pose2D(0.1, 0.0, 0.0), 6.6).gave_up == ""
    b.reset(6.6)
    b.step(0.3, 0.0, BOXED_IN, Pose2D(0.1, 0.0, 0.0), 9.0)
    assert b.step(0.3, 0.0, BOXED_IN, Pose2D(0.1, 0.0, 0.0), 13.0).gave_up == ""


def test_a_detour_whose_command_does_not_move_the_robot_is_held_and_times_out(monkeypatch):
    a = avoidance(wait=0.0, timeout=5.0)
    a.step(0.3, 0.0, PERSON, HERE, 0.0)
    assert a.step(0.3, 0.0, PERSON, HERE, 0.1).phase == "detour"
    monkeypatch.setattr("maps.avoidance.detour.steer", lambda *_: (0.0, 0.0))  # a direction, but no motion to it
    assert a.step(0.3, 0.0, PERSON, HERE, 0.2).gave_up == ""
    assert a.step(0.3, 0.0, PERSON, HERE, 5.2).gave_up.startswith("blocked for 5 s by an obstacle")


def test_with_pass_turns_a_turn_on_the_spot_passes_while_waiting_and_on_a_detour():
    a = avoidance(wait=0.0, pass_turns=True)
    a.step(0.3, 0.0, PERSON, HERE, 0.0)
    assert a.phase == "waiting" and a.step(0.0, 0.5, PERSON, HERE, 0.1).passed
    assert a.step(0.3, 0.0, PERSON, HERE, 0.2).phase == "detour"
    turn = a.step(0.0, -0.5, PERSON, HERE, 0.3)
    assert turn.passed and (turn.v, turn.w, turn.phase) == (0.0, -0.5, "detour")
    steered = avoidance(wait=0.0)  # without it, the detour steers a turn wish to its own direction
    steered.step(0.3, 0.0, PERSON, HERE, 0.0)
    steered.step(0.3, 0.0, PERSON, HERE, 0.1)
    assert not steered.step(0.0, -0.5, PERSON, HERE, 0.2).passed


def test_with_pass_turns_the_nodes_own_turns_do_not_count_as_the_detour_turning_round():
    """On a detour the motion node turns by 100 deg on the spot (passed: a homing facing its target),
    then the detour turns 100 deg more: the detour itself has turned 100 deg, not 200, and goes on;
    the same 200 deg all turned on the detour's ticks give up as going round."""
    a = avoidance(wait=0.0, pass_turns=True)
    a.step(0.3, 0.0, PERSON, HERE, 0.0)
    assert a.step(0.3, 0.0, PERSON, HERE, 0.1).phase == "detour"
    t = 0.2
    for heading in np.radians(np.arange(20.0, 100.1, 20.0)):  # the node's own turn, passed
        assert a.step(0.0, 0.5, PERSON, Pose2D(0.0, 0.0, float(heading)), t).passed
        t += 0.1
    for heading in np.radians(np.arange(100.0, 200.1, 20.0)):  # the detour's ticks
        assert a.step(0.3, 0.0, PERSON, Pose2D(0.0, 0.0, float(heading)), t).gave_up == ""
        t += 0.1
    b = avoidance(wait=0.0)
    b.step(0.3, 0.0, PERSON, HERE, 0.0)
    assert b.step(0.3, 0.0, PERSON, HERE, 0.1).phase == "detour"
    gave_up = ""
    for i, heading in enumerate(np.radians(np.arange(20.0, 200.1, 20.0))):
        gave_up = gave_up or b.step(0.3, 0.0, PERSON, Pose2D(0.0, 0.0, float(heading)), 0.2 + 0.1 * i).gave_up
    assert gave_up.startswith("the detour turned 200 deg")


def test_without_going_round_a_detour_that_turns_200_deg_goes_on():
    """A search pattern's eight turns by itself: its detours turn with it, which is not going round."""
    c = avoidance(wait=0.0, going_round=False)
    c.step(0.3, 0.0, PERSON, HERE, 0.0)
    assert c.step(0.3, 0.0, PERSON, HERE, 0.1).phase == "detour"
    for i, heading in enumerate(np.radians(np.arange(20.0, 200.1, 20.0))):  # as b above: b gave up
        decision = c.step(0.3, 0.0, PERSON, Pose2D(0.0, 0.0, float(heading)), 0.2 + 0.1 * i)
        assert decision.gave_up == "" and decision.phase == "detour"


def test_a_detour_that_turns_on_the_spot_and_gets_nowhere_gives_up_after_the_timeout():
    """Each tick a direction will do and the detour turns towards it, but the robot never gets 0.1 m
    from where it was (turning to and fro, each direction blocked once faced): after ``timeout``, it
    gives up; one that moves on does not."""
    stuck, moving = avoidance(wait=0.0, timeout=5.0), avoidance(wait=0.0, timeout=5.0)
    for a in (stuck, moving):
        a.step(0.3, 0.0, PERSON, HERE, 0.0)
        assert a.step(0.3, 0.0, PERSON, HERE, 0.1).phase == "detour"
    reasons, t, when = [], 0.2, 0.0
    while t < 6.0 and not any(reasons):
        decision = stuck.step(0.3, 0.0, PERSON, HERE, t)
        assert decision.gave_up or decision.choice.direction is not None  # never held: a direction every tick
        reasons.append(decision.gave_up)
        when, t = t, t + 0.1
    assert reasons[-1] == "the detour got nowhere for 5 s (within 0.1 m)" and when == pytest.approx(5.25, abs=0.06)
    for i in range(60):  # 0.05 m a tick along x: 3 m in 6 s, the person always 0.6 m ahead
        assert moving.step(0.3, 0.0, PERSON, Pose2D(0.05 * i, 0.0, 0.0), 0.2 + 0.1 * i).gave_up == ""


def test_a_detour_soon_after_one_given_up_near_there_takes_the_other_side():
    a = avoidance(wait=0.0, max_length=1.0)
    a.step(0.3, 0.0, PERSON, HERE, 0.0)
    first = a.step(0.3, 0.0, PERSON, HERE, 0.1)
    assert first.phase == "detour" and first.choice is not None and first.choice.side != 0
    assert a.step(0.3, 0.0, PERSON, Pose2D(1.2, 0.0, 0.0), 0.2).gave_up.startswith("a detour of 1.2 m")
    there = Pose2D(1.2, 0.0, 0.0)
    a.step(0.3, 0.0, PERSON, there, 0.3)  # held again where it gave up: waiting, then a detour
    again = a.step(0.3, 0.0, PERSON, there, 0.4)
    assert again.phase == "detour" and again.choice is not None and again.choice.side == -first.choice.side
    fresh = avoidance(wait=0.0, max_length=1.0)  # the same place without that memory: the first side again
    fresh.step(0.3, 0.0, PERSON, there, 0.3)
    assert fresh.step(0.3, 0.0, PERSON, there, 0.4).choice.side == first.choice.side
    far = Pose2D(4.0, 0.0, 0.0)  # farther than max_stray (1.5 m) from where it gave up: either side
    a.reset(0.5)
    a.step(0.3, 0.0, PERSON, far, 0.6)
    assert a.step(0.3, 0.0, PERSON, far, 0.7).choice.side == first.choice.side


def test_a_detour_that_would_stray_too_far_holds_and_gives_up_saying_so():
    a = avoidance(wait=0.0, timeout=5.0)
    assert a.step(0.3, 0.0, PERSON, HERE, 0.0).phase == "waiting"
    assert a.step(0.3, 0.0, PERSON, HERE, 0.1).phase == "detour"  # held at the origin, heading +x
    # 1.45 m to the left of that line now, something ahead and on the right: only the directions to the
    # left are free, and they end beyond 1.5 m
    wall = np.array([[0.5 * np.cos(a), 0.5 * np.sin(a)] for a in np.linspace(-2.2, 0.3, 12)])
    aside = Pose2D(0.5, 1.45, 0.0)
    held = a.step(0.3, 0.0, wall, aside, 0.2)
    assert held.choice is not None and held.choice.only_straying and (held.v, held.w) == (0.0, 0.0)
    gave_up = a.step(0.3, 0.0, wall, aside, 5.2)
    assert gave_up.gave_up.startswith("blocked for 5 s by an obstacle ")
    assert gave_up.gave_up.endswith("; no way around within 1.5 m of the path")


def test_a_detour_longer_than_max_length_gives_up():
    a = avoidance(wait=0.0, max_length=1.0)
    a.step(0.3, 0.0, PERSON, HERE, 0.0)
    a.step(0.3, 0.0, PERSON, HERE, 0.1)
    assert a.step(0.3, 0.0, PERSON, Pose2D(0.6, 0.0, 0.0), 0.2).phase == "detour"
    gave_up = a.step(0.3, 0.0, PERSON, Pose2D(1.2, 0.0, 0.0), 0.3)
    assert gave_up.gave_up == "a detour of 1.2 m did not get past the obstacle (at most 1 m)"


def test_a_stop_of_the_collision_monitor_holds_the_robot_until_a_detour():
    a = avoidance(wait=1.0)
    held = a.step(0.3, 0.0, NOTHING, HERE, 0.0, stopped=True)  # a bumper, or a point the scan does not show
    assert held.phase == "waiting" and held.event == "the way is blocked (the collision monitor stopped it): waiting"
    assert a.step(0.3, 0.0, NOTHING, HERE, 0.5).phase == "waiting"  # the stop of a zero command says nothing
    assert a.step(0.3, 0.0, NOTHING, HERE, 1.0).phase == "detour"


def test_reset_tallies_what_was_going_on():
    a = avoidance(wait=0.0)
    a.step(0.3, 0.0, PERSON, HERE, 0.0)
    a.step(0.3, 0.0, PERSON, HERE, 0.5)
    a.step(0.3, 0.0, PERSON, Pose2D(0.3, 0.0, 0.0), 1.0)
    a.reset(2.0)
    assert (a.tally.detours, a.tally.detour_length, a.tally.detour_time) == (1, pytest.approx(0.3), pytest.approx(1.5))
    assert a.phase == "clear" and a.line is None


def test_a_wish_that_stops_at_its_goal_short_of_what_blocks_is_not_held():
    """The person 0.34 m from the disc (0.24 m from it grown by the clearance) blocks the 0.33 m a 0.3 m/s
    wish needs (eq. 1); a node whose goal is 0.3 m on stops 0.04 m short of them and passes; a goal
    0.4 m on, beyond them, is held for."""
    a = avoidance()
    short = a.step(0.3, 0.0, PERSON, HERE, 0.0, reach=0.3)
    assert short.passed and short.phase == "clear" and a.tally.waits == 0
    assert a.step(0.3, 0.0, PERSON, HERE, 0.1, reach=0.4).phase == "waiting"
    assert a.step(0.3, 0.0, PERSON, HERE, 0.2).phase == "waiting"  # no goal in sight: held as before


def test_a_drive_to_a_goal_in_front_of_a_desk_arrives_without_a_hold():
    """A drive to a goal 0.12 m short of a desk's edge, ramping down as sqrt(2 a d) with the avoidance's
    a = 0.25 m/s^2 from 0.3 m/s; the base moves as commanded, 10 ticks a second. Within its last 0.43 m
    the grown footprint's sweep reaches the desk, and within its last 0.10 m the disc is nearer the
    desk than the clearance: neither holds it. Without the goal's reach the desk beyond it holds the
    drive 0.26 + 0.1 + 0.33 m short of the desk (eq. 1)."""
    desk = np.array([[0.9, y] for y in np.linspace(-0.6, 0.6, 25)])  # the desk's edge, odometry frame
    goal = 0.9 - 0.26 - 0.12
    a, x, t = avoidance(), 0.0, 0.0
    while goal - x > 0.005:
        v = min(0.3, float(np.sqrt(2 * 0.25 * (goal - x))))
        decision = a.step(v, 0.0, desk - [x, 0.0], Pose2D(x, 0.0, 0.0), t, reach=goal - x)
        assert decision.passed, f"held {goal - x:.2f} m short of the goal"
        x, t = x + 0.1 * v, t + 0.1
    assert a.tally.waits == 0 and a.tally.detours == 0
    blind = avoidance()  # the same drive, its goal unknown
    held = next(x for x in np.arange(0.0, goal, 0.01)
                if not blind.step(0.3, 0.0, desk - [x, 0.0], Pose2D(x, 0.0, 0.0), 0.0).passed)
    assert 0.9 - held == pytest.approx(0.26 + 0.1 + 0.33, abs=0.011)


def test_a_detour_ends_once_the_wishs_goal_lies_short_of_the_obstacle():
    a = avoidance(wait=0.0)
    a.step(0.3, 0.0, PERSON, HERE, 0.0)
    assert a.step(0.3, 0.0, PERSON, HERE, 0.1).phase == "detour"
    assert a.step(0.3, 0.0, PERSON, HERE, 0.2, reach=0.2).passed  # the node now stops 0.2 m on
    end = a.step(0.3, 0.0, PERSON, HERE, 1.2, reach=0.2)
    assert end.phase == "clear" and end.event.startswith("past the obstacle")


def test_a_detour_ends_when_the_wish_turns_to_a_goal_nothing_sensed_is_as_near_as():
    a = avoidance(wait=2.0)
    for t in np.arange(0.0, 2.1, 0.1):
        decision = a.step(0.3, 0.0, PERSON, HERE, float(t))
    assert decision.phase == "detour"
    # beside the person now, 0.9 m off them; the goal 0.3 m behind: the wish turns on the spot
    beside = Pose2D(0.6, 0.9, 0.0)
    person = np.array([[0.0, -0.9]])  # where the person is, seen from there
    far = a.step(0.0, 0.5, person, beside, 2.5, reach=0.7)  # 0.7 + 0.26 = 0.96 > 0.9: not yet
    assert far.phase == "detour" and not far.passed
    near = a.step(0.0, 0.5, person, beside, 2.6, reach=0.3)  # 0.3 + 0.26 = 0.56 < 0.9: a straight drive is free
    assert near.passed and near.phase == "clear" and (near.v, near.w) == (0.0, 0.5)
    assert near.event.startswith("the goal 0.30 m away, nothing nearer: a detour of")
    assert a.tally.detours == 1 and a.phase == "clear"


def test_a_wish_turning_on_the_spot_without_a_goal_in_sight_does_not_end_a_detour():
    a = avoidance(wait=2.0)
    for t in np.arange(0.0, 2.1, 0.1):
        a.step(0.3, 0.0, PERSON, HERE, float(t))
    turning = a.step(0.0, 0.5, NOTHING, Pose2D(0.6, 0.9, 0.0), 2.5)  # reach: inf
    assert turning.phase == "detour" and not turning.passed


def test_a_turn_on_the_spot_away_from_the_remembered_heading_replaces_it():
    """A detour remembers where the last forward wish headed (0.6 rad/s for 1 s: 0.6 rad left) and a
    turn on the spot the same way keeps it; a turn on the spot the other way (the node now wants
    something to the right) stands for itself: the fan's right edge, and no longer the memory."""
    same, other = avoidance(wait=0.0), avoidance(wait=0.0)
    on_the_arc = np.array([[0.55, 0.25]])  # ahead and to the left, where the wish's arc goes
    for a in (same, other):
        a.step(0.3, 0.6, on_the_arc, HERE, 0.0)
        assert a.step(0.3, 0.6, on_the_arc, HERE, 0.1).phase == "detour"
    kept = same.step(0.0, 0.8, PERSON, HERE, 0.2)
    assert kept.choice is not None and kept.choice.wish == pytest.approx(0.6)
    turned = other.step(0.0, -0.8, PERSON, HERE, 0.2)
    assert turned.choice is not None and turned.choice.wish == pytest.approx(-np.radians(120.0))
    assert other.step(0.0, -0.8, PERSON, Pose2D(0.0, 0.0, -0.3), 0.3).choice.wish == pytest.approx(
        -np.radians(120.0) + 0.3)  # the new heading is remembered: it does not swing as the robot turns


def test_a_detour_takes_no_direction_more_than_a_right_angle_from_the_wish():
    """A detour started to the right of something ahead and on its left (-40 degrees, the free
    direction nearest straight on). The robot has since turned 100 degrees right, and the node
    turns on the spot back to the left: where it heads lies 100 degrees left now. The free
    directions are straight on and to the right, 100 degrees or more from the wish, on the
    detour's side: taking them drives away from where the node heads (the office's pacer, stop
    45), so none is taken and the robot is held."""
    a = avoidance(wait=0.0)
    ahead_left = np.array([[0.6, 0.0], [0.55, 0.2], [0.5, 0.35]])
    a.step(0.3, 0.0, ahead_left, HERE, 0.0)
    started = a.step(0.3, 0.0, ahead_left, HERE, 0.1)
    assert started.phase == "detour" and started.choice is not None and started.choice.side == -1
    assert started.choice.direction is not None and started.choice.direction.angle == pytest.approx(np.radians(-40.0))
    left = np.radians(np.arange(10.0, 125.0, 5.0))
    wall_on_the_left = 0.45 * np.column_stack((np.cos(left), np.sin(left)))
    turned = a.step(0.0, 0.8, wall_on_the_left, Pose2D(0.0, 0.0, np.radians(-100.0)), 0.2)
    assert turned.choice is not None and turned.choice.wish == pytest.approx(np.radians(100.0))
    assert turned.choice.direction is None and (turned.v, turned.w) == (0.0, 0.0) and turned.phase == "detour"


def test_a_wish_held_only_by_the_margin_beside_its_way_creeps_on():
    """In a doorway (jambs 0.16 m either side of the disc) a wish curving left is held by the clearance,
    not by the jambs themselves: the footprint goes as far as it means to go and the margin farther.
    It goes on along the same arc at the creep speed, which needs less room; a point in the way (0.36 m
    ahead of the disc, short of what the wish needs and the margin) holds the robot as before."""
    xs = np.linspace(-0.2, 0.8, 11)
    jambs = np.vstack((np.column_stack((xs, np.full(11, 0.42))), np.column_stack((xs, np.full(11, -0.42)))))
    a = avoidance()
    creep = a.step(0.3, 0.45, jambs, HERE, 0.0)
    assert (creep.phase, creep.passed) == ("clear", False)
    assert (creep.v, creep.w) == pytest.approx((0.1, 0.15))  # the wish's arc (curvature 1.5 /m), slower
    assert creep.event == "held only by what lies beside the way: on at 0.1 m/s"
    assert a.step(0.3, 0.45, jambs, HERE, 0.1).event == "" and a.tally.creeps == 1  # one spell, one event
    assert avoidance().step(0.3, 0.0, jambs, HERE, 0.0).passed  # straight through: nothing holds it
    in_the_way = avoidance().step(0.3, 0.0, np.vstack((jambs, [[0.62, 0.0]])), HERE, 0.0)
    assert (in_the_way.phase, in_the_way.v) == ("waiting", 0.0)


def test_with_no_direction_within_a_right_angle_a_way_round_is_planned_on_the_echoes_kept():
    # boxed in at the front (a half circle 0.45 m away): no direction within 90 degrees of the wish will do.
    # A second after the wait (a walker gone is still in the last second's echoes) a way round is planned:
    # the echoes kept show nothing behind, so it goes back and round. It starts behind the robot, beyond the
    # fan's 120 degrees, so the robot first turns on the spot towards it.
    a = avoidance(wait=2.0, plan=True)
    assert a.step(0.3, 0.0, BOXED_IN, HERE, 0.0, echoes=KEPT).phase == "waiting"
    assert a.step(0.3, 0.0, BOXED_IN, HERE, 2.9, echoes=KEPT).phase == "waiting"
    turned = a.step(0.3, 0.0, BOXED_IN, HERE, 3.0, echoes=KEPT)
    assert turned.phase == "detour" and turned.event.startswith("no direction will do after 3.0 s: a way round of ")
    assert turned.v == 0.0 and abs(turned.w) == pytest.approx(np.radians(45.0))
    assert a.tally.ways == 1 and a.tally.detours == 1


def test_without_the_echoes_kept_or_with_plan_off_no_way_round_is_planned():
    for a, echoes in ((avoidance(wait=2.0, plan=True), None), (avoidance(wait=2.0), KEPT)):
        a.step(0.3, 0.0, BOXED_IN, HERE, 0.0, echoes=echoes)
        held = a.step(0.3, 0.0, BOXED_IN, HERE, 3.0, echoes=echoes)
        assert (held.phase, held.v, held.w, a.tally.ways) == ("waiting", 0.0, 0.0, 0)


def test_held_on_a_way_round_until_the_timeout_gives_up_saying_so():
    a = avoidance(wait=2.0, timeout=20.0, plan=True)
    a.step(0.3, 0.0, BOXED_IN, HERE, 0.0, echoes=KEPT)
    decision = a.step(0.3, 0.0, BOXED_IN, HERE, 3.0, echoes=KEPT)
    assert a.tally.ways == 1
    t = 3.0
    while not decision.gave_up and t < 30.0:  # the collision monitor stops every command
        t = round(t + 0.1, 1)
        decision = a.step(0.3, 0.0, BOXED_IN, HERE, t, stopped=True, echoes=KEPT)
    # the way's first command (a turn, at 3.0 s) moved the robot; held from the next tick (3.1 s), 20 s on
    assert t == pytest.approx(23.1)
    assert decision.gave_up.startswith("blocked for 20 s by an obstacle 0.19 m ahead; the way round planned (")
    assert decision.gave_up.endswith(" m) was not free") and a.tally.give_ups == 1

