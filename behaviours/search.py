"""The recovery of route following: drive a lying eight until the trail is found again.

When too few landmarks match the target viewframe (``FollowRoute`` fails), the paper drives a
search pattern, a "lying 8" 1.2 m across, until the trail is found. Here the eight is two
circles of diameter ``width / 2`` side by side, the first turning left and the second right,
laid on the odometry frame where the robot lost the trail and followed as a path (it ends where
it started): a carrot a fifth of the width (:data:`LOOKAHEAD`) ahead of the robot's place along
it, steered to by pure pursuit. What a detour or a wait keeps it from driving in time (more than
:data:`LAG` behind the eight driven at ``speed`` from its start) is skipped, so a search ends in
about the time its eights take even where people stand on them. Until stop 42 the eight was
driven open loop, as a fixed speed and turn rate, and every detour of the avoidance round a
person moved the rest of it: in the office with 3 more people on the route, one search's eights
walked the robot 1.5 m through a door into the meeting room, where nothing of the route was in
view (docs/obstacles-measured.md). Every new
observation is matched against the target viewframe and the next ones along the route
(``window``), then the ones before it (``behind``): the first with enough matches (the same rule
as ``FollowRoute``'s) and a valid Z-infinity rotation becomes the target, and the node succeeds so
the mission resumes following (in a ``RecoveryNode``). FAILURE after ``eights`` eights without the
trail, or when stalled, and at once when more than ``searches`` searches have started since the
route last moved on (its target went farther along the route than at any search before): ``follow_route``'s
``retries`` count the trails lost and found again in one stretch of the route, not over the whole
route, so a long route among people, losing and finding the trail now and then, is not failed for
losses it recovered from long ago; a robot losing the trail again and again in one place is.

With ``behind``, viewframes already passed count too (a departure: the paper searches for the one it lost). A
robot that lost the trail getting round people has often been pushed back or aside, nearer the
viewframes it passed than the one it lost; following again from one of them costs a few metres,
while an eight that does not find the lost one fails the mission. ``behind`` is 0 (off) in the
shipped ``follow_route``: in the clinic with 3 people on the route (docs/obstacles-measured.md) it got no
more repeats home (0 of 3 against 1 of 3), the robot re-following passed viewframes into a room.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.landmark_tree import LTMAP_IN
from behaviours.motion import COMMAND, ODOMETRY, STALLED
from behaviours.ports import InputPort, OutputPort
from behaviours.registry import register
from behaviours.route import MIN_MATCHES, OBSERVATION_IN, PROGRESS_IN, PROGRESS_KEY, RouteProgress, sees
from behaviours.telemetry import Drawing, Figure, Lines
from drivers.interfaces import STOP, VelocityCommand
from maps.pursuit import carrot, place_along
from perception.geometry import Pose2D, frame_to_parent, wrap_angle

LOOKAHEAD = 0.25 / 1.2  # of the width: the carrot (0.25 m on the 1.2 m eight: a chord of its circles to pursue)
TURN_IN_PLACE = math.radians(60.0)  # the carrot this far off the heading: turn to it on the spot
TURN_GAIN = 1.5  # 1/s: the turn rate on the spot per rad off (FollowRoute's heading gain)
AHEAD = 0.5  # of the width: how far along the eight the robot's next place is looked for (not across its crossing)
LAG = 1.0  # of the width: the most the robot's place falls behind the eight driven on time (the rest is skipped)


def lying_eight(width: float, points: int = 64) -> np.ndarray:
    """The pattern from its start (origin, heading +x): a left circle, then a right one (N x 2)."""
    radius = width / 4.0
    angles = np.linspace(0.0, 2.0 * np.pi, points // 2, endpoint=False)
    left = np.column_stack((radius * np.sin(angles), radius * (1.0 - np.cos(angles))))
    right = np.column_stack((radius * np.sin(angles), -radius * (1.0 - np.cos(angles))))
    return np.vstack((left, right, [[0.0, 0.0]]))


@register
class SearchPattern(BearingsBehaviour):
    """Drive a lying eight ``width`` across until the trail is found; then SUCCESS.

    Found: a viewframe among the target and the next ``window`` along the route matches at least
    as many landmarks as following needs (``min_matches``, see
    :func:`perception.viewframe_motion.lost_threshold`) with a valid Z-infinity rotation; it
    becomes the target (``found`` output).
    """

    WIDTH = InputPort("width", float, 1.2, unit="m", minimum=0.1, maximum=10.0, doc="the eight from end to end")
    SPEED = InputPort("speed", float, 0.15, unit="m/s", minimum=0.01, maximum=1.2, doc="driving speed")
    EIGHTS = InputPort("eights", int, 2, minimum=1, doc="eights driven before giving up")
    WINDOW = InputPort("window", int, 2, minimum=0, doc="viewframes past the target also searched for")
    BEHIND = InputPort("behind", int, 0, minimum=0,
                       doc="viewframes before the target (already passed) searched for after those ahead")
    SEARCHES = InputPort("searches", int, 0, minimum=0,
                         doc="searches allowed since the route last moved on (its target advanced); one more fails at "
                             "once: the trail lost and found again this often in one stretch; 0: no limit")
    FOUND = OutputPort("found", type=RouteProgress, key=PROGRESS_KEY, doc="the progress with the viewframe found")
    PORTS = (WIDTH, SPEED, EIGHTS, WINDOW, BEHIND, SEARCHES, MIN_MATCHES,
             LTMAP_IN, PROGRESS_IN, OBSERVATION_IN, ODOMETRY, STALLED, COMMAND, FOUND)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.recoveries = 0
        self.found_again = 0
        self._rng = np.random.default_rng(0)
        self._origin: Pose2D | None = None
        self._logged_origin: Pose2D | None = None
        self._path = np.zeros((0, 2))  # the eights to drive, odometry frame
        self._along = np.zeros(0)  # the distance along them to each point
        self._index = 0  # the robot's place along them (the nearest point, never going back)
        self._started = 0.0  # when the eights were laid
        self._stamp: float | None = None
        self._farthest: int | None = None  # the farthest target along the route a search started from
        self._since = 0  # searches started since the target last went farther
        self._reset()

    def _reset(self) -> None:
        self._origin, self._path, self._along, self._index, self._stamp = None, np.zeros((0, 2)), np.zeros(0), 0, None

    def initialise(self) -> None:
        self._reset()
        self.recoveries += 1
        progress = self.get_input(PROGRESS_IN, None)
        if progress is not None:
            reach = progress.target * progress.direction
            if self._farthest is None or reach > self._farthest:
                self._farthest, self._since = reach, 0
        self._since += 1

    def update(self) -> Status:
        pose = self.get_input(ODOMETRY, None)
        if self.get_input(STALLED, False):
            self.feedback_message = "stalled"
            return self._stop(Status.FAILURE)
        if pose is None:
            self.feedback_message = "waiting for odometry"
            return self._stop(Status.RUNNING)
        searches = self.get_input(self.SEARCHES)
        if searches and self._since > searches:
            self.feedback_message = f"the trail was lost {self._since} times since the route last moved on"
            return self._stop(Status.FAILURE)
        if self._found():
            return self._stop(Status.SUCCESS)
        eights = self.get_input(self.EIGHTS)
        here, width, speed = np.array([pose.x, pose.y]), self.get_input(self.WIDTH), self.get_input(self.SPEED)
        if self._origin is None:
            self._origin, self._started = pose, self.now()
            self._path = _eights_at(pose, width, eights)
            self._along = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(self._path, axis=0).T))))
        due = speed * (self.now() - self._started) - LAG * width  # no farther behind the eights driven on time
        last = len(self._path) - 1
        window = int(np.searchsorted(self._along, self._along[self._index] + AHEAD * width, side="right"))
        self._index = min(last, max(place_along(self._path, self._index, window, here),  # never going back,
                                    int(np.searchsorted(self._along, due))))  # nor across the eight's crossing
        if self._index == last and (math.dist(self._path[last], here) < LOOKAHEAD * width or due >= self._along[-1]):
            self.feedback_message = f"the trail was not found in {eights} eights"
            return self._stop(Status.FAILURE)
        target = carrot(self._path, self._index, here, LOOKAHEAD * width)
        self.set_output(COMMAND, _pursue(pose, target, speed, width))
        self.feedback_message = f"searching: {100 * self._index / last:.0f} % of {eights} eights"
        return Status.RUNNING

    def _stop(self, status: Status) -> Status:
        self.set_output(COMMAND, STOP)
        return status

    def _found(self) -> bool:
        tree = self.get_input(LTMAP_IN, None)
        progress = self.get_input(PROGRESS_IN, None)
        observation = self.get_input(OBSERVATION_IN, None)
        if tree is None or progress is None or observation is None or progress.finished:
            return False
        if observation.stamp == self._stamp:
            return False
        self._stamp = observation.stamp
        last = tree.viewframe_count - 1
        window = self.get_input(self.WINDOW)
        behind = self.get_input(self.BEHIND)
        steps = (*range(window + 1), *range(-1, -behind - 1, -1))  # ahead first, then back along the route
        candidates = [progress.target + progress.direction * k for k in steps]
        for index in (c for c in candidates if 0 <= c <= last):
            if sees(tree, index, observation, self.get_input(MIN_MATCHES), self._rng):
                self.set_output(self.FOUND, progress.retargeted(index, self.now()))
                self.found_again += 1
                self.feedback_message = f"the trail is found again at viewframe {index}"
                return True
        return False

    def figures(self) -> Iterator[Figure]:
        yield Figure("ltmap", "recoveries", self.recoveries, headline=True)
        yield Figure("ltmap", "recoveries_found", self.found_again)

    def drawings(self) -> Iterator[Drawing]:
        """The eight being driven, in the odometry frame, each time a search starts."""
        origin = self._origin
        if origin is None or origin is self._logged_origin:
            return
        self._logged_origin = origin
        yield Lines("odometry_frame/route/search_pattern", [_eights_at(origin, self.get_input(self.WIDTH), 1)],
                    colours=(255, 0, 160))


def _eights_at(origin: Pose2D, width: float, eights: int) -> np.ndarray:
    """``eights`` lying eights ``width`` across, one after the other, from ``origin`` (odometry frame)."""
    one = lying_eight(width)
    return frame_to_parent(origin, np.vstack([*[one[:-1]] * eights, one[-1:]]))


def _pursue(pose: Pose2D, carrot: np.ndarray, speed: float, width: float) -> VelocityCommand:
    """Pure pursuit to ``carrot``: the arc through it tangent to the heading, at ``speed`` slowed by the
    cosine of the bearing off the heading; turned to on the spot beyond :data:`TURN_IN_PLACE` (an arc
    to a carrot square to the heading is a crawl). The turn rate is capped at twice the eight's own
    (``speed`` round a circle ``width / 2`` across)."""
    dx, dy = carrot[0] - pose.x, carrot[1] - pose.y
    error = wrap_angle(math.atan2(dy, dx) - pose.theta)
    most = 2.0 * speed / (width / 4.0)
    if abs(error) > TURN_IN_PLACE:
        return VelocityCommand(0.0, float(np.clip(TURN_GAIN * error, -most, most)))
    v = speed * math.cos(error)
    w = 2.0 * v * math.sin(error) / max(math.hypot(dx, dy), 1e-6)  # curvature 2 sin(error) / distance
    return VelocityCommand(v, float(np.clip(w, -most, most)))
