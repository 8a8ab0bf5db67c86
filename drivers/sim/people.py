"""People in a simulated world: where each one is, and how the crowd steps with simulated time.

A person walks a fixed schedule (:func:`position_at`): along the path at its speed, waiting at each
end, round the loop or back and forth, starting at the path's first point at time 0. The schedule
runs on the person's own *walked time*, which the simulation advances with the simulated clock
(:class:`Crowd`); the one thing that holds it is the robot: a person does not walk through the
robot, they wait while their next step would bring them within :data:`PERSONAL_SPACE_M` of its
disc (and closer than they are), as a person would, and walk on once it is out of the way. So
people move deterministically (the robot's motion is deterministic for a seed), never walk into
the robot, and a contact between the robot and a person is always the robot's doing.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import numpy as np

from drivers.sim.world_values import Person

PERSONAL_SPACE_M = 0.1  # m: a walking person stops this far from the robot's disc


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
    """The people of a world as the simulation steps them: each one's walked time and position."""

    def __init__(self, people: Sequence[Person]) -> None:
        self.people = tuple(people)
        self.walked = np.zeros(len(self.people))
        self.xy = np.array([position_at(p, 0.0) for p in self.people], dtype=float).reshape(-1, 2)
        self.radii = np.array([p.radius for p in self.people], dtype=float)

    def __len__(self) -> int:
        return len(self.people)

    def step(self, dt: float, robot_xy: Sequence[float] | np.ndarray, robot_radius: float) -> None:
        """Advance every person by ``dt`` seconds, except those whose next step would come within
        :data:`PERSONAL_SPACE_M` of the robot's disc at ``robot_xy`` and closer than they are now."""
        rx, ry = robot_xy
        for i, person in enumerate(self.people):
            if len(person.path) == 1:
                continue
            nx, ny = position_at(person, self.walked[i] + dt)
            reach = person.radius + robot_radius + PERSONAL_SPACE_M
            after = math.hypot(nx - rx, ny - ry)
            if after < reach and after < math.hypot(self.xy[i, 0] - rx, self.xy[i, 1] - ry):
                continue  # waits for the robot to get out of the way
            self.walked[i] += dt
            self.xy[i] = (nx, ny)

    def clearance(self, x: float, y: float) -> float:
        """Distance (m) from (x, y) to the nearest person's surface (inf: nobody)."""
        if not len(self.people):
            return math.inf
        return float(np.min(np.hypot(self.xy[:, 0] - x, self.xy[:, 1] - y) - self.radii))
