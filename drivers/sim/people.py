"""People in a simulated world: where each one is, and how the crowd steps with simulated time.

A person walks a fixed schedule (:func:`position_at`): along the path at its speed, waiting at each
end, round the loop or back and forth, starting at the path's first point at time 0. The schedule
runs on the person's own *walked time*, which the simulation advances with the simulated clock
(:class:`Crowd`). The one thing that changes it is the robot. A person does not walk through the
robot: when their next step would bring them within :data:`PERSONAL_SPACE_M` of its disc (and
closer than they are), they do what people in a corridor do:

- **wait** for it to pass, as long as it moves; a robot that stands in their way (slower than
  :data:`STILL_M_S`: waiting, turning on the spot) they wait for :data:`YIELD_S` seconds, then
- **step aside**: sideways, away from the robot (never to its side of their path), at their
  walking speed, up to :data:`SIDESTEP_M` off their path, where the walls, boxes and pillars
  leave them room, and walk on past it at that offset (no nearer the robot's disc than
  :data:`PASSING_M`), easing back onto their path once past;
- **wait** on, where there is no room to pass (a robot in the middle of a 1.4 m hallway), and
  **turn back** after :data:`PATIENCE_S` seconds held by it: they walk their schedule backwards (the
  way they came) until the robot holds them again, when they turn once more.

Until stop 39 people only waited, for ever, and a robot that waits for a person and a person who
waits for the robot stood facing each other until the run's time limit (an exploration of
``flat`` for 550 s, a person 0.2 m from the robot's disc in the hallway; in the office corridor
two people 0.10 m from it while it waited for them), which no person does.

People move deterministically (the robot's motion is deterministic for a seed), never walk into
the robot (nor step or turn towards it), and a contact between the robot and a person is always
the robot's doing.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence

import numpy as np

from drivers.sim.world_values import Person

PERSONAL_SPACE_M = 0.1  # m: a walking person stops this far from the robot's disc ...
PASSING_M = 0.05  # m: ... and passes it, stepped aside, no nearer than this
SIDESTEP_M = 0.6  # m: the farthest a person steps aside from their path to pass the robot (on its centre line)
STILL_M_S = 0.05  # m/s: a robot slower than this stands in the way (turning on the spot, waiting)
YIELD_S = 5.0  # s a person waits for a robot standing in the way before stepping aside round it ...
PATIENCE_S = 10.0  # s ... and before turning back, when there is no room to step aside


def position_at(person: Person, walked: float) -> tuple[float, float]:
    """Where ``person`` is after ``walked`` seconds of its schedule (t >= 0).

    Back and forth (``loop`` false), one period is: walk to the last point (``T = L / speed``),
    wait ``wait``, walk back (``T``), wait ``wait``. Round a loop: walk the closed path
    (``T = L / speed``, ``L`` including the way back to the first point), wait ``wait``.
    """
    points, lengths, total = _polyline(person)
    if total == 0.0:
        return points[0]
    walk = total / person.speed
    if person.loop:
        phase = walked % (walk + person.wait)
        along = total if phase >= walk else person.speed * phase  # waiting at the first point: along = L
    else:
        phase = walked % (2.0 * (walk + person.wait))
        if phase < walk:  # going
            along = person.speed * phase
        elif phase < walk + person.wait:  # waiting at the last point
            along = total
        elif phase < 2.0 * walk + person.wait:  # coming back
            along = total - person.speed * (phase - walk - person.wait)
        else:  # waiting at the first point
            along = 0.0
    return _point_along(points, lengths, along)


@functools.lru_cache(maxsize=1024)
def _polyline(person: Person) -> tuple[tuple[tuple[float, float], ...], tuple[float, ...], float]:
    """The points a person walks through (a loop back to its first), each step's length, their sum."""
    points = (*person.path, person.path[0]) if person.loop and len(person.path) > 1 else person.path
    lengths = tuple(math.dist(a, b) for a, b in zip(points, points[1:], strict=False))
    return points, lengths, sum(lengths)


def _point_along(points: Sequence[tuple[float, float]], lengths: Sequence[float], along: float) -> tuple[float, float]:
    """The point ``along`` metres down the polyline (clamped to its ends)."""
    for (a, b), length in zip(zip(points, points[1:], strict=False), lengths, strict=True):
        if along <= length:
            f = along / length if length > 0.0 else 0.0
            return a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])
        along -= length
    return points[-1]


class Crowd:
    """The people of a world as the simulation steps them: each one's walked time, position, offset
    from their path and patience (module docstring). ``room(x, y)``: the distance from a point to
    the nearest wall, box or pillar, where people may step aside (None: anywhere)."""

    def __init__(self, people: Sequence[Person], room: Callable[[float, float], float] | None = None) -> None:
        self.people = tuple(people)
        self.room = room
        self.walked = np.zeros(len(self.people))
        self.xy = np.array([position_at(p, 0.0) for p in self.people], dtype=float).reshape(-1, 2)
        self.radii = np.array([p.radius for p in self.people], dtype=float)
        self.offset = np.zeros((len(self.people), 2))  # stepped aside from the path by this (world frame)
        self.side = np.zeros(len(self.people), dtype=int)  # +1 left of the way they walk, -1 right, 0 on it
        self.direction = np.ones(len(self.people))  # -1: walking their schedule backwards (turned back)
        self.held = np.zeros(len(self.people))  # s held by a robot standing still, neither walking nor stepping aside
        self._robot: np.ndarray | None = None  # where the robot was at the last step

    def __len__(self) -> int:
        return len(self.people)

    def step(self, dt: float, robot_xy: Sequence[float] | np.ndarray, robot_radius: float) -> None:
        """Advance every person by ``dt`` seconds: walk on, step aside, wait or turn back (module docstring)."""
        robot = np.array(robot_xy, dtype=float)  # a copy: kept as where the robot was, for the next step
        still = self._robot is not None and float(np.hypot(*(robot - self._robot))) <= STILL_M_S * dt
        for i, person in enumerate(self.people):
            if len(person.path) == 1:
                continue
            if self._walk(i, person, dt, robot, robot_radius):
                continue
            if (self.held[i] >= YIELD_S or self.offset[i].any()) and self._step_aside(i, person, dt, robot,
                                                                                      robot_radius):
                continue
            self.held[i] = self.held[i] + dt if still else 0.0  # waits for a robot that is getting on ...
            if self.held[i] >= PATIENCE_S:  # ... and, held by one that stands, goes back the way they came
                self.direction[i], self.held[i], self.side[i] = -self.direction[i], 0.0, 0
        self._robot = robot

    def _walk(self, i: int, person: Person, dt: float, robot: np.ndarray, robot_radius: float) -> bool:
        """One step along the schedule, easing back towards the path (or keeping the offset) where
        that does not come too near the robot; False: the robot holds them."""
        later = self.walked[i] + self.direction[i] * dt
        ahead = np.array(position_at(person, later))
        kept = self.offset[i]
        eased = kept - kept * min(1.0, person.speed * dt / max(float(np.hypot(*kept)), 1e-12))
        passing = person.radius + robot_radius + PASSING_M
        for offset in (eased, kept) if kept.any() else (kept,):
            there = ahead + offset
            aside = offset.any() and _beside(robot, there, there - self.xy[i]) >= passing  # walks past, not at it
            near = passing if aside else person.radius + robot_radius + PERSONAL_SPACE_M
            if self._clear_of(robot, i, there, near) and self._roomy(there, ahead, offset, person.radius):
                self.walked[i], self.xy[i], self.offset[i] = later, there, offset
                if not offset.any():  # back on their path: the encounter is over
                    self.side[i], self.held[i] = 0, 0.0
                return True
        return False

    def _step_aside(self, i: int, person: Person, dt: float, robot: np.ndarray, robot_radius: float) -> bool:
        """One sideways step off the path, away from the robot, where there is room; False: none."""
        on_path = np.array(position_at(person, self.walked[i]))
        heading = np.array(position_at(person, self.walked[i] + self.direction[i] * dt)) - on_path
        if not heading.any():
            return False
        left = np.array([-heading[1], heading[0]]) / float(np.hypot(*heading))
        side = int(self.side[i]) or (-1 if float(np.dot(left, robot - self.xy[i])) > 0.0 else 1)  # away from it
        offset = self.offset[i] + side * left * person.speed * dt
        there = on_path + offset
        if np.hypot(*offset) <= SIDESTEP_M and self._clear_of(
                robot, i, there, person.radius + robot_radius + PASSING_M) and self._roomy(there, on_path, offset,
                                                                                          person.radius):
            self.xy[i], self.offset[i], self.side[i] = there, offset, side
            return True
        return False

    def _clear_of(self, robot: np.ndarray, i: int, there: np.ndarray, reach: float) -> bool:
        """Whether person ``i`` at ``there`` keeps ``reach`` from the robot's centre, or at least comes no nearer."""
        after = float(np.hypot(*(there - robot)))
        return after >= reach or after >= float(np.hypot(*(self.xy[i] - robot)))

    def _roomy(self, there: np.ndarray, on_path: np.ndarray, offset: np.ndarray, radius: float) -> bool:
        """Whether a person stepped aside to ``there`` stands clear of the walls, boxes and pillars (or
        no nearer them than their path at ``on_path``: paths may be drawn anywhere)."""
        if self.room is None or not offset.any():
            return True
        return self.room(*there) >= min(radius, self.room(*on_path))

    def clearance(self, x: float, y: float) -> float:
        """Distance (m) from (x, y) to the nearest person's surface (inf: nobody)."""
        if not len(self.people):
            return math.inf
        return float(np.min(np.hypot(self.xy[:, 0] - x, self.xy[:, 1] - y) - self.radii))


def _beside(point: np.ndarray, through: np.ndarray, heading: np.ndarray) -> float:
    """How far ``point`` lies from the line through ``through`` along ``heading`` (inf: no heading)."""
    length = float(np.hypot(*heading))
    if length == 0.0:
        return math.inf
    return abs(float(heading[0] * (point[1] - through[1]) - heading[1] * (point[0] - through[0]))) / length
