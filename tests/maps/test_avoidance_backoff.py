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
from maps.avoidance.detour import BACKOFFS_PER_HOLD, Avoidance
from maps.avoidance.state import DetourSettings
from maps.avoidance.sweep import AvoidSettings
from perception.geometry import Pose2D, parent_to_frame
from perception.polygons import disc

AVOID = AvoidSettings(disc(0.26))
CORNER = np.array([[0.35 * math.cos(a), 0.35 * math.sin(a)] for a in np.radians(np.arange(-90.0, 91.0, 10.0))])


def seen(pose: Pose2D, world: np.ndarray = CORNER) -> np.ndarray:
    """The ``world``'s points (odometry; the corner by default) in the base frame of ``pose``."""
    return np.asarray(parent_to_frame(pose, world))


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


# A person 0.75 m ahead of the route's line (+x from the origin, odometry), their outline every 10 deg.
PERSON_AHEAD = np.array([[0.75 + 0.25 * math.cos(a), 0.25 * math.sin(a)] for a in np.radians(np.arange(0, 360, 10))])


def _wedge(at: np.ndarray) -> np.ndarray:
    """Points 0.45 m round ``at`` (odometry) from -90 to +60 deg of +x: nothing within 90 deg of the
    route's heading is free there (0.19 m from the disc, less than the 0.18 m a detour needs plus the
    clearance), only the way back, 120 deg."""
    return np.array([at + 0.45 * np.array([math.cos(a), math.sin(a)]) for a in np.radians(np.arange(-90, 61, 10))])


def _detour_into_a_wedge(a: Avoidance, length: float = 0.4) -> tuple[float, Pose2D, int, np.ndarray]:
    """Drive up to the person, wait, detour ``length`` m the way the detour chose, where a wedge closes
    in (someone stepping up beside the person); returns the time, the pose, the side and the world points."""
    t = drive_in(a)
    here = Pose2D()
    assert a.step(0.3, 0.0, seen(here, PERSON_AHEAD), here, t).phase == "waiting"
    start = a.step(0.3, 0.0, seen(here, PERSON_AHEAD), here, t + 2.0)
    assert start.phase == "detour" and start.choice is not None and start.choice.direction is not None
    side, psi = start.choice.side, start.choice.direction.angle
    now, pose = t + 2.0, here
    for s in np.arange(0.02, length + 0.01, 0.02):  # the robot drives the chosen direction, the node wishing back
        now += 0.1
        pose = Pose2D(float(s * math.cos(psi)), float(s * math.sin(psi)), psi)
        assert a.step(0.0, -side * 0.5, seen(pose, PERSON_AHEAD), pose, now).phase == "detour"
    world = np.vstack((PERSON_AHEAD, _wedge(np.array([pose.x, pose.y]))))
    return now, pose, side, world


def _back_to_the_start(a: Avoidance, now: float, pose: Pose2D, side: int, world: np.ndarray) -> tuple[float, Pose2D]:
    """The robot backs along the detour to where it began while the avoidance backs it (odometry
    fed by hand, 5 % of the way a tick); returns the time and the pose there."""
    for f in np.arange(0.95, 0.0, -0.05):
        now += 0.2
        pose = Pose2D(pose.x * f / (f + 0.05), pose.y * f / (f + 0.05), pose.theta)
        if a.step(0.0, -side * 0.5, seen(pose, world), pose, now).phase != "backoff":
            break
    return now, Pose2D(0.0, 0.0, pose.theta)


def test_a_detour_wedged_on_its_way_round_is_undone_and_the_other_side_taken():
    """``undo``: held on a detour with nothing free within 90 deg of the route (in the lab a detour
    went between a pillar and a person standing on the route and stood there for 200 s), the robot
    drives back the way the detour came, as far as the detour went, even with back-offs off
    (``backoff: 0``, the route's: a wait for a person does not back away), then takes the other side.
    It does so where it would give up, at the hold's timeout: a wedge that a walking person makes
    opens by itself (in the lab's seed 7 undoing after the 2 s wait lost a repeat that waiting got home)."""
    a = Avoidance(AVOID, DetourSettings(wait=2.0, timeout=20.0, undo=True), BackoffSettings(distance=0.0))
    now, pose, side, world = _detour_into_a_wedge(a)
    held = a.step(0.0, -side * 0.5, seen(pose, world), pose, now + 0.1)
    assert (held.phase, held.v, held.w) == ("detour", 0.0, 0.0) and held.choice is not None
    assert held.choice.direction is None  # nothing within 90 deg of the route
    for t in np.arange(now + 0.5, now + 20.0, 0.5):  # held: a person beside it may yet walk on
        d = a.step(0.0, -side * 0.5, seen(pose, world), pose, float(t))
        assert (d.phase, d.v, d.w) == ("detour", 0.0, 0.0)
    back = a.step(0.0, -side * 0.5, seen(pose, world), pose, now + 20.2)  # held for the timeout: undone
    assert back.phase == "backoff" and back.v < 0.0 and not back.gave_up
    assert back.event == "no way round: backing away 0.40 m the way it came"
    now, pose = _back_to_the_start(a, now + 20.2, pose, side, world)
    after = a.step(0.0, -side * 0.5, seen(pose, world), pose, now + 0.2)
    assert a.tally.backoffs == 1 and a.tally.backoff_length == pytest.approx(0.4, abs=0.03)
    assert after.phase == "detour" and after.choice is not None and after.choice.direction is not None
    assert after.choice.side == -side  # the other side of the person


def test_without_undo_the_wedged_detour_stays_held_with_back_offs_off_and_gives_up():
    a = Avoidance(AVOID, DetourSettings(wait=2.0, timeout=20.0), BackoffSettings(distance=0.0))
    now, pose, side, world = _detour_into_a_wedge(a)
    for t in np.arange(now + 0.1, now + 20.0, 0.5):
        d = a.step(0.0, -side * 0.5, seen(pose, world), pose, float(t))
        assert (d.phase, d.v, d.w) == ("detour", 0.0, 0.0)
    assert a.step(0.0, -side * 0.5, seen(pose, world), pose, now + 20.2).gave_up.startswith("blocked for 20 s")
    assert a.tally.backoffs == 0


def test_an_undone_detour_held_on_the_other_side_too_gives_up_after_the_wait():
    """Undoing is one more chance, not a new hold: with no way on the other side either, it gives up
    ``wait`` seconds after it is back, not ``timeout`` seconds."""
    a = Avoidance(AVOID, DetourSettings(wait=2.0, timeout=20.0, undo=True), BackoffSettings(distance=0.0))
    now, pose, side, world = _detour_into_a_wedge(a)
    for t in np.arange(now + 0.1, now + 20.0, 0.5):  # held from now + 0.1
        a.step(0.0, -side * 0.5, seen(pose, world), pose, float(t))
    now += 20.2
    assert a.step(0.0, -side * 0.5, seen(pose, world), pose, now).phase == "backoff"
    now, pose = _back_to_the_start(a, now, pose, side, world)
    boxed = np.vstack((world, _wedge(np.zeros(2)), _wedge(np.zeros(2)) * [1.0, -1.0]))  # nothing free here now
    held = a.step(0.0, -side * 0.5, seen(pose, boxed), pose, now + 0.2)
    assert (held.phase, held.v, held.w, held.gave_up) == ("detour", 0.0, 0.0, "")
    d = a.step(0.0, -side * 0.5, seen(pose, boxed), pose, now + 2.2)
    assert d.gave_up.startswith("blocked for 20 s") and a.tally.give_ups == 1


def test_a_detour_that_hardly_moved_is_not_undone_it_gives_up_as_before():
    """A detour of 6 cm (turning to and fro, edging) led into nothing: undoing it would only swap
    sides where the robot stands (in the clinic, three such undos of 5 cm each cost a repeat its time)."""
    a = Avoidance(AVOID, DetourSettings(wait=2.0, timeout=20.0, undo=True), BackoffSettings(distance=0.0))
    now, pose, side, world = _detour_into_a_wedge(a, length=0.06)
    for t in np.arange(now + 0.1, now + 20.0, 0.5):
        assert a.step(0.0, -side * 0.5, seen(pose, world), pose, float(t)).phase == "detour"
    assert a.step(0.0, -side * 0.5, seen(pose, world), pose, now + 20.2).gave_up.startswith("blocked for 20 s")
    assert a.tally.backoffs == 0
