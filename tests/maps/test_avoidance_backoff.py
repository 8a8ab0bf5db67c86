"""Backing away along the trail when no direction will do, with hand-set points, poses and clock.

The robot is the simulator's 0.26 m disc. The corner: points 0.35 m from its centre (0.09 m from
the disc) from -90 to +90 degrees of +x, fixed in the odometry frame at (0, 0): every
direction of the histogram (+-120 degrees) is blocked within centimetres, only straight back is
open, the way the robot came along the x axis.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.avoidance.backoff import BackoffSettings, Surroundings, Trail, back_command
from maps.avoidance.detour import BACKOFFS_PER_HOLD, Avoidance, DetourSettings
from maps.avoidance.sweep import AvoidSettings
from perception.geometry import Pose2D, parent_to_frame
from perception.polygons import disc

AVOID = AvoidSettings(disc(0.26))
CORNER = np.array([[0.35 * math.cos(a), 0.35 * math.sin(a)] for a in np.radians(np.arange(-90.0, 91.0, 10.0))])


def seen(pose: Pose2D) -> np.ndarray:
    """The corner's points in the base frame of ``pose``."""
    return np.asarray(parent_to_frame(pose, CORNER))


def drive_in(a: Avoidance, start: float = -1.0) -> float:
    """Drive along +x from ``start`` to the corner at (0, 0), 0.02 m a tick, nothing in the way (its
    trail); returns the time (s) the robot stands in the corner."""
    t = 0.0
    for x in np.arange(start, 0.0, 0.02):
        assert a.step(0.2, 0.0, np.zeros((0, 2)), Pose2D(float(x), 0.0, 0.0), t).passed
        t += 0.1
    return t


def test_the_trail_keeps_a_point_every_step_and_only_the_last_metres():
    trail = Trail(keep=0.5)
    for x in np.arange(0.0, 1.0, 0.005):  # 5 mm a tick: a point every 2 cm is kept
        trail = trail.added(Pose2D(float(x), 0.0, 0.0))
    xs = [p[0] for p in trail.points]
    assert np.allclose(np.diff(xs), 0.02, atol=0.006)
    assert xs[-1] == pytest.approx(0.98, abs=0.02) and xs[-1] - xs[0] == pytest.approx(0.5, abs=0.03)


def test_the_target_lies_as_far_back_along_the_trail_as_asked_and_the_trail_ends_there():
    trail = Trail(((0.0, 0.0), (0.2, 0.0), (0.5, 0.0), (0.6, 0.0)), keep=2.0)
    target, left = trail.target(Pose2D(0.6, 0.0, 0.0), 0.4)
    assert target == pytest.approx((0.2, 0.0))  # between 0.5 (0.1 away) and 0.2 (0.4 away): 0.4 exactly
    target, left = trail.target(Pose2D(0.6, 0.0, 0.0), 0.25)
    assert target == pytest.approx((0.35, 0.0)) and left.points[-1] == pytest.approx((0.35, 0.0))
    assert left.points[:-1] == ((0.0, 0.0), (0.2, 0.0))
    assert trail.target(Pose2D(0.6, 0.0, 0.0), 5.0)[0] == (0.0, 0.0)  # a shorter trail: its oldest point
    assert Trail(((0.55, 0.0),)).target(Pose2D(0.6, 0.0, 0.0), 0.4)[0] is None  # 5 cm of trail: no back-off


def test_the_back_off_arc_goes_through_the_target_eq_7():
    around = Surroundings.of(np.zeros((0, 2)), AVOID)
    # behind and to the right: kappa = 2 (-0.1) / (0.3^2 + 0.1^2) = -2, w = v kappa = -0.1 * -2 = 0.2 rad/s
    v, w = back_command((-0.3, -0.1), Pose2D(), around, AVOID, BackoffSettings()) or (0.0, 0.0)
    assert (v, w) == (pytest.approx(-0.1), pytest.approx(0.2))
    # the same target from a robot at (1, 1) facing +y: behind it is -y
    turned = back_command((1.1, 0.7), Pose2D(1.0, 1.0, math.pi / 2), around, AVOID, BackoffSettings())
    assert turned == (pytest.approx(-0.1), pytest.approx(0.2))


def test_something_behind_holds_the_back_off():
    settings = BackoffSettings()
    behind = Surroundings.of(np.array([[-0.30, 0.0]]), AVOID)  # 0.04 m behind the disc
    assert back_command((-0.4, 0.0), Pose2D(), behind, AVOID, settings) is None


def test_wedged_with_nothing_free_within_120_deg_it_backs_away_along_its_trail():
    a = Avoidance(AVOID, DetourSettings(wait=2.0, timeout=20.0))
    t = drive_in(a)
    here = Pose2D(0.0, 0.0, 0.0)
    assert a.step(0.3, 0.0, seen(here), here, t).phase == "waiting"
    waited = a.step(0.3, 0.0, seen(here), here, t + 1.9)
    assert (waited.phase, waited.v) == ("waiting", 0.0)
    back = a.step(0.3, 0.0, seen(here), here, t + 2.0)  # the old code: held, (0, 0), until the timeout
    assert back.phase == "backoff" and back.v == pytest.approx(-0.1) and back.w == pytest.approx(0.0)
    assert back.event == "no way round: backing away 0.40 m the way it came"
    assert a.tally.backoffs == 1
    now = t + 2.0
    for x in np.arange(-0.02, -0.39, -0.02):  # it backs, the corner's points drawing away
        now += 0.2
        pose = Pose2D(float(x), 0.0, 0.0)
        step = a.step(0.3, 0.0, seen(pose), pose, now)
        assert step.phase == "backoff" and step.v < 0.0
    there = Pose2D(-0.4, 0.0, 0.0)
    after = a.step(0.3, 0.0, seen(there), there, now + 0.2)
    assert a.tally.backoff_length == pytest.approx(0.4, abs=0.01)
    # straight ahead is free to the corner, 0.39 m, more than a detour needs (0.18 m) but not past where
    # it was wedged (0.40 + 0.18 m): no way out that way; it detours towards a direction free beyond that
    assert after.phase == "detour" and after.choice is not None and after.choice.direction is not None
    ahead = after.choice.directions[len(after.choice.directions) // 2]
    assert ahead.angle == 0.0 and 0.18 < ahead.free < 0.58 and not ahead.will_do(after.choice.reach)
    assert after.choice.reach == pytest.approx(0.58, abs=0.01) and after.choice.direction.free >= 0.58


def test_the_back_offs_of_one_hold_are_counted_and_then_it_gives_up_as_before():
    # people keeping round the robot as it backs: the corner's points the same in the base frame
    a = Avoidance(AVOID, DetourSettings(wait=2.0, timeout=20.0), BackoffSettings(distance=0.1))
    t = drive_in(a, start=-2.0)
    pose, now = Pose2D(0.0, 0.0, 0.0), t
    backoffs = 0
    while now < t + 25.0:
        d = a.step(0.3, 0.0, CORNER, pose, now)
        if d.gave_up:
            break
        if d.phase == "backoff":
            backoffs = a.tally.backoffs
            pose = Pose2D(pose.x - 0.02, 0.0, 0.0)  # it goes back as commanded
        now += 0.1
    assert backoffs == BACKOFFS_PER_HOLD and a.tally.give_ups == 1
    assert now == pytest.approx(t + 20.0, abs=0.15)  # the timeout of the hold, back-offs and all
    assert a.tally.reasons[0].startswith("blocked for 20 s by an obstacle")


def test_the_holds_timeout_ends_a_back_off_still_going():
    """Held at t, backing from t + 2 s (the wait) at 0.1 m/s for 0.4 m (4 s): the 3 s timeout comes
    1 s into the back-off, which it ends (before, the give-up waited for the back-off's end, ~t + 6 s)."""
    a = Avoidance(AVOID, DetourSettings(wait=2.0, timeout=3.0))
    t = drive_in(a)
    pose = Pose2D(0.0, 0.0, 0.0)
    assert a.step(0.3, 0.0, seen(pose), pose, t).phase == "waiting"
    now = t + 2.0
    assert a.step(0.3, 0.0, seen(pose), pose, now).phase == "backoff"
    while True:
        now += 0.2
        pose = Pose2D(pose.x - 0.02, 0.0, 0.0)  # it goes back as commanded
        d = a.step(0.3, 0.0, seen(pose), pose, now)
        if d.phase != "backoff":
            break
    assert d.gave_up and now == pytest.approx(t + 3.0, abs=0.01) and (d.v, d.w) == (0.0, 0.0)
    assert d.gave_up == "blocked for 3 s: backing away 0.10 m did not free the way"
    assert a.tally.backoff_length == pytest.approx(0.10, abs=1e-9) and a.phase == "clear"


def test_without_a_trail_or_with_back_offs_off_it_stays_held():
    for a in (Avoidance(AVOID, DetourSettings(wait=2.0)),  # never moved: no trail
              Avoidance(AVOID, DetourSettings(wait=2.0), BackoffSettings(distance=0.0))):
        if a.backoff.distance:
            here = Pose2D()
        else:
            drive_in(a)
            here = Pose2D()
        for t in np.arange(10.0, 15.0, 0.5):
            d = a.step(0.3, 0.0, seen(here), here, float(t))
            assert (d.phase, d.v, d.w) == ("waiting", 0.0, 0.0)
        assert a.tally.backoffs == 0


SLOT = np.array([[x, side * 0.40] for x in np.arange(-1.0, 2.01, 0.05) for side in (-1.0, 1.0)])  # walls 0.14 m off


def test_held_while_the_wish_turns_round_it_backs_out_of_a_slot_rather_than_driving_on_into_it():
    """In a slot (walls 0.14 m beside the disc, open ahead), the monitor stops the robot and the node
    then wishes to turn round (a new goal behind it). Straight ahead is the only free direction, but
    120 degrees from the turn's edge: driving on takes the robot away from where it turns to (in
    `flat`'s exploration it drove 1 m on between a bed and a wall, never to get out). It backs out
    the way it came instead."""
    a = Avoidance(AVOID, DetourSettings(wait=2.0, timeout=20.0))
    t = drive_in(a)
    pose = Pose2D(0.0, 0.0, 0.0)
    assert a.step(0.2, 0.0, SLOT, pose, t, stopped=True).phase == "waiting"
    for now in np.arange(t + 0.1, t + 2.0, 0.1):
        assert a.step(0.0, 0.5, SLOT, pose, float(now)).phase == "waiting"
    d = a.step(0.0, 0.5, SLOT, pose, t + 2.0)
    assert d.phase == "backoff" and d.v < 0.0 and a.tally.detours == 0
    # a wish that drives (the node faces where it goes) may take any free direction again
    b = Avoidance(AVOID, DetourSettings(wait=2.0, timeout=20.0))
    t = drive_in(b)
    b.step(0.2, 0.0, SLOT, pose, t, stopped=True)
    ahead = b.step(0.2, 0.0, SLOT, pose, t + 2.0)
    assert ahead.phase == "detour" and ahead.v > 0.0
