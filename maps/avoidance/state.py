"""The values one tick of getting around reads and writes: its settings, its decision, its tallies,
and the episode (a wait and the detour it may turn into) that :class:`maps.avoidance.detour.Avoidance`
carries from tick to tick. Pure values; the logic is :mod:`maps.avoidance.detour`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

from maps.avoidance.directions import Choice
from maps.avoidance.sweep import DetourLine
from maps.avoidance.wayround import WayRound
from perception.geometry import Pose2D

Phase = Literal["clear", "waiting", "detour", "backoff"]


@dataclass(frozen=True, slots=True)
class DetourSettings:
    """How long to wait, when to give up (:mod:`maps.avoidance.detour`)."""

    wait: float = 2.0  # s held before a detour is tried
    timeout: float = 20.0  # s held (waiting, or on a detour with no direction) before giving up
    clear_time: float = 1.0  # s the way must stay clear to end a wait or a detour
    max_length: float = 6.0  # m: a detour this long that has not got past gives up
    pass_turns: bool = False  # a wish to turn on the spot passes in every phase (nodes that turn by a measured angle)
    going_round: bool = True  # a detour turned by GOING_ROUND gives up (off for nodes whose own path turns)
    undo: bool = False  # a detour held to its timeout: back along its own way, then the other side
    plan: bool = False  # no direction will do: plan a way round on the echoes kept (maps.avoidance.wayround)


@dataclass(frozen=True, slots=True)
class Decision:
    """What the base gets this tick, the phase after the tick and why."""

    v: float
    w: float
    phase: Phase
    choice: Choice | None = None  # the fan, when it was judged this tick
    event: str = ""  # a line for the recording's event log ("" when nothing changed)
    gave_up: str = ""  # the reason, when the avoidance gives up this tick
    passed: bool = False  # the wish went on unchanged


@dataclass
class Tally:
    """What the avoidance did over a run (the report's figures)."""

    waits: int = 0  # times the robot was held for a blocked way
    waits_cleared: int = 0  # ... of which the way cleared by itself (no detour)
    wait_time: float = 0.0  # s held before the way cleared or a detour started
    detours: int = 0
    detour_length: float = 0.0  # m driven on detours (odometry)
    detour_time: float = 0.0  # s
    give_ups: int = 0
    backoffs: int = 0  # times the robot backed away along its trail, no direction doing
    backoff_length: float = 0.0  # m backed (odometry)
    creeps: int = 0  # times a wish held only by what lies beside its way went on at the creep speed
    ways: int = 0  # ways round planned where no direction would do (``plan``)
    way_length: float = 0.0  # m driven along them (odometry)
    reasons: list[str] = field(default_factory=list)  # why, per give-up


@dataclass(frozen=True, slots=True)
class HoldEnded:
    """A hold that stopped without ending (cut short by the node's ending, or left by a back-off):
    since when it held, when it stopped, where, and its back-offs. A new hold soon after, near there,
    is the same hold going on (:meth:`goes_on`)."""

    origin: float
    when: float
    where: Pose2D
    backoffs: int = 0

    def goes_on(self, pose: Pose2D, now: float, *, within: float, near: float) -> bool:
        """Is a hold at ``pose`` now this one going on: within ``within`` s of when it stopped and
        ``near`` m of where?"""
        return now - self.when <= within and math.hypot(pose.x - self.where.x, pose.y - self.where.y) <= near


@dataclass
class Episode:
    """A wait, and the detour it may turn into."""

    since: float  # when the robot was first held
    line: DetourLine
    origin: float  # when the hold began, for the wait and the timeout: since, or a cut hold's (_held_since)
    detour_start: float | None = None
    length: float = 0.0
    turned: float = 0.0  # rad, signed: the heading's change since the detour started
    last: Pose2D | None = None
    side: int = 0
    goal: float | None = None  # rad, odometry: where the wish heads, from its last forward command
    clear_since: float | None = None  # the way clear since (the wish passing again)
    held_since: float | None = None  # on a detour with no direction (or stopped by the monitor) since
    by_monitor: bool = False  # held because the collision monitor stopped a wish the arcs found free
    child_turning: bool = False  # the last tick passed the node's own turn on the spot (pass_turns)
    backoffs: int = 0  # back-offs in this hold; after one the wait lasts until a detour starts
    backing: tuple[float, float] | None = None  # the trail point backed to (odometry), while backing
    backed: float = 0.0  # m backed in the current back-off
    back_limit: float = 0.0  # m the current back-off was asked for (it backs at most twice that)
    beyond: float = 0.0  # m a direction must be free for after a back-off: past where the robot was wedged
    undoing: bool = False  # the back-off going on undoes the detour (``undo``): the other side after it
    undone: bool = False  # the detour was undone once (an episode undoes once)
    anchor: tuple[float, Pose2D] | None = None  # (since, where): the detour has not moved PROGRESS from there since
    way: WayRound | None = None  # the way round being driven (``plan``)
    way_from: tuple[float, float, float] | None = None  # (x, y, heading), odometry: where, whither first planned
    way_start: float = 0.0  # the detour's length when the way began (its length limit counts from there)
    planned: float = -math.inf  # when a way was last planned
