"""Route following on an LT-map: home to one viewframe after another (docs/design.md, method 1).

Three nodes share the work, composed in a mission (``follow_route.yaml``) with the control
nodes rather than in one behaviour; what they compute about a viewframe is perception's
(:mod:`perception.viewframe_motion`):

- :class:`StartRoute` writes the :class:`RouteProgress` (``/map/route_progress``): direction
  (forward along the route, or reverse, back to its start) and the first target viewframe.
- :class:`FollowRoute` homes to the target viewframe: Z-infinity against its landmarks gives the
  direction to it and the robot's rotation from it (eqs. 2-6), the circular median of the last K
  directions is steered along (eqs. 7-8), the speed scales with the estimate's confidence
  (eq. 9). It publishes a :class:`RouteEstimate` (``/map/route_estimate``) every new observation,
  and fails when fewer than ``min_matches`` landmarks match the viewframe for ``lost_time``
  (the trail is lost: a recovery, ``SearchPattern``, takes over); over a shorter gap it keeps the
  last command, so a few frames with too few matches between two viewframes do not stop it.
  While ``held`` (``AvoidObstacles`` round it holds the robot behind something in the way for
  its wait) too few matches do not count as lost: it keeps the last command and waits too.
- :class:`ViewframeSwitch` moves the target on when ``delta_t`` (eq. 1) against it falls under
  the map's threshold, or when the direction to it flips by more than 90 degrees (it was
  passed), the second rule blocked after each switch for as long as a 180 degree turn takes
  (tree clock). SUCCESS when the last viewframe of the route is reached.

How the paper is read here (where it is vague):

- **Frames.** Stored bearings are in the route frame of their viewframe (compensated for the
  teaching robot's heading); the current bearings are in the camera body frame. Z-infinity's
  rotation between the two gives the robot's heading in the viewframe's frame (``-yaw``), its
  translation the direction to the viewframe in that frame. Headings are filtered in the
  viewframe's frame, where turning on the spot does not move them, so the median of the last K
  estimates (eqs. 7-8) is not disturbed by the robot's own turns; odometry is not used.
- **Speed (eq. 9).** ``v = max(min_speed, speed * c)`` with ``c`` the median confidence
  (``1 - lambda_1 / lambda_2`` of ``M``) of the last K estimates, times ``cos`` of the heading
  error, and zero while the error exceeds ``turn_in_place``. The floor keeps the robot moving
  near a viewframe, where the translation is short and the confidence low, until the switch
  rule fires.
- **Lost.** Fewer matches than :func:`perception.viewframe_motion.lost_threshold` (the paper's
  50, or half a small viewframe, never under Z-infinity's 8). An observation with no usable
  estimate (no rotation, or no direction yet) counts as lost too. **Held is not lost**: a person
  standing in front of the robot hides a good part of the panorama, so the matches drop under the
  threshold just when the avoidance holds the robot behind them, waiting for the way to clear by
  itself before it tries a detour (its ``wait``, 2 s). While the avoidance says so (``held``)
  the lost timer does not run and the last command is kept (the robot stands still, so it still
  points where it pointed; the avoidance judges it). Otherwise the trail was "lost" after
  ``lost_time`` (1 s) of every such wait, the avoidance never got to its detour, and the
  mission's recovery skipped or searched instead (a robot held between two people on the route
  used up the mission's searches). Once the wait is over the avoidance drives a detour (the robot
  turns: the last command no longer points to the viewframe) or holds the robot with no way round
  (nothing left to wait for: the recovery may skip past it), and lost is lost as before. Stopping
  the lost timer for the whole of a hold was tried and dropped: in the lab with 3 people standing
  on the route the robot then stood 20 s (``timeout``) behind someone again and again (95 s in
  one repeat) and got home no more often (docs/obstacles-measured.md).
- **Odometry while lost (a departure, off by default).** With ``odometry_reach`` > 0 and a map
  taught with odometry, lost after a switch, the robot drives on by the taught odometry through the
  next viewframes' places (:mod:`behaviours.route_anchor` ties the two odometry frames at each
  switch) until the view is back, and only then counts as lost. Measured no better than vision
  alone among people (docs/ltmap.md), so the paper's rule is the default.
- **Rotation.** Z-infinity down a ladder of far thresholds, with a compass as the last resort
  (:func:`perception.viewframe_motion.zinf_motion`; the module doc says why).
- **Goal.** The switch rule fires within some radius of a viewframe (where ``delta_t`` first falls
  under the threshold), which is right for passing through viewframes but leaves the robot short
  of the route's end: the last viewframe is reached under the eq. 1 cost of ``goal_fraction``
  (0.34) of the threshold's bearing change (1 deg of the default 3 deg), or by the flip rule
  when the robot passes it. Fractions are taken of the bearing change, not of the cost
  (:func:`perception.similarity.scaled`): eq. 1 is quartic near 0, so a quarter of the cost
  would be 0.7 of the change. Eq. 1 weighs changes under 2 deg very little, so the goal needs
  1 deg where the earlier angle form's quarter threshold stood for 1.35 deg (measured outdoors,
  ``docs/ltmap.md``: the goal error 0.59 m instead of 0.67 m; the lab's is 0.04 m either way).
- **Flip rule.** The filtered direction to the target is compared with the previous one for the
  same target; a change of more than ``flip_angle`` is a flip. It counts only near the viewframe
  (``delta_t`` under the cost of ``flip_near`` = 2.7 times the threshold's bearing change, 8 deg
  as before): outdoors, with few near landmarks, the direction is noisy metres away from a
  viewframe, and a flip there is noise, not a passed viewframe.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.landmark_tree import LTMAP_IN
from behaviours.motion import COMMAND, ODOMETRY, STALLED
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.route_anchor import RouteAnchor
from behaviours.telemetry import Arrows, Drawing, Event, Figure, Plot, Points
from drivers.interfaces import STOP, VelocityCommand
from maps.ltmap.tree import LandmarkTree
from perception.geometry import wrap_angle
from perception.heading import HeadingFilter, heading_flipped, scaled_velocity
from perception.matching import LandmarkMatches
from perception.observation import Observation
from perception.similarity import scaled
from perception.viewframe_motion import (
    COMPASS,
    RULES,
    ZINF_MIN_LANDMARKS,
    RuledMotion,
    change_since,
    compass_motion,
    lost_threshold,
    zinf_motion,
)

PROGRESS_KEY = "/map/route_progress"
ESTIMATE_KEY = "/map/route_estimate"
DIRECTIONS = ("forward", "reverse")
NO_ROTATION, LOST = "no_rotation", "lost"
ESTIMATE_RULES = (*RULES, NO_ROTATION, LOST)  # how FollowRoute counts its estimates (report: ltmap.estimates)


@dataclass(frozen=True, slots=True)
class RouteProgress:
    """Where route following is: the viewframe homed to, and how it got there.

    ``direction`` +1 follows the route from start to goal, -1 from goal back to start;
    ``target`` is the viewframe homed to (route order; outside ``0 .. viewframes - 1`` once the
    last one was reached); ``switched_at`` the tree time of the last switch (the start time
    before the first).
    """

    direction: int
    target: int
    viewframes: int
    switched_at: float
    switches: int = 0
    anchor: RouteAnchor | None = None  # the tie of the teach's odometry to the repeat's, made at the last switch

    @classmethod
    def start(cls, viewframes: int, direction: int, now: float) -> RouteProgress:
        """Home to the route's first viewframe in ``direction`` first."""
        return cls(direction, 0 if direction > 0 else viewframes - 1, viewframes, now)

    @property
    def finished(self) -> bool:
        """The last viewframe of the route was reached."""
        return not 0 <= self.target < self.viewframes

    @property
    def remaining(self) -> int:
        """Viewframes still to reach, the target included."""
        return max(0, self.viewframes - self.target if self.direction > 0 else self.target + 1)

    def advanced(self, now: float, anchor: RouteAnchor | None = None) -> RouteProgress:
        """The target moved on to the next viewframe in the route's direction (``anchor``: made at
        the viewframe reached; the previous one is kept without it)."""
        return replace(self, target=self.target + self.direction, switched_at=now, switches=self.switches + 1,
                       anchor=anchor or self.anchor)

    def retargeted(self, target: int, now: float) -> RouteProgress:
        """Home to ``target`` from now on (the trail was found again there, or a skip moved it past
        something in the way). The tie to the teach's odometry is dropped: a drive by odometry is
        for going on along the route, not for the target a recovery chose (the next switch ties again)."""
        return replace(self, target=int(target), switched_at=now, anchor=None)


@dataclass(frozen=True, slots=True)
class RouteEstimate:
    """What one observation says about the target viewframe (published by :class:`FollowRoute`).

    ``heading``: eqs. 7-8, the filtered direction to the viewframe in the viewframe's frame
    (rad, NaN before the first estimate); ``error``: the same relative to the robot's heading,
    what steering turns by (NaN when unknown); ``delta_t``: eq. 1 against the viewframe (inf
    without a rotation); ``status``: Z-infinity's (``perception.zinf.ZinfStatus``) or ``"lost"``
    when too few landmarks matched; ``rule``: what made the rotation (a rung of Z-infinity's
    ladder or the compass, ``perception.viewframe_motion.RULES``; empty when lost); ``rotation``:
    the robot's heading in the viewframe's frame (Z-infinity's rotation, rad; NaN without one).
    """

    viewframe: int
    stamp: float
    matched: int
    status: str
    delta_t: float
    heading: float
    error: float
    confidence: float
    rule: str = ""
    rotation: float = math.nan

    @property
    def usable(self) -> bool:
        return math.isfinite(self.error)


@register
class StartRoute(BearingsBehaviour):
    """Start following the LT-map's route: forward from its start, or in reverse back home.

    Writes the first :class:`RouteProgress`; SUCCESS at once (FAILURE without a map).
    """

    DIRECTION = InputPort("direction", str, "forward", choices=DIRECTIONS,
                          doc="forward: start to goal; reverse: goal back to the start (return home)")
    PROGRESS = OutputPort("progress", RouteProgress, PROGRESS_KEY, doc="the target viewframe and the switches so far")
    PORTS = (DIRECTION, LTMAP_IN, PROGRESS)

    def update(self) -> Status:
        tree = self.get_input(LTMAP_IN, None)
        if tree is None or tree.viewframe_count == 0:
            self.feedback_message = "no LT-map to follow"
            return Status.FAILURE
        direction = self.get_input(self.DIRECTION)
        self.set_output(self.PROGRESS, RouteProgress.start(tree.viewframe_count, 1 if direction == "forward" else -1,
                                                           self.now()))
        self.feedback_message = f"{tree.viewframe_count} viewframes, {direction}"
        return Status.SUCCESS


FOLLOW_SPEED = InputPort("speed", float, 0.3, unit="m/s", minimum=0.01, maximum=1.2, doc="top speed (eq. 9)")
TURN_RATE = InputPort("turn_rate", float, 45.0, unit="deg/s", minimum=1.0, maximum=300.0, doc="top turn rate")
MIN_MATCHES = InputPort("min_matches", int, 50, minimum=ZINF_MIN_LANDMARKS,
                        doc="fewer matched landmarks: the trail is lost (the paper: 50; see lost_threshold)")
PROGRESS_IN = InputPort("progress", RouteProgress, Ref(PROGRESS_KEY), doc="the target viewframe")
OBSERVATION_IN = InputPort("observation", Observation, Ref("/perception/observation"),
                           doc="the landmarks seen now (Perceive)")


def sees(tree: LandmarkTree, index: int, observation: Observation, min_matches: int, rng: np.random.Generator
         ) -> bool:
    """Does ``observation`` match viewframe ``index`` well enough to home to it (``FollowRoute``'s rule:
    enough matches, and a valid Z-infinity rotation)? What a skip or a search needs to take it as the target."""
    matches = tree.match(index, observation)
    if len(matches) < lost_threshold(len(tree.viewframe(index)), min_matches):
        return False
    return zinf_motion(matches.ref, matches.cur, rng).motion.rotation_ok


def _counted_as(estimate: RouteEstimate) -> str:
    """The rule an estimate is counted under: its own when it found a rotation."""
    if estimate.status == LOST:
        return LOST
    return estimate.rule if math.isfinite(estimate.delta_t) else NO_ROTATION


ARRIVED = 0.25  # m: a drive by odometry is at the target's place (about a switching radius indoors)


@dataclass(frozen=True, slots=True)
class _OdometryDrive:
    """A drive by odometry while lost: since when, the last pose and the place driven to (odometry)."""

    since: float
    last: tuple[float, float]
    place: tuple[float, float] = (math.nan, math.nan)


@register
class FollowRoute(BearingsBehaviour):
    """Home to the target viewframe with Z-infinity: filtered heading, confidence-scaled speed.

    RUNNING while it follows (it never ends by itself: :class:`ViewframeSwitch` ends the route);
    FAILURE when the trail is lost (fewer than ``min_matches`` landmarks match, or no usable
    estimate, for ``lost_time`` while not ``held``; until then it keeps the last command) or
    the base is stalled.
    Writes the velocity to ``command`` and a :class:`RouteEstimate` per new observation to
    ``estimate``.
    """

    MIN_SPEED = InputPort("min_speed", float, 0.05, unit="m/s", minimum=0.0, maximum=1.2,
                          doc="speed floor while the estimate is usable, so a viewframe is always reached")
    HEADING_GAIN = InputPort("heading_gain", float, 1.5, unit="1/s", minimum=0.01,
                             doc="turn rate per rad of heading error")
    TURN_IN_PLACE = InputPort("turn_in_place", float, 45.0, unit="deg", minimum=1.0, maximum=180.0,
                              doc="heading error above which the robot turns on the spot")
    K = InputPort("k", int, 5, minimum=1, maximum=100, doc="headings in the circular median (eqs. 7-8)")
    MIN_CONFIDENCE = InputPort("min_confidence", float, 0.0, minimum=0.0, maximum=0.99,
                               doc="confidence mapped to zero speed (eq. 9)")
    LOST_TIME = InputPort("lost_time", float, 1.0, unit="s", minimum=0.0, doc="how long lost before FAILURE")
    HELD = InputPort("held", bool, False,
                     doc="true while the avoidance holds the robot for the way to clear ('{/robot/held}' of "
                         "AvoidObstacles): too few matches then do not count as lost")
    ROTATION = InputPort("rotation", str, "zinf", choices=("zinf", "compass"),
                         doc="zinf: rotation from far landmarks (the paper); compass: from all (for comparison)")
    ODOMETRY_REACH = InputPort("odometry_reach", float, 0.0, unit="m", minimum=0.0,
                               doc="lost for lost_time, drive on by odometry to the target's taught place when it "
                                   "was taught at most this far from the last viewframe reached (maps with places; "
                                   "route_anchor.py); 0: lost is lost (the paper)")
    ODOMETRY_TIME = InputPort("odometry_time", float, 20.0, unit="s", minimum=0.0,
                              doc="the longest drive by odometry before the trail counts as lost")
    ESTIMATE = OutputPort("estimate", RouteEstimate, ESTIMATE_KEY, doc="the latest estimate against the target")
    PASSED = OutputPort("passed", RouteProgress, PROGRESS_KEY,
                        doc="the progress after a target's place was reached by odometry (the next one is driven to)")
    PORTS = (FOLLOW_SPEED, MIN_SPEED, TURN_RATE, HEADING_GAIN, TURN_IN_PLACE, K, MIN_CONFIDENCE, MIN_MATCHES,
             LOST_TIME, HELD, ROTATION, ODOMETRY_REACH, ODOMETRY_TIME, LTMAP_IN, PROGRESS_IN, OBSERVATION_IN,
             ODOMETRY, STALLED, COMMAND, ESTIMATE, PASSED)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.matches: LandmarkMatches | None = None  # the latest, for the recording
        self.estimate: RouteEstimate | None = None
        self.rules = dict.fromkeys(ESTIMATE_RULES, 0)  # estimates by the rule that made them, over the run
        self.drives = {"started": 0, "found": 0, "passed": 0, "metres": 0.0}  # drives by odometry while lost
        self._rng = np.random.default_rng(0)
        self._reset()

    def _reset(self) -> None:
        self._filter = HeadingFilter(self.get_input(self.K))
        self._target: int | None = None
        self._stamp: float | None = None
        self._lost_since: float | None = None
        self._command = self._coast = STOP
        self._drive: _OdometryDrive | None = None

    def initialise(self) -> None:
        self._reset()

    def update(self) -> Status:
        tree = self.get_input(LTMAP_IN, None)
        progress = self.get_input(PROGRESS_IN, None)
        observation = self.get_input(OBSERVATION_IN, None)
        if self.get_input(STALLED, False):
            self.feedback_message = "stalled"
            return self._stop(Status.FAILURE)
        if tree is None or progress is None or observation is None:
            self.feedback_message = "waiting for the map, the route progress and an observation"
            return self._stop(Status.RUNNING)
        if progress.finished:
            self.feedback_message = "the route's last viewframe was reached"
            return self._stop(Status.SUCCESS)
        if progress.target != self._target:
            self._filter, self._target, self._stamp = self._filter.reset(), progress.target, None
        if observation.stamp != self._stamp:  # a new observation: a new estimate and command
            self._stamp = observation.stamp
            self.estimate = self._estimate(tree, progress.target, observation)
            self.rules[_counted_as(self.estimate)] += 1
            self.set_output(self.ESTIMATE, self.estimate)
            self._command = self._steer(self.estimate)
        return self._lost_or_follow(tree, progress)

    def _lost_or_follow(self, tree: LandmarkTree, progress: RouteProgress) -> Status:
        estimate = self.estimate
        if estimate is not None and estimate.usable:
            if self._drive is not None:  # the view is back: found by odometry
                self.drives["found"] += 1
                self._drive = None
            self._lost_since = None
            self._coast = self._command
            self.set_output(COMMAND, self._command)
            self.feedback_message = (f"viewframe {estimate.viewframe}: {estimate.matched} matched, "
                                     f"error {math.degrees(estimate.error):+.0f} deg")
            return Status.RUNNING
        now = self.now()
        matched = estimate.matched if estimate is not None else 0
        self.feedback_message = f"lost: {matched} landmarks match viewframe {self._target}" + (
            f" ({estimate.status})" if estimate is not None else "")
        if self.get_input(self.HELD, False):  # waiting behind an obstacle that hides the view: not lost
            self._lost_since = None
            self.feedback_message += ", held by an obstacle in the way"
        else:
            self._lost_since = now if self._lost_since is None else self._lost_since
            if now - self._lost_since >= self.get_input(self.LOST_TIME):
                command = self._by_odometry(tree, progress, now)
                if command is None:
                    return self._stop(Status.FAILURE)
                self.set_output(COMMAND, command)
                return Status.RUNNING
        self.set_output(COMMAND, self._coast)  # a short gap: keep on as before (STOP before any estimate)
        return Status.RUNNING

    def _stop(self, status: Status) -> Status:
        self.set_output(COMMAND, STOP)
        return status

    def _by_odometry(self, tree: LandmarkTree, progress: RouteProgress, now: float) -> VelocityCommand | None:
        """Towards the target's taught place, by odometry from the last switch (route_anchor.py),
        and on through the next places while still blind; None when there is no place to go to
        (none within ``odometry_reach`` of the viewframe reached), at the route's last viewframe's
        place (the goal is for vision to confirm), or after ``odometry_time``."""
        pose = self.get_input(ODOMETRY, None)
        place = self._odometry_place(tree, progress)
        if pose is None or place is None:
            return None
        if self._drive is None:
            self._drive = _OdometryDrive(now, (pose.x, pose.y))
            self.drives["started"] += 1
        self.drives["metres"] += math.dist(self._drive.last, (pose.x, pose.y))
        self._drive = replace(self._drive, last=(pose.x, pose.y))
        if now - self._drive.since > self.get_input(self.ODOMETRY_TIME):
            return None
        while math.dist(place, (pose.x, pose.y)) < ARRIVED:  # at the target's place: on to the next one
            if progress.remaining <= 1:
                return None
            ahead = progress.advanced(now)  # the tie stays the last switch's
            place = self._odometry_place(tree, ahead)
            if place is None:
                return None
            progress = ahead
            self.set_output(self.PASSED, progress)
            self.drives["passed"] += 1
        self._drive = replace(self._drive, place=(float(place[0]), float(place[1])))
        distance = math.dist(place, (pose.x, pose.y))
        self.feedback_message += f", driving by odometry to viewframe {progress.target}'s place, {distance:.1f} m"
        speed = min(self.get_input(FOLLOW_SPEED), max(self.get_input(self.MIN_SPEED), distance))
        return self._toward(wrap_angle(math.atan2(place[1] - pose.y, place[0] - pose.x) - pose.theta), speed)

    def _odometry_place(self, tree: LandmarkTree, progress: RouteProgress) -> np.ndarray | None:
        """The target's taught place in this run's odometry frame, when the map has places, a
        switch tied the frames and the place lies within ``odometry_reach`` of the viewframe reached."""
        anchor = progress.anchor
        if anchor is None or not tree.has_places or not 0 <= progress.target < tree.viewframe_count:
            return None
        reached, target = tree.place(anchor.viewframe), tree.place(progress.target)
        if reached is None or target is None or math.dist(reached, target) > self.get_input(self.ODOMETRY_REACH):
            return None
        return anchor.to_odometry(reached, target)

    def _estimate(self, tree: LandmarkTree, target: int, observation: Observation) -> RouteEstimate:
        matches = self.matches = tree.match(target, observation)
        needed = lost_threshold(len(tree.viewframe(target)), self.get_input(MIN_MATCHES))
        nan = float("nan")
        if len(matches) < needed:
            return RouteEstimate(target, observation.stamp, len(matches), LOST, math.inf, nan, nan, 0.0)
        chosen = self.get_input(self.ROTATION) == COMPASS  # the compass asked for, not as the last resort
        if chosen:
            ruled = RuledMotion(compass_motion(matches.ref, matches.cur, self._rng), COMPASS)
        else:
            ruled = zinf_motion(matches.ref, matches.cur, self._rng)  # eqs. 2-6
        motion, rule = ruled.motion, ruled.rule
        status = f"compass, {motion.status.value}" if ruled.compass and not chosen else motion.status.value
        if not motion.rotation_ok:
            return RouteEstimate(target, observation.stamp, len(matches), status, math.inf, nan, nan, 0.0, rule)
        change = change_since(matches.ref, matches.cur, motion, tree.scale)  # eq. 1 over the inliers
        if motion.ok:
            home = -motion.translation  # towards the viewframe, in its frame
            self._filter = self._filter.push(math.atan2(home[1], home[0]), motion.confidence)
        heading = self._filter.heading  # eqs. 7-8: circular median of the last K
        rotation = wrap_angle(-motion.yaw)  # the robot's heading in the viewframe's frame
        if heading is None:
            return RouteEstimate(target, observation.stamp, len(matches), status, change, nan, nan, 0.0, rule,
                                 rotation)
        error = wrap_angle(heading + motion.yaw)  # heading - rotation
        return RouteEstimate(target, observation.stamp, len(matches), status, change, heading, error,
                             self._filter.confidence, rule, rotation)

    def _steer(self, estimate: RouteEstimate) -> VelocityCommand:
        if not estimate.usable:
            return STOP
        speed = scaled_velocity(estimate.confidence, self.get_input(FOLLOW_SPEED),
                                min_confidence=self.get_input(self.MIN_CONFIDENCE))  # eq. 9
        return self._toward(estimate.error, max(self.get_input(self.MIN_SPEED), speed))

    def _toward(self, error: float, speed: float) -> VelocityCommand:
        """Turn by ``error`` (rad): on the spot above ``turn_in_place``, else at ``speed`` times its cosine."""
        turn = math.radians(self.get_input(TURN_RATE))
        w = float(np.clip(self.get_input(self.HEADING_GAIN) * error, -turn, turn))
        if abs(error) > math.radians(self.get_input(self.TURN_IN_PLACE)):
            return VelocityCommand(0.0, w)
        return VelocityCommand(speed * math.cos(error), w)

    def figures(self) -> Iterator[Figure]:
        """Every estimate counted by the rule that made it (``estimates.zinf_1deg`` ..
        ``estimates.compass``), or as ``no_rotation`` (no rule found one) or ``lost`` (too few matches);
        the drives by odometry while lost (``odometry_drives``), those that found the view again
        (``found_by_odometry``), the viewframes' places passed on the way (``passed_by_odometry``)
        and their length (``odometry_m``)."""
        for rule, count in self.rules.items():
            yield Figure("ltmap", f"estimates.{rule}", count)
        yield Figure("ltmap", "odometry_drives", self.drives["started"])
        yield Figure("ltmap", "found_by_odometry", self.drives["found"])
        yield Figure("ltmap", "passed_by_odometry", self.drives["passed"])
        yield Figure("ltmap", "odometry_m", round(self.drives["metres"], 2))

    def drawings(self) -> Iterator[Drawing]:
        """While following: the target, matches, ``delta_t`` (capped at 1) and confidence as plots,
        the estimated direction and the matched landmarks' bearings in the robot's frame."""
        estimate = self.estimate
        if estimate is None or self.status != Status.RUNNING:
            return
        yield Plot("route/target_viewframe", float(estimate.viewframe))
        yield Plot("route/matched", float(estimate.matched))
        yield Plot("route/delta_t", min(float(estimate.delta_t), 1.0))
        yield Plot("route/confidence", float(estimate.confidence))
        if estimate.usable:
            direction = np.array([[math.cos(estimate.error), math.sin(estimate.error)]])
            yield Arrows("route/robot_frame/direction", direction, colours=(255, 80, 0))
        if self._drive is not None and not estimate.usable:
            yield Points("odometry_frame/route/odometry_target", np.array([self._drive.place]), colours=(255, 0, 200),
                         radius=0.08)
        if self.matches is not None and len(self.matches):
            cur = np.asarray(self.matches.cur)
            azimuth = np.arctan2(cur[:, 1], cur[:, 0])
            yield Points("route/robot_frame/matched_landmarks", np.column_stack((np.cos(azimuth), np.sin(azimuth))),
                         colours=(40, 160, 255), radius=0.02)


@register
class ViewframeSwitch(BearingsBehaviour):
    """Move the target to the next viewframe when it is reached; SUCCESS after the last one.

    Reached: ``delta_t`` (eq. 1) against the target under the map's threshold, or the direction to
    it flipped by more than ``flip_angle`` (it was passed) once the block after the last switch is
    over (180 degrees at ``turn_rate``: the robot may be turning to the new target). Tree clock.
    Reports every switch (viewframe, time, rule) in the ``ltmap`` section.
    """

    THRESHOLD = InputPort("threshold", float, 0.0, minimum=0.0,
                          doc="eq. 1 switch threshold; 0: the one the map was taught with")
    GOAL_FRACTION = InputPort("goal_fraction", float, 0.34, minimum=0.01, maximum=1.0,
                              doc="the route's last viewframe is reached under the eq. 1 cost of this fraction "
                                  "of the threshold's bearing change")
    FLIP_ANGLE = InputPort("flip_angle", float, 90.0, unit="deg", minimum=1.0, maximum=180.0,
                           doc="a change of the direction to the target larger than this: it was passed")
    FLIP_NEAR = InputPort("flip_near", float, 2.7, minimum=1.0,
                          doc="a flip counts only while delta_t is under the eq. 1 cost of this many times the "
                              "threshold's bearing change (near the viewframe)")
    ESTIMATE = InputPort("estimate", RouteEstimate, Ref(ESTIMATE_KEY), doc="the latest estimate (FollowRoute)")
    ADVANCED = OutputPort("advanced", RouteProgress, PROGRESS_KEY, doc="the progress after a switch")
    PORTS = (THRESHOLD, GOAL_FRACTION, FLIP_ANGLE, FLIP_NEAR, TURN_RATE, LTMAP_IN, PROGRESS_IN, ODOMETRY, ESTIMATE,
             ADVANCED)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.reached: list[dict[str, Any]] = []
        self._reached_at: list[list[float]] = []  # odometry (x, y) of each switch, for the recording
        self._logged = 0
        self._last: tuple[int, float] | None = None  # (target, stamp) of the last estimate used
        self._heading: float | None = None

    @property
    def block_time(self) -> float:
        """Seconds the flip rule waits after a switch: a 180 degree turn at ``turn_rate``."""
        return 180.0 / self.get_input(TURN_RATE)

    def update(self) -> Status:
        progress = self.get_input(PROGRESS_IN, None)
        estimate = self.get_input(self.ESTIMATE, None)
        tree = self.get_input(LTMAP_IN, None)
        if progress is None or tree is None:
            self.feedback_message = "waiting for the route progress and the map"
            return Status.RUNNING
        if progress.finished:
            return Status.SUCCESS
        if estimate is None or estimate.viewframe != progress.target or (progress.target, estimate.stamp) == self._last:
            return Status.RUNNING
        if self._last is None or self._last[0] != progress.target:
            self._heading = None
        self._last = (estimate.viewframe, estimate.stamp)
        rule = self._rule(estimate, progress, self.get_input(self.THRESHOLD) or tree.threshold, tree.scale)
        if math.isfinite(estimate.heading):
            self._heading = estimate.heading
        self.feedback_message = f"target {progress.target}, delta_t {estimate.delta_t:.2g}"
        if rule is None:
            return Status.RUNNING
        now = self.now()
        self.reached.append({"viewframe": progress.target, "time_s": round(now, 3), "rule": rule})
        pose = self.get_input(ODOMETRY, None)
        anchor = None
        if pose is not None:
            self._reached_at.append([pose.x, pose.y])
            if math.isfinite(estimate.rotation):  # ties the teach's odometry to this one (route_anchor.py)
                anchor = RouteAnchor(progress.target, pose, estimate.rotation)
        advanced = progress.advanced(now, anchor)
        self.set_output(self.ADVANCED, advanced)
        self._heading = None
        return Status.SUCCESS if advanced.finished else Status.RUNNING

    def _rule(self, estimate: RouteEstimate, progress: RouteProgress, threshold: float, scale: float) -> str | None:
        if progress.remaining == 1:  # the goal: home closer than the switching radius of the others
            threshold = scaled(threshold, self.get_input(self.GOAL_FRACTION), scale)
        if estimate.delta_t < threshold:  # eq. 1 under the threshold: at the viewframe
            return "delta_t"
        blocked = self.now() - progress.switched_at < self.block_time
        far = estimate.delta_t >= scaled(threshold, self.get_input(self.FLIP_NEAR), scale)
        if blocked or far or self._heading is None or not math.isfinite(estimate.heading):
            return None
        limit = math.radians(self.get_input(self.FLIP_ANGLE))
        return "flip" if heading_flipped(self._heading, estimate.heading, limit=limit) else None

    def figures(self) -> Iterator[Figure]:
        rules = [r["rule"] for r in self.reached]
        yield Figure("ltmap", "switches", len(self.reached), headline=True)  # viewframes reached on the way
        yield Figure("ltmap", "switches_by_flip", rules.count("flip"))
        yield Figure("ltmap", "reached", list(self.reached))

    def drawings(self) -> Iterator[Drawing]:
        """Each new switch as an event, and where the viewframes were reached (odometry frame)."""
        new = self.reached[self._logged:]
        self._logged = len(self.reached)
        for entry in new:
            yield Event("route/events", f"viewframe {entry['viewframe']} reached ({entry['rule']})")
        if new and self._reached_at:
            yield Points("odometry_frame/route/reached_viewframes", np.array(self._reached_at), colours=(0, 200, 120),
                         radius=0.05)
