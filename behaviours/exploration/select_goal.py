"""The next exploration goal (algorithm 3, eq. 1): :class:`SelectGoalPoint`.

It chooses where to go next by the attractive power of the detected points (eq. 1; frontier mode
when no point lies more than K beyond the border, :mod:`maps.exploration.goal`), and succeeds when
no border is reachable: exploration is done. It works in the frame of the pose it reads on its
``odometry`` input, like :class:`behaviours.exploration.map_stereo.MapStereo`. Path following is
:class:`behaviours.exploration.follow_path.FollowPath`, the gaze :mod:`behaviours.exploration.gaze`.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import replace
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.exploration.ports import CLEARANCE, MAP, MARGIN, PENALTY, POSE, ROBOT_RADIUS, disc_radius
from behaviours.footprint import FOOTPRINT
from behaviours.ports import InputPort, OutputPort
from behaviours.registry import register
from behaviours.telemetry import Drawing, Figure, Lines, Points
from maps.exploration.goal import (
    Goal,
    GoalParams,
    Mode,
    ModeSwitch,
    goal_travel,
    select_goal,
    verification_goal,
)
from maps.exploration.grid import ExplorationMap
from maps.exploration.queries import blocking_cells, moved_onto
from maps.exploration.travel import TravelCost
from perception.geometry import Pose2D

STRATEGIES = ("nearby_attraction", "attraction", "closest_frontier")


@register
class SelectGoalPoint(BearingsBehaviour):
    """Choose the next exploration goal by attractive power (eq. 1); SUCCESS when no border is reachable.

    ``A_P = d(P_p, P_b) - eta G(v_S, P_b)``: the detected point farthest beyond the explored
    border, less eta times the travel cost to that border; the goal is the border point ``P_b``
    (see :mod:`maps.exploration.goal`). No point more than ``k`` beyond the border: frontier mode,
    the closest reachable border point, until one is. ``strategy``: ``nearby_attraction`` (the
    default) lets only points whose border point costs at most ``nearby`` metres more than the
    closest one compete; ``attraction`` is eq. 1 over all points, as the paper writes it (it goes
    after far points first); ``closest_frontier`` is frontier mode always (the evaluation's
    baseline). The goal is chosen again every ``reselect`` seconds (the map grows as the robot
    drives; the current goal is kept while within ``hysteresis`` of the best) and when the robot
    is within ``reach`` of it (its point is then spent and its border point avoided: the unknown
    beyond it was not seen from there). Points seen in fewer than
    ``min_sightings`` observations do not attract (stray stereo matches).

    RUNNING while there is a goal (written to ``goal``; path following and the gaze read it);
    SUCCESS when no border has been reachable ``patience`` selections in a row (DONE); FAILURE
    when no border is reachable but patience is not used up: look around and tick it again (a
    recovery). A goal abandoned because the branch was halted (path following failed: a path
    blocked by what the cameras saw on the way) is spent and its border point avoided too. Before a
    selection finds no border, the avoided border points get a second chance (the map may have
    changed since: a doorway's stray obstacles cleared; the cameras looked elsewhere on arrival);
    one reached or abandoned again is avoided for good. Before a selection without a reachable border
    counts, the obstacle cells that close a border a narrower disc reaches are looked at again
    (:func:`maps.exploration.goal.verification_goal`: a VERIFY goal), once per place; a place
    whose look-from point is within ``reach`` of the robot already is looked at by the look-around
    the FAILURE starts (driving there would end at once, before the cameras turn to it); so is the
    place of a VERIFY goal once reached (FAILURE, not a strike): the cameras, watching interest
    edges on the way, need not have looked at it (in the office, 15 trips to look again ended with
    a doorway's cells where they were, the only look-around far from them).
    The mode, strikes, spent points, avoided targets and verified places outlive re-entries.
    """

    STRATEGY = InputPort("strategy", str, "nearby_attraction", choices=STRATEGIES, literal_only=True,
                         doc="nearby_attraction: eq. 1 among the points whose border is within nearby of the "
                             "closest; attraction: eq. 1 over all points; closest_frontier: the closest border always")
    ETA = InputPort("eta", float, 0.25, minimum=0.0, maximum=0.5, literal_only=True,
                    doc="weight of the travel cost in eq. 1")
    K = InputPort("k", float, 1.0, unit="m", minimum=0.0, maximum=100.0, literal_only=True,
                  doc="a point must lie this far beyond the border to attract")
    PATIENCE = InputPort("patience", int, 2, minimum=1, maximum=100, literal_only=True,
                         doc="selections in a row without a reachable border before done")
    MIN_FRONTIER = InputPort("min_frontier", float, 0.3, unit="m", minimum=0.0, maximum=10.0, literal_only=True,
                             doc="shorter border pieces are ignored")
    HYSTERESIS = InputPort("hysteresis", float, 0.5, unit="m", minimum=0.0, maximum=10.0, literal_only=True,
                           doc="keep the current goal while its power (frontier: cost) is this close to the best")
    RESELECT = InputPort("reselect", float, 2.0, unit="s", minimum=0.1, maximum=600.0, literal_only=True,
                         doc="choose again this often while driving")
    REACH = InputPort("reach", float, 0.6, unit="m", minimum=0.05, maximum=5.0, literal_only=True,
                      doc="a goal this close is reached")
    MIN_SIGHTINGS = InputPort("min_sightings", int, 2, minimum=1, maximum=1000, literal_only=True,
                              doc="points seen in fewer observations do not attract")
    POINT_CLEARANCE = InputPort("point_clearance", float, 0.3, unit="m", minimum=0.0, maximum=10.0,
                                literal_only=True,
                                doc="points whose floor projection is this close to an obstacle do not attract")
    VERIFY_RADIUS = InputPort("verify_radius", float, 0.13, unit="m", minimum=0.0, maximum=2.0, literal_only=True,
                              doc="before done, look again at what closes a border a disc this size reaches "
                                  "(0: never)")
    LOOK_BACK = InputPort("look_back", float, 1.0, unit="m", minimum=0.0, maximum=10.0, literal_only=True,
                          doc="...from this far before the first place the robot's disc cannot pass")
    NEARBY = InputPort("nearby", float, 1.0, unit="m", minimum=0.0, maximum=100.0, literal_only=True,
                       doc="nearby_attraction: a point attracts when its border costs at most this more than the "
                           "closest border")
    GOAL_OUT: OutputPort[Goal | None] = OutputPort("goal", Goal, "/map/exploration_goal",
                                                   doc="the goal: border point, path, mode (None: none)")
    PORTS = (STRATEGY, ETA, K, ROBOT_RADIUS, CLEARANCE, MARGIN, PENALTY, PATIENCE, MIN_FRONTIER, HYSTERESIS,
             RESELECT, REACH, MIN_SIGHTINGS, POINT_CLEARANCE, VERIFY_RADIUS, LOOK_BACK, MAP, POSE, GOAL_OUT, NEARBY,
             FOOTPRINT)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        strategy = self.get_input(self.STRATEGY)
        self.params = GoalParams(
            eta=self.get_input(self.ETA), k=self.get_input(self.K),
            robot_radius=self.get_input(ROBOT_RADIUS) + self.get_input(CLEARANCE),
            min_frontier=self.get_input(self.MIN_FRONTIER),
            margin=self.get_input(MARGIN), penalty=self.get_input(PENALTY),
            patience=self.get_input(self.PATIENCE), hysteresis=self.get_input(self.HYSTERESIS),
            closest_frontier=strategy == "closest_frontier",
            nearby=self.get_input(self.NEARBY) if strategy == "nearby_attraction" else math.inf,
            min_sightings=self.get_input(self.MIN_SIGHTINGS),
            point_clearance=self.get_input(self.POINT_CLEARANCE),
            verify_radius=self.get_input(self.VERIFY_RADIUS), look_back=self.get_input(self.LOOK_BACK),
        )  # fmt: skip
        self._clear_map: ExplorationMap | None = None  # the last map on which the goal's path was clear
        self._sized = False  # robot_radius 0: the footprint's, known once the tree runs
        self.switch = ModeSwitch()
        self.goal: Goal | None = None
        self.avoid: list[tuple[float, float]] = []  # reached or abandoned: avoided until a second chance
        self.forgiven: list[tuple[float, float]] = []  # had their second chance
        self.given_up: list[tuple[float, float]] = []  # reached or abandoned twice: avoided for good
        self.verified: list[tuple[float, float]] = []  # border points whose blocking cells were looked at again
        self.selected_at = -math.inf
        self.goals: list[list[Any]] = []
        self.mode_switches: list[list[Any]] = []
        self.selections = 0
        self.reached = 0
        self.abandoned = 0
        self._drawn: Goal | None = None  # the goal last drawn
        self._recorded: Goal | None = None  # the goal last recorded in ``goals``

    def initialise(self) -> None:
        self.goal = None  # choose afresh on every entry

    def _size(self) -> None:
        """Plan for the robot's own disc (robot_radius 0), known once the tree runs: on the first tick."""
        if not self._sized:
            self._sized = True
            self.params = replace(self.params, robot_radius=disc_radius(self) + self.get_input(CLEARANCE))

    def update(self) -> Status:
        m = self.get_input(MAP, None)
        pose = self.get_input(POSE, None)
        if m is None or pose is None:
            self.feedback_message = "waiting for the map and a pose"
            return Status.RUNNING
        self._size()
        goal, now = self.goal, self.now()
        reached = goal is not None and math.hypot(pose.x - goal.target[0], pose.y - goal.target[1]) <= self.get_input(
            self.REACH)
        if goal is not None and not reached and self._keep(m, goal, now):
            return Status.RUNNING
        if reached and goal is not None:
            self.reached += 1
            self._spend(goal)
            if goal.mode is Mode.VERIFY:  # at the place to look from: the look-around the FAILURE starts looks
                self._set_goal(None)
                self.feedback_message = "at a place to look again from: look around at it"
                return Status.FAILURE
        before = self.switch
        # one travel-cost search from here serves the selection and its second chance (DONE selects nothing)
        travel = None if self.switch.mode is Mode.DONE else goal_travel(m, (pose.x, pose.y), self.params)
        self._clear_map = m  # the map the goal's path is chosen on: clear
        self._select(m, pose, None if reached else goal, travel)
        if self.goal is None and self.avoid:  # a second chance for the abandoned border points
            self.forgiven += self.avoid
            self.avoid = []
            self.switch = before
            self._select(m, pose, None, travel)
        if self.goal is None and self._verify(m, pose):
            self.switch = before  # looking again is not a strike
            if self.goal is None:
                self.feedback_message = "a border closed where the robot stands: look around at it again"
                return Status.FAILURE
        if self.switch.mode is Mode.DONE:
            self.feedback_message = "done: no border is reachable"
            return Status.SUCCESS
        if self.goal is None:
            strikes = f"{self.switch.strikes} of {self.params.patience}"
            self.feedback_message = f"no reachable border ({strikes}): look around"
            return Status.FAILURE
        g = self.goal
        self.feedback_message = f"{g.mode.value}: to ({g.target[0]:.2f}, {g.target[1]:.2f}), G {g.cost:.2f} m"
        return Status.RUNNING

    def _keep(self, m: ExplorationMap, goal: Goal, now: float) -> bool:
        """Keep the goal (not reached) without choosing again: it is not time to, or its path is
        blocked only by what moved onto free floor since it was last clear (a person crossing it, who
        will walk on; path following waits for them, up to its ``wait``). Its path clear, this map
        becomes the one to compare with."""
        if now - self.selected_at < self.get_input(self.RESELECT):
            return True
        blocking = blocking_cells(m, goal.path, self.params.robot_radius)
        if self._clear_map is None or len(blocking) == 0:
            self._clear_map = m
            return False
        if not moved_onto(self._clear_map, blocking):
            return False
        self.selected_at = now
        self.feedback_message = "something moved onto the goal's path: keeping the goal while it clears"
        return True

    def _spend(self, goal: Goal) -> None:
        """A goal reached or abandoned: its point spent and its border point avoided, or, for a
        VERIFY goal, the place it looked at verified."""
        if goal.mode is Mode.VERIFY and goal.blocked is not None:
            self.verified.append(goal.blocked)
            return
        self.switch = self.switch.spend(goal.point)
        self._avoid(goal.target)

    def _verify(self, m: ExplorationMap, pose: Pose2D) -> bool:
        """No border is reachable: is some border closed only by cells worth looking at again
        (:func:`maps.exploration.goal.verification_goal`)? Its VERIFY goal is set, or, when the robot
        stands at its look-from point already, the place counts as verified and no goal is set: the
        look-around that follows the FAILURE looks at it (a goal reached at once would be spent
        before the cameras turned that way)."""
        goal = verification_goal(m, (pose.x, pose.y), self.params, avoid=self._avoided(),
                                 verified=np.array(self.verified) if self.verified else None)
        if goal is None:
            return False
        if math.hypot(pose.x - goal.target[0], pose.y - goal.target[1]) <= self.get_input(self.REACH):
            self._set_goal(goal)  # recorded (the report's verifications), then looked at from here
            self._spend(goal)
            goal = None
        self._set_goal(goal)
        return True

    def _avoided(self) -> np.ndarray | None:
        """The targets whose border points are no candidates now (K x 2), None without any."""
        targets = self.avoid + self.given_up
        return np.array(targets) if targets else None

    def _avoid(self, target: tuple[float, float]) -> None:
        """Avoid a border point reached or abandoned: until its second chance, or for good after it."""
        again = any(math.dist(target, f) <= self.params.avoid_radius for f in self.forgiven)
        (self.given_up if again else self.avoid).append(target)

    def _select(self, m: ExplorationMap, pose: Pose2D, current: Goal | None, travel: TravelCost | None) -> None:
        before = self.switch.mode
        self.switch, goal = select_goal(self.switch, m, (pose.x, pose.y), self.params, current=current,
                                        avoid=self._avoided(), travel=travel)
        self.selections += 1
        self.selected_at = self.now()
        now = round(self.now(), 2)
        if self.switch.mode is not before:
            self.mode_switches.append([now, before.value, self.switch.mode.value])
        self._set_goal(goal)

    def _set_goal(self, goal: Goal | None) -> None:
        """Make ``goal`` the goal (on the blackboard) and record it when it is a new one."""
        last = self._recorded
        if goal is not None and (last is None or goal.mode is not last.mode or goal.point != last.point
                                 or math.dist(goal.target, last.target) > 0.25):
            self._recorded = goal
            self.goals.append([round(self.now(), 2), goal.mode.value, round(goal.target[0], 3),
                               round(goal.target[1], 3), goal.point, round(goal.distance, 3), round(goal.cost, 3),
                               None if math.isnan(goal.power) else round(goal.power, 3)])
        self.goal = goal
        self.set_output(self.GOAL_OUT, goal)

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID and self.goal is not None:  # halted: the goal could not be followed
            self.abandoned += 1
            self._spend(self.goal)
            self.goal = None
            self.set_output(self.GOAL_OUT, None)

    def figures(self) -> Iterator[Figure]:
        """The ``exploration`` section's goal part: goals, mode switches, how selection ended."""
        yield from (Figure("exploration", name, value) for name, value in (
            ("mode", self.switch.mode.value),
            ("done", self.switch.mode is Mode.DONE),
            ("strategy", self.get_input(self.STRATEGY)),
            ("selections", self.selections),
            ("goals_reached", self.reached),
            ("goals_abandoned", self.abandoned),
            ("verifications", sum(g[1] == Mode.VERIFY.value for g in self.goals)),
            ("goal_count", len(self.goals)),
            ("goals", self.goals),
            ("goal_columns", "t, mode, x, y, point, d, G, A_P"),
            ("mode_switch_count", len(self.mode_switches)),
            ("mode_switches", self.mode_switches),
        ))

    def drawings(self) -> Iterator[Drawing]:
        """The goal: its border point and its path (odometry frame), when it is a new one."""
        goal = self.goal
        if goal is None or self._drawn is goal:
            return
        self._drawn = goal
        colour = (255, 80, 80) if goal.mode is Mode.ATTRACTION else (255, 160, 0)
        yield Points("odometry_frame/exploration/goal", np.array([goal.target]), colour, radius=0.1,
                     labels=(goal.mode.value,))
        if len(goal.path) > 1:
            yield Lines("odometry_frame/exploration/path", [goal.path], colour, radius=0.02)
