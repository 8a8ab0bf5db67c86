"""The free direction closest to what a motion node wished, and the command that takes it.

A polar histogram in the manner of Borenstein and Koren's vector field histogram (VFH+, Ulrich
& Borenstein 1998), with the footprint's exact sweep in place of a certainty grid:

- the **wish**: where the motion node's command heads, its turn rate times ``steer_time`` from
  the heading (eq. 4); a turn on the spot wishes for the farthest direction that way;
- a **histogram** of ``directions`` evenly spaced over +-``spread``: for each, how far the
  footprint grown by the clearance goes straight that way once it has turned to face it
  (:meth:`maps.avoidance.sweep.Surroundings.free_towards`);
- a direction **will do** when it is free for the distance the detour needs, the turn to face it
  is free, and (with a detour's line and the odometry pose) its end does not lie farther than
  ``max_stray`` from the line unless it comes back towards it (eq. 3);
- the **choice** (eq. 5): of those, the one closest to the wish; once a detour has taken a side
  of the wish it keeps it, and the first choice between two equally close directions goes to
  the side with more of them free;
- the **command** (eq. 6): a direction within ``turn_first`` of the heading is steered to along
  an arc (``speed``, turning by the direction over ``steer_time``) when that arc is free too;
  otherwise the robot turns on the spot towards it at ``turn_rate`` (turning sweeps nothing
  ahead, and the next tick's choice sees from the new heading).

Choosing the direction closest to the wish, not an arc of the command's own, lets the robot turn
towards where the motion node heads when the obstacle is between: a person standing ahead and to
the right of a robot whose goal is ahead and to the right is passed on their far side.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maps.avoidance.sweep import AvoidSettings, DetourLine, Surroundings, needed_distance
from perception.geometry import Pose2D

OTHER_SIDE = 1000.0  # cost added to a direction on the other side of a detour's: taken only when nothing else is


@dataclass(frozen=True, slots=True)
class Direction:
    """One direction of the histogram: its angle from the heading (rad, left positive), how far it is
    free (m), whether the turn to face it is free and whether it strays from the detour's line."""

    angle: float
    free: float
    turns: bool = True
    strays: bool = False

    def will_do(self, reach: float) -> bool:
        return self.free >= reach and self.turns and not self.strays


@dataclass(frozen=True, slots=True)
class Choice:
    """The histogram judged for one wish: the directions, the one chosen (None: none will do), the
    wish (rad) and the distance every direction had to be free for."""

    directions: tuple[Direction, ...]
    chosen: int | None
    wish: float
    reach: float

    @property
    def direction(self) -> Direction | None:
        return None if self.chosen is None else self.directions[self.chosen]

    @property
    def side(self) -> int:
        """+1 when the chosen direction is left of the wish, -1 right, 0 on it or when none is chosen."""
        d = self.direction
        return 0 if d is None else int(np.sign(d.angle - self.wish))

    @property
    def only_straying(self) -> bool:
        """Directions are free, but every one of them strays too far: the bound, not an obstacle, holds the robot."""
        return self.chosen is None and any(d.free >= self.reach and d.turns and d.strays for d in self.directions)


def angles(settings: AvoidSettings) -> np.ndarray:
    """The histogram's directions (rad from the heading), from the farthest right to the farthest left."""
    return np.linspace(-settings.spread, settings.spread, settings.directions)


def wished_direction(v: float, w: float, settings: AvoidSettings) -> float:
    """Where a command heads (eq. 4), within the histogram's spread; a turn on the spot wishes for its edge."""
    if v <= 0.0:
        return math.copysign(settings.spread, w) if w else 0.0
    return float(np.clip(w * settings.steer_time, -settings.spread, settings.spread))  # eq. 4


def choose(around: Surroundings, wish: float, settings: AvoidSettings, *, reach: float | None = None, side: int = 0,
           pose: Pose2D | None = None, line: DetourLine | None = None, within: float = math.inf) -> Choice:
    """Judge the histogram against the points ``around`` the base and choose the direction for the
    ``wish`` (module docstring); ``reach`` defaults to what the detour's speed needs (eq. 1), ``side``
    (+1 left, -1 right of the wish) is the side a detour took; directions more than ``within`` (rad)
    from the wish are not taken."""
    reach = needed_distance(settings.speed, settings) if reach is None else reach
    fan = angles(settings)
    free = around.free_towards(fan)
    directions = tuple(Direction(float(a), float(f), around.turns(float(a)),
                                 _strays(float(a), reach, settings.max_stray, pose, line))
                       for a, f in zip(fan, free, strict=True))
    usable = [i for i, d in enumerate(directions) if d.will_do(reach) and abs(d.angle - wish) <= within]
    if not usable:
        return Choice(directions, None, wish, reach)
    step = float(fan[1] - fan[0]) if len(fan) > 1 else 1.0
    room = {s: _room(directions, wish, s, reach) for s in (-1, 1)}

    def cost(i: int) -> float:
        there = int(np.sign(directions[i].angle - wish))
        off = abs(directions[i].angle - wish) / step  # eq. 5, in steps of the histogram
        if side and there == -side:
            return off + OTHER_SIDE
        return off - (0.5 * room[there] if not side and there else 0.0)

    return Choice(directions, min(usable, key=cost), wish, reach)


def steer(choice: Choice, around: Surroundings, settings: AvoidSettings) -> tuple[float, float]:
    """The command that takes the chosen direction (eq. 6): an arc when it is near the heading and the
    arc is free, else a turn on the spot towards it; a stop when none was chosen."""
    direction = choice.direction
    if direction is None:
        return 0.0, 0.0
    psi = direction.angle
    if abs(psi) <= settings.turn_first:
        v, w = settings.speed, psi / settings.steer_time  # eq. 6
        if around.open(v, w, choice.reach):
            return v, w
    return 0.0, math.copysign(settings.turn_rate, psi) if psi else 0.0


def _room(directions: tuple[Direction, ...], wish: float, side: int, reach: float) -> float:
    """The fraction of the directions on ``side`` of the wish that will do."""
    there = [d for d in directions if np.sign(d.angle - wish) == side]
    return sum(d.will_do(reach) for d in there) / len(there) if there else 0.0


def _strays(psi: float, reach: float, max_stray: float, pose: Pose2D | None, line: DetourLine | None) -> bool:
    """Whether the point ``reach`` metres away in direction ``psi`` lies farther than ``max_stray`` from
    the detour's line and farther than the robot is now (eq. 3)."""
    if pose is None or line is None:
        return False
    x, y = reach * math.cos(psi), reach * math.sin(psi)
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    end = abs(line.offset(pose.x + c * x - s * y, pose.y + s * x + c * y))
    return end > max_stray and end > abs(line.offset(pose.x, pose.y))
