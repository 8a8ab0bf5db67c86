"""One tick of getting around what blocks the way: pass the wish on, wait, detour, or give up.

A motion node wishes a command ``(v, w)``; :class:`Avoidance` decides, once per tick, what the
base gets instead, from the obstacle points around the base (:mod:`perception.obstacle_memory`) and
the robot's odometry. Three phases:

- **clear**: the wish passes unchanged. A forward wish whose arc is not free for as far as it
  means to go (:func:`maps.avoidance.sweep.needed_distance`, but no farther than the node's goal
  when the wish says where that is: ``reach``), or one the collision monitor stopped, holds the
  robot: it waits. Unless only the margin holds it: where the footprint itself goes that far and
  the margin farther, what holds it lies beside the way (a doorway's jambs), and the same arc at
  :data:`CREEP` speed goes on if that is open (a 0.52 m disc keeps 0.09 m each side in a 0.9 m door
  with 0.1 m of clearance, too little for 0.3 m of a turning arc: in `flat` the robot, met at a
  door 14 degrees off its axis, waited, detoured and never went through, while without the
  avoidance it passed 0.17 m from the jambs).
- **waiting**: stopped, so that a person walking across can pass (a blocked way that changes by
  itself costs no detour). The way clearing ends the wait; a way blocked again within
  ``clear_time`` resumes the same wait (the clock keeps running). After ``wait`` seconds still
  blocked, a detour starts when a direction will do (:func:`maps.avoidance.directions.choose`,
  kept within ``max_stray`` of the line the robot was on when it was first held).
- **detour**: every tick the free direction closest to the wish, on the side the detour took,
  steered to (:func:`maps.avoidance.directions.steer`: an arc, or a turn on the spot first).
  Once a forward wish's own arc is free again (as far as the detour needs, a hysteresis) the
  wish passes; ``clear_time`` of that ends the detour, and the motion node steers back to its
  path by itself. A wish to stop or to back away passes (the collision monitor judges it). Where
  the wish heads is kept in the odometry frame from its last forward command, so that a wish to
  turn on the spot (which says only which way) does not swing the choice as the robot turns (a
  turn on the spot the other way from the remembered heading replaces it: :meth:`Avoidance._wish`).
  No direction more than :data:`FACING` (a right angle) from the wish is taken; with none the robot
  is held and backs away (below): a direction farther round drives away from where the node
  heads, which is going back, not round. A hold whose wish is a turn on the spot (the node means
  to face something beyond the fan's edge: a new goal behind the robot) is measured from that
  edge (in `flat`'s exploration the monitor stopped the robot at the mouth of a slot between a bed
  and a wall as a goal 13 m behind it was chosen; the only free direction was straight on, and the
  detour drove 1 m into the slot, where the robot stayed). Until stop 45 the bound held only for
  such a hold, and a detour whose wish had swung round as the robot turned took any direction on
  its side: in the office with 3 more people, a detour started to the right of a pacer; as it
  turned the robot right, the route's viewframe came to lie 90-145 degrees to the left, and the
  detour went on taking the free directions on its right, 100-135 degrees from the wish, driving
  0.6 m north-east, away from home, where the trail was lost. So
  a wish to turn on the spot towards a goal (``reach``) nearer than anything sensed (every point
  farther from the robot's centre than the goal and the footprint's farthest corner together)
  ends the detour at once: the detour took the robot beside its goal (past a person, to a
  waypoint now behind it), and a straight drive there, in whatever direction, touches nothing
  (in an untuned office the detour went on along the corridor, its goal 0.35 m behind, until it
  gave up after 6 m). No direction will do: stopped. With ``pass_turns`` a wish to turn on the
  spot passes in every phase: a node that turns by a measured angle (the roadmap's random moves
  and scans) fails when its turn does not happen; such a turn during a detour is the node's, not
  the detour's, and does not count towards :data:`GOING_ROUND`.

A way round (``plan``): when, :data:`SETTLE` after the wait or ``wait`` seconds into a detour's
hold, no direction within :data:`FACING` will do for the obstacles around (not merely for
straying), a path is planned on the echoes kept longer (``step``'s ``echoes``) before anything
backs away, and driven as a detour (:mod:`maps.avoidance.wayround`); held, it is planned again
(every :data:`REPLAN` s at most); none left, or driven, the detour goes on as without it. The
turns on a way are not the detour's (:data:`GOING_ROUND`), and its length counts from the way's start.

Backing away (``backoff``): when, after the wait or ``wait`` seconds into a detour's hold, no
direction will do for the obstacles around (not merely for straying), the robot backs along its
own trail (:mod:`maps.avoidance.backoff`) up to ``distance`` metres, then judges again from there;
after a back-off a direction must be free past where the robot was wedged (the distance backed
plus what the detour needs), or the detour would drive straight back into the corner, and the
way clearing no longer ends the wait (the wish would lead back in too): a detour must start. At
most :data:`BACKOFFS_PER_HOLD` back-offs per hold; a new hold soon (within ``timeout``) after one,
near where it began, is the same hold (its clock and back-offs go on), so driving back in and
backing out cannot go on for ever. The timeout counts on through back-offs, and ends one that
is still going ("backing away 0.20 m did not free the way").

Undoing a detour (``undo``): where a detour held with no direction would give up (its
``timeout``), it backs along its own way instead, as far as it went (up to the trail kept),
whatever ``distance`` says, once (not a detour shorter than
:data:`~maps.avoidance.backoff.MIN_BACK`: it led nowhere), and then takes the other side of the
wish, giving up ``wait`` seconds later when no direction will do there either: the side it took
led into a wedge (in the lab, between a pillar and a person standing on the route, where the
robot stood for 200 s, losing 20 s at a time to a give-up, a skip that saw nothing farther and a
search that found the trail where it stood). Not sooner: a wedge a walking person makes opens by
itself.

Giving up (FAILURE, with a reason, so the mission's recovery takes over): held, waiting or
without a direction, for ``timeout`` seconds (a hold the motion node's ending cut short, a route
follower losing the trail for a moment, goes on counting when the node starts again within
:data:`RESTART_GAP` where the robot stood: otherwise a node that fails and is restarted every
few seconds in front of a person would hold the robot for ever) ("blocked for 20 s by an obstacle 0.40 m ahead"), a
detour longer than ``max_length`` metres that has not got past, one that has turned by
:data:`GOING_ROUND` (180 degrees): it is going round the obstacle, because what the motion node
heads for is behind it or in it (a person standing where a viewframe was taught), or one that has
got nowhere (not :data:`PROGRESS` m from where it was) for ``timeout`` seconds: turning to and fro
on the spot between two directions, each blocked once faced (in the lab, 166 s wedged between a
desk and two people until the time limit). A new detour soon after one given up (within
``timeout``), near where it was given up (within ``max_stray``), takes the other side of the wish:
the side the last one took led into a corner (in the lab, south of two people standing 0.24 m
apart beside a desk, while the way past was north of both).

Pure: no clock of its own (``now`` is passed in), no I/O; the tallies (:class:`Tally`) are what
the run report's ``avoidance`` section shows.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from maps.avoidance.backoff import MIN_BACK, STEP, BackoffSettings, Trail, back_command
from maps.avoidance.directions import Choice, choose, steer, wished_direction
from maps.avoidance.state import Decision, DetourSettings, Episode, HoldEnded, Phase, Tally
from maps.avoidance.sweep import AvoidSettings, DetourLine, Surroundings, free_distance, needed_distance
from maps.avoidance.wayround import WayRound, along, plan
from perception.echo_map import EchoMap
from perception.geometry import Pose2D, wrap_angle
from perception.polygons import distance, enclosing_radius

GOING_ROUND = math.pi  # rad: a detour that has turned this much is going round the obstacle, not past it
BACKOFFS_PER_HOLD = 2  # back-offs in one hold (the hold goes on where the robot backed away from)
RESTART_GAP = 2.0  # s: a hold cut short by the node's ending goes on when held again this soon ...
STOOD = 0.05  # m: ... this close to where it was held
PROGRESS = 0.1  # m: a detour that has not moved this far from where it was for ``timeout`` s got nowhere
CREEP = 0.1  # m/s: a wish held only by the margin beside its way goes on this slowly, where that is open
FACING = math.pi / 2.0  # rad: a detour takes no direction farther than this from the wish
REPLAN = 1.0  # s: a way round held is planned again at most this often
SETTLE = 1.0  # s beyond the wait before a way round is planned: a walker gone is in the last second's echoes
WAY_LENGTH = 2.0  # a way round may be this many times a detour's ``max_length`` (it goes back round what holds it)



class Avoidance:
    """Decides each tick's command for one motion node's wishes (module docstring)."""

    def __init__(self, avoid: AvoidSettings, settings: DetourSettings | None = None,
                 backoff: BackoffSettings | None = None) -> None:
        self.avoid = avoid
        self.settings = settings or DetourSettings()
        self.backoff = backoff or BackoffSettings()
        self.trail = Trail(keep=self.backoff.keep)
        self._backed_from: HoldEnded | None = None  # the last back-off: its hold, when it ended, where it began
        self.tally = Tally()
        self.phase: Phase = "clear"
        self._episode: Episode | None = None
        self._pose: Pose2D | None = None  # the last tick's
        self._cut: HoldEnded | None = None  # a hold that reset cut short
        self._failed: tuple[Pose2D, float, int] | None = None  # the last detour given up: (where, when, its side)
        self._creeping = False  # the last tick went on at the creep speed
        self._around: tuple[np.ndarray, EchoMap | None] = (np.zeros((0, 2)), None)  # this tick's points, echoes kept

    @property
    def line(self) -> DetourLine | None:
        """The line the current wait or detour started on (None while clear)."""
        return self._episode.line if self._episode is not None else None

    @property
    def way(self) -> WayRound | None:
        """The way round being driven (None: none)."""
        return self._episode.way if self._episode is not None else None

    def step(self, v: float, w: float, points: np.ndarray, pose: Pose2D, now: float, *,
             stopped: bool = False, reach: float = math.inf, echoes: EchoMap | None = None) -> Decision:
        """The command for the wish ``(v, w)`` with ``points`` around the base (base frame), the
        robot at odometry ``pose``; ``stopped``: the collision monitor stopped the last command;
        ``reach``: how far the wish means to go before the node's goal (m; ``inf``: no goal in sight);
        ``echoes``: the echoes kept longer (:mod:`perception.echo_map`), which a way round is planned
        on, with ``points`` (``plan``; None: none is)."""
        self._around = (points, echoes)
        creeping, self._creeping = self._creeping, False
        episode = self._episode
        if episode is not None and episode.backing is not None:
            backing = self._back(episode, Surroundings.of(points, self.avoid), pose, now)
            if backing is not None:
                return backing
        self.trail = self.trail.added(pose)
        if self.settings.pass_turns and v == 0.0 and w != 0.0:  # the monitor judges a turn on the spot
            episode = self._episode
            if episode is not None and episode.detour_start is not None:
                self._travelled(episode, pose)
                episode.child_turning = True  # its own measured turn is not the detour's: not counted
            return Decision(v, w, self.phase, passed=True)
        around = Surroundings.of(points, self.avoid)
        self._pose = pose
        episode = self._episode
        if episode is not None and episode.detour_start is not None:
            return self._detour(episode, v, w, around, pose, now, stopped, reach)
        blocked = self._blocked(v, w, around, reach=reach)
        if self.phase == "clear":
            if not blocked and not (stopped and v > 0.0):
                self._settle(now)
                return Decision(v, w, "clear", passed=True)
            creep = None if stopped else self._creep(v, w, around, reach, now, creeping)
            if creep is not None:
                return creep
            return self._hold(v, w, around, pose, now, by_monitor=not blocked)
        assert episode is not None
        if not blocked and not episode.by_monitor and not episode.backoffs:  # cleared while waiting (once it stays)
            self.phase, episode.clear_since = "clear", now
            return Decision(v, w, "clear", event=f"the way cleared after {now - episode.since:.1f} s", passed=True)
        return self._wait(episode, v, w, around, pose, now)

    def reset(self, now: float) -> None:
        """End whatever is going on (the motion node ended or was halted), tallying it as it is."""
        episode = self._episode
        held = None if episode is None else episode.held_since if episode.detour_start is not None else \
            None if self.phase == "clear" else episode.origin
        self._cut = None if held is None or self._pose is None else HoldEnded(held, now, self._pose)
        if episode is not None:
            if episode.detour_start is not None:
                self._end_detour(episode, now)
            elif self.phase == "clear" and episode.clear_since is not None:
                self._end_wait(episode, episode.clear_since, cleared=True)
            else:
                self.tally.wait_time += now - episode.since
            self.tally.backoff_length += episode.backed
        self.phase, self._episode = "clear", None

    # -- the phases ------------------------------------------------------------------------------
    def _hold(self, v: float, w: float, around: Surroundings, pose: Pose2D, now: float, *, by_monitor: bool
              ) -> Decision:
        """A clear way is blocked: wait (or go on waiting, when it cleared only a moment ago). Held by
        the monitor alone (the arcs find the wish free), the wait lasts until a detour starts."""
        self._settle(now)
        episode = self._episode
        resumed = episode is not None and episode.clear_since is not None
        if episode is None or not resumed:
            episode = self._episode = Episode(now, DetourLine.at(pose), self._held_since(pose, now))
            self._near_backoff(episode, pose, now)
            self.tally.waits += 1
        episode.clear_since = None
        episode.by_monitor = episode.by_monitor or by_monitor
        self.phase = "waiting"
        ahead = "(the collision monitor stopped it)" if by_monitor else self._ahead(v, w, around.points)
        return Decision(0.0, 0.0, "waiting", event="" if resumed else f"the way is blocked {ahead}: waiting")

    def _wait(self, episode: Episode, v: float, w: float, around: Surroundings, pose: Pose2D, now: float
              ) -> Decision:
        held = now - episode.origin
        if held < self.settings.wait:
            return Decision(0.0, 0.0, "waiting")
        choice = choose(around, self._wish(episode, v, w, pose), self.avoid, reach=self._reach(v, episode), pose=pose,
                        line=episode.line, side=self._other_side(pose, now), within=FACING)
        if choice.direction is not None:
            self._start_detour(episode, pose, now, choice.side)
            side = {1: "left", -1: "right"}.get(choice.side, "ahead")
            return Decision(*steer(choice, around, self.avoid), "detour", choice,
                            f"detour to the {side} after {held:.1f} s")
        if self._planned(episode, held, choice, (v, w), pose, now):
            self._start_detour(episode, pose, now, 0)
            return self._way_begun(episode, (v, w), around, pose, now, f"no direction will do after {held:.1f} s")
        backing = self._start_back(episode, choice, around, pose, now)
        if backing is not None:
            return backing
        if held >= self.settings.timeout:
            return self._give_up(self._blocked_reason(held, v, w, around.points, choice), now)
        return Decision(0.0, 0.0, "waiting", choice)

    def _detour(self, episode: Episode, v: float, w: float, around: Surroundings, pose: Pose2D, now: float,
                stopped: bool, reach: float) -> Decision:
        self._travelled(episode, pose)
        episode.child_turning = False
        reason = self._detour_over(episode, pose, now)
        if reason:
            self._failed = (pose, now, episode.side)
            return self._give_up(reason, now)
        if v < 0.0 or (v == 0.0 and w == 0.0):  # backing away (from a stall), stopping: the monitor's to judge
            episode.clear_since = None
            return Decision(v, w, "detour", passed=True)
        if episode.way is not None:
            on_way = self._on_way(episode, (v, w), around, pose, now, stopped=stopped)
            if on_way is not None:
                return on_way
        if v == 0.0 and around.goal_free(reach, enclosing_radius(self.avoid.footprint)):  # nothing as near: done
            return self._detour_done(episode, v, w, now, f"the goal {reach:.2f} m away, nothing nearer")
        if v > 0.0 and not stopped and not self._blocked(v, w, around, at_least=self._reach(v), reach=reach):
            episode.held_since = None
            episode.clear_since = now if episode.clear_since is None else episode.clear_since
            if now - episode.clear_since >= self.settings.clear_time:
                return self._detour_done(episode, v, w, now, "past the obstacle")
            return Decision(v, w, "detour", passed=True)
        episode.clear_since = None
        choice = choose(around, self._wish(episode, v, w, pose), self.avoid, reach=self._reach(v, episode),
                        side=episode.side, pose=pose, line=episode.line, within=FACING)
        command = steer(choice, around, self.avoid)
        if choice.direction is not None and not stopped and command != (0.0, 0.0):
            episode.held_since = None
        else:  # no direction will do, none that moves the robot, or the monitor stopped the last command: held
            held = self._detour_held(episode, (v, w), choice, around, pose, now)
            if held is not None:
                return held
        episode.side = episode.side or choice.side
        return Decision(*command, "detour", choice)

    def _detour_held(self, episode: Episode, wish: tuple[float, float], choice: Choice, around: Surroundings,
                     pose: Pose2D, now: float) -> Decision | None:
        """A detour held with no direction: after ``wait``, a way round planned, or backing away; after
        ``timeout``, giving up. None: held on."""
        episode.held_since = now if episode.held_since is None else episode.held_since
        held = now - episode.held_since
        if held >= self.settings.wait:
            if self._planned(episode, held, choice, wish, pose, now):
                return self._way_begun(episode, wish, around, pose, now, f"no direction will do after {held:.1f} s")
            backing = self._start_back(episode, choice, around, pose, now, timed_out=held >= self.settings.timeout)
            if backing is not None:
                return backing
        if held >= self.settings.timeout:
            return self._give_up(self._blocked_reason(held, *wish, around.points, choice), now)
        return None

    def _start_detour(self, episode: Episode, pose: Pose2D, now: float, side: int) -> None:
        """A wait turns into a detour."""
        self._end_wait(episode, now, cleared=False)
        episode.detour_start, episode.last, episode.side = now, pose, side
        self.phase = "detour"
        self.tally.detours += 1

    def _planned(self, episode: Episode, held: float, choice: Choice, wish: tuple[float, float], pose: Pose2D,
                 now: float) -> bool:
        """Held ``held`` s with no direction: is a way round planned (module docstring)?"""
        return not choice.only_straying and held >= self.settings.wait + SETTLE and \
            self._plan_way(episode, *wish, pose, now)

    def _plan_way(self, episode: Episode, v: float, w: float, pose: Pose2D, now: float) -> bool:
        """Plan a way round past where the robot was first held, along where the wish headed then,
        every :data:`REPLAN` s at most, :data:`WAY_LENGTH` detours long at most. True: ``episode.way``."""
        points, echoes = self._around
        if not self.settings.plan or echoes is None or now - episode.planned < REPLAN:
            return False
        episode.planned = now
        if episode.way_from is None:
            heading = episode.goal if episode.goal is not None else pose.theta + wished_direction(v, w, self.avoid)
            episode.way_from = (pose.x, pose.y, heading)
        x, y, heading = episode.way_from
        way = plan(np.vstack((points, echoes.around(pose))), pose, heading, self.avoid, origin=(x, y),
                   line=episode.line)
        if way is None or way.length > WAY_LENGTH * self.settings.max_length:
            return False
        if episode.way is None:
            self.tally.ways += 1
            episode.way_start, episode.turned = episode.length, 0.0
        if episode.held_since is None:  # a way planned from a wait: held since the hold began, until it moves
            episode.held_since = episode.origin
        episode.way = way
        return True

    def _way_begun(self, episode: Episode, wish: tuple[float, float], around: Surroundings, pose: Pose2D,
                   now: float, why: str) -> Decision:
        """The first tick along a way round just planned (``why``: what ended the detour without it)."""
        way = episode.way
        assert way is not None
        event = f"{why}: a way round of {way.length:.2f} m"
        return self._on_way(episode, wish, around, pose, now, stopped=False, event=event) or \
            Decision(0.0, 0.0, "detour", event=event)

    def _on_way(self, episode: Episode, wish: tuple[float, float], around: Surroundings, pose: Pose2D, now: float,
                *, stopped: bool, event: str = "") -> Decision | None:
        """A tick along the way round (:func:`maps.avoidance.wayround.along`); held, it is planned again
        (:data:`REPLAN`), and dropped when there is none. None once it is driven or dropped: the detour
        goes on as without it (the wish's own arc free does not end it: a pocket's mouth is free)."""
        way = episode.way
        assert way is not None
        if way.driven(pose):
            self._way_over(episode)
            return None
        command, choice = along(way, around, pose, self.avoid)
        if not stopped and command != (0.0, 0.0):
            episode.held_since = None
            return Decision(*command, "detour", choice, event)
        episode.held_since = now if episode.held_since is None else episode.held_since
        held = now - episode.held_since
        if held >= self.settings.timeout:
            reason = self._blocked_reason(held, *wish, around.points, choice)
            return self._give_up(f"{reason}; the way round planned ({way.length:.2f} m) was not free", now)
        if now - episode.planned < REPLAN or self._plan_way(episode, 0.0, 0.0, pose, now):
            return Decision(0.0, 0.0, "detour", choice, event)
        self._way_over(episode)
        return None

    def _way_over(self, episode: Episode) -> None:
        """The way is driven or dropped; its turns are not the detour's (it went back round)."""
        self.tally.way_length += episode.length - episode.way_start
        episode.way, episode.turned = None, 0.0

    def _detour_done(self, episode: Episode, v: float, w: float, now: float, why: str) -> Decision:
        """End a detour that did its work; the wish passes."""
        length, took = episode.length, now - (episode.detour_start or now)
        self._end_detour(episode, now)
        self.phase, self._episode = "clear", None
        return Decision(v, w, "clear", event=f"{why}: a detour of {length:.2f} m in {took:.1f} s", passed=True)

    def _detour_over(self, episode: Episode, pose: Pose2D, now: float) -> str:
        """Why a detour gives up now ("" while it goes on): too long, going round, or getting nowhere."""
        if episode.length - episode.way_start > self.settings.max_length:
            return (f"a detour of {episode.length:.1f} m did not get past the obstacle "
                    f"(at most {self.settings.max_length:g} m)")
        if self.settings.going_round and episode.way is None and abs(episode.turned) > GOING_ROUND:
            return (f"the detour turned {math.degrees(abs(episode.turned)):.0f} deg: it goes round the obstacle, "
                    "not past it")
        if episode.anchor is None or math.hypot(pose.x - episode.anchor[1].x, pose.y - episode.anchor[1].y) > PROGRESS:
            episode.anchor = (now, pose)
        elif episode.held_since is None and now - episode.anchor[0] >= self.settings.timeout:  # held: its own timeout
            return f"the detour got nowhere for {now - episode.anchor[0]:.0f} s (within {PROGRESS:g} m)"
        return ""

    def _start_back(self, episode: Episode, choice: Choice, around: Surroundings, pose: Pose2D, now: float,
                    *, timed_out: bool = False) -> Decision | None:
        """No direction will do for the obstacles around: back away along the trail
        (:mod:`maps.avoidance.backoff`), if this hold has not done so :data:`BACKOFFS_PER_HOLD` times,
        the trail goes back far enough and the way back is free. Not when free directions stray too far
        (the bound holds the robot, not an obstacle). A detour's hold that has ``timed_out`` is undone
        instead, with ``undo``: back along the detour's own way, once (module docstring)."""
        undo = timed_out and self.settings.undo and episode.detour_start is not None and not episode.undone \
            and episode.length >= MIN_BACK  # a detour that hardly moved led nowhere: nothing to undo
        distance = min(episode.length, self.backoff.keep) if undo else self.backoff.distance
        if distance <= 0.0 or (episode.backoffs >= BACKOFFS_PER_HOLD and not undo) or choice.only_straying:
            return None
        target, trail = self.trail.target(pose, distance)
        command = None if target is None else back_command(target, pose, around, self.avoid, self.backoff)
        if target is None or command is None:
            return None
        self.trail = trail
        episode.backing, episode.backed, episode.last, episode.back_limit = target, 0.0, pose, distance
        if undo:  # the drive back has the hold's whole timeout; after it, only a wait (_back)
            episode.undoing, episode.undone, episode.held_since = True, True, now
        episode.backoffs += 1
        self._backed_from = HoldEnded(episode.origin, now, pose, episode.backoffs)
        self.phase = "backoff"
        self.tally.backoffs += 1
        away = math.hypot(target[0] - pose.x, target[1] - pose.y)
        return Decision(*command, "backoff", event=f"no way round: backing away {away:.2f} m the way it came")

    def _back(self, episode: Episode, around: Surroundings, pose: Pose2D, now: float) -> Decision | None:
        """A tick of backing away; None once it is over (at the trail point, backed twice the distance,
        or the way back blocked): the phase it interrupted goes on from where the robot now stands."""
        assert episode.backing is not None
        if episode.last is not None:
            episode.backed += math.hypot(pose.x - episode.last.x, pose.y - episode.last.y)
        episode.last = pose
        held = episode.origin if episode.detour_start is None else episode.held_since
        if held is not None and now - held >= self.settings.timeout:  # the hold's timeout counts on while backing
            return self._give_up(f"blocked for {now - held:.0f} s: backing away {episode.backed:.2f} m did not "
                                 "free the way", now)
        tx, ty = episode.backing
        command = None
        if math.hypot(tx - pose.x, ty - pose.y) > STEP and episode.backed < 2.0 * episode.back_limit:
            command = back_command(episode.backing, pose, around, self.avoid, self.backoff)
        if command is not None:
            return Decision(*command, "backoff")
        self.tally.backoff_length += episode.backed
        episode.beyond = episode.backed + needed_distance(self.avoid.speed, self.avoid)
        episode.backing, episode.backed = None, 0.0
        if episode.undoing:  # the side the detour took led into a wedge: the other, or give up after a wait
            episode.undoing, episode.side = False, -episode.side
            episode.held_since = now - max(0.0, self.settings.timeout - self.settings.wait)
        self.phase = "waiting" if episode.detour_start is None else "detour"
        if self._backed_from is not None:  # a hold near here goes on from when the back-off ended
            self._backed_from = replace(self._backed_from, when=now)
        return None

    def _other_side(self, pose: Pose2D, now: float) -> int:
        """The side a new detour must take (0: either): the other side of a detour given up soon
        before (within ``timeout``), near here (within ``max_stray``), which took one side and got
        nowhere or went round: that side led into a corner, and the other may not."""
        failed = self._failed
        if failed is None or not failed[2]:
            return 0
        where, when, side = failed
        near = math.hypot(pose.x - where.x, pose.y - where.y) <= self.avoid.max_stray
        return -side if near and now - when <= self.settings.timeout else 0

    def _near_backoff(self, episode: Episode, pose: Pose2D, now: float) -> None:
        """A new hold soon (within ``timeout``) after a back-off, near where the robot backed away from:
        the same hold (its clock and its back-offs go on), so that driving back into the corner and
        backing away again cannot go on for ever."""
        record = self._backed_from
        if record is not None and record.goes_on(pose, now, within=self.settings.timeout,
                                                 near=self.backoff.distance + STEP):
            episode.origin, episode.backoffs = min(episode.origin, record.origin), record.backoffs

    @staticmethod
    def _travelled(episode: Episode, pose: Pose2D) -> None:
        """Add the motion since the last tick to the detour's length and turn, unless it was the motion
        node's own turn on the spot passed with ``pass_turns`` (a homing's measured turns to and from a
        sidestep would otherwise add up to the 180 degrees that give up)."""
        if episode.last is not None and not episode.child_turning:
            episode.length += math.hypot(pose.x - episode.last.x, pose.y - episode.last.y)
            episode.turned += wrap_angle(pose.theta - episode.last.theta)
        episode.last = pose

    def _held_since(self, pose: Pose2D, now: float) -> float:
        """When a new hold began: now, or when a hold cut short by the node's ending began, if the
        robot is held again soon after where it stood (module docstring)."""
        cut, self._cut = self._cut, None
        return cut.origin if cut is not None and cut.goes_on(pose, now, within=RESTART_GAP, near=STOOD) else now

    def _give_up(self, reason: str, now: float) -> Decision:
        self.reset(now)
        self._cut = self._backed_from = None
        self.tally.give_ups += 1
        self.tally.reasons.append(reason)
        return Decision(0.0, 0.0, "clear", event=f"gave up: {reason}", gave_up=reason)

    # -- tallies ---------------------------------------------------------------------------------
    def _settle(self, now: float) -> None:
        """A wait whose way has stayed clear for ``clear_time`` is over."""
        episode = self._episode
        if episode is not None and episode.clear_since is not None and \
                now - episode.clear_since >= self.settings.clear_time:
            self._end_wait(episode, episode.clear_since, cleared=True)
            self._episode = None

    def _end_wait(self, episode: Episode, end: float, *, cleared: bool) -> None:
        self.tally.wait_time += end - episode.since
        self.tally.waits_cleared += int(cleared)

    def _end_detour(self, episode: Episode, now: float) -> None:
        if episode.way is not None:
            self._way_over(episode)
        self.tally.detour_length += episode.length
        self.tally.detour_time += now - (episode.detour_start or now)

    # -- judging the wish ------------------------------------------------------------------------
    def _blocked(self, v: float, w: float, around: Surroundings, at_least: float = 0.0, reach: float = math.inf
                 ) -> bool:
        """Is a forward wish's arc not free for as far as it means to go (eq. 1, or ``at_least`` that
        far, but never beyond the node's goal ``reach`` metres on), or does it graze a point already
        within the clearance? What lies beyond the goal does not block a wish that stops there, and the
        goal itself may lie nearer something than the clearance (a target taken beside a desk).
        Turns on the spot and backing away are the collision monitor's to judge."""
        if v <= 0.0:
            return False
        need = max(needed_distance(v, self.avoid), at_least)
        return not around.open(v, w, need, goal=reach)

    def _creep(self, v: float, w: float, around: Surroundings, reach: float, now: float, creeping: bool
               ) -> Decision | None:
        """Go on at the creep speed where only the margin beside the way holds the wish
        (:meth:`_squeeze`); None: it does not. A spell of creeping is one event and one count."""
        slow = self._squeeze(v, w, around, reach)
        if slow is None:
            return None
        self._settle(now)
        self._creeping = True
        if creeping:
            return Decision(*slow, "clear")
        self.tally.creeps += 1
        return Decision(*slow, "clear", event=f"held only by what lies beside the way: on at {CREEP:g} m/s")

    def _squeeze(self, v: float, w: float, around: Surroundings, reach: float) -> tuple[float, float] | None:
        """A forward wish held only by the margin beside its way: the footprint itself goes as far as the
        wish means to go and the margin farther, and grazes nothing, so what holds it lies beside the
        way, not in it (a doorway's jambs; something ahead is nearer the footprint's front than that).
        The same arc at :data:`CREEP` speed, if that is open (it needs less room); None otherwise."""
        if v <= CREEP:
            return None
        need = min(needed_distance(v, self.avoid) + around.margin, reach)
        if free_distance(self.avoid.footprint, around.points, v, w) < need or around.grazes(v, w, reach):
            return None
        slow = (CREEP, w * CREEP / v)
        return None if self._blocked(*slow, around, reach=reach) else slow

    def _ahead(self, v: float, w: float, points: np.ndarray) -> str:
        """Where the obstacle is, in words: along the wish's arc, or the nearest point."""
        if len(points) == 0:
            return "ahead"
        along = free_distance(self.avoid.footprint, points, v, w) if v > 0.0 else math.inf
        if math.isfinite(along):
            return f"{along:.2f} m ahead"
        return f"{float(distance(self.avoid.footprint, points).min()):.2f} m away"

    def _blocked_reason(self, held: float, v: float, w: float, points: np.ndarray, choice: Choice | None) -> str:
        reason = f"blocked for {held:.0f} s by an obstacle {self._ahead(v, w, points)}"
        if choice is not None and choice.only_straying:
            reason += f"; no way around within {self.avoid.max_stray:g} m of the path"
        return reason

    def _wish(self, episode: Episode, v: float, w: float, pose: Pose2D) -> float:
        """Where the wish heads from the robot's heading now (rad). A forward command says it (eq. 4),
        and is remembered in the odometry frame; a turn on the spot says only which way, so the
        remembered heading stands for it (the turn's way while there is none), and the choice does
        not swing as the robot turns. A turn on the spot away from the remembered heading (it lies to
        the left, the node turns right) says the node wants what the memory does not: the turn's way
        stands for it from then on (in the office, a detour followed a heading remembered 44 degrees
        left for 10 s while the route follower turned right, back towards its route, and drove
        through a door into a room, where the trail was lost)."""
        if v > 0.0 or episode.goal is None or _turns_away(episode.goal, pose, v, w):
            episode.goal = pose.theta + wished_direction(v, w, self.avoid)
        return float(np.clip(wrap_angle(episode.goal - pose.theta), -self.avoid.spread, self.avoid.spread))

    def _reach(self, v: float, episode: Episode | None = None) -> float:
        """How far a detour's direction must be free: as far as the detour's speed needs, or the wish's,
        the farther (a direction taken instead of the wish is free in the sense the wish was blocked);
        after a back-off, past where the robot was wedged (a direction ending there is no way out)."""
        beyond = 0.0 if episode is None else episode.beyond
        return max(needed_distance(self.avoid.speed, self.avoid), needed_distance(v, self.avoid), beyond)


def _turns_away(goal: float, pose: Pose2D, v: float, w: float) -> bool:
    """Is the wish a turn on the spot the other way from the remembered heading ``goal`` (odometry)?"""
    if v != 0.0 or w == 0.0:
        return False
    return float(np.sign(wrap_angle(goal - pose.theta))) == -float(np.sign(w))
