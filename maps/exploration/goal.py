"""Where to explore next (algorithm 3): attractive power (eq. 1), frontier mode, done.

The next goal is the detected point ``P_p`` with the highest attractive power

    A_P = d(P_p, P_b) - eta * G(v_S, P_b)            (eq. 1, eta in [0, 0.5])

where ``P_b`` is a border point of the explored area, ``d`` the plan distance from the point's
floor projection to it and ``G`` the travel cost from the robot through known free space
(:func:`maps.exploration.travel.travel_cost`). When no point lies farther than ``K`` beyond the border,
the robot is in *frontier mode* until one does; exploration is *done* when no border is
reachable. The mode switching is the small value :class:`ModeSwitch`, so the behaviour that uses
it only reads the map, calls :func:`select_goal` and writes the goal.

Choices where the paper is vague:

- ``P_b`` for a point is the reachable border point nearest to it (a k-d tree over the reachable
  border cells): d says how far into the unknown the point lies, G what reaching the unknown
  there costs. A point whose floor projection is already explored or an obstacle cell has d = 0.
  Borders that no path reaches do not count for d (they are the ones exploration cannot use).
- The goal to drive to is ``P_b``, not ``P_p``: ``P_p`` may be a wall seen 7 m away, while ``P_b``
  is reachable through known free space by construction; on arrival the cameras see further and
  the next selection moves on.
- Frontier mode: the paper says "closest obstacle". A goal has to be a place the robot can reach
  whose neighbourhood is unexplored, so here it is the reachable border point with the smallest
  travel cost (explore_lite's closest frontier).
- DONE is absorbing (the mission has succeeded); a new :class:`ModeSwitch` starts over. The
  paper ends at the first selection without a reachable border; ``patience`` > 1 waits for that
  many in a row, and in between :func:`select_goal` returns no goal in a mode that is not DONE:
  the behaviour looks around (:func:`maps.exploration.gaze.survey`) and asks again: a second
  look clears the speckle of the stereo matcher in a doorway (see ``EvidenceParams``), though
  not walls smeared by odometry drift.
- A point the robot went for once and reached is ``spent`` (:meth:`ModeSwitch.spend`): it can no
  longer attract, so a point whose surroundings cannot be explored (under a desk, behind glass)
  does not hold the robot forever. Spent points do not count for "a point has d > K" either.
- Selection on a map with no explored free cell raises: mark the robot's footprint first
  (:func:`maps.exploration.grid.mark_traversed`), otherwise the first call would be "done".
- Selection is repeated as the map grows; two nearly equal points would make the robot dither
  between them. With ``hysteresis`` > 0 the ``current`` goal's point is kept while its attractive
  power is within that of the best (in frontier mode: its border point, while its travel cost is
  within that of the closest).
- Border points near ``avoid`` targets (ones the robot reached or gave up on without the unknown
  beyond them becoming seen: under furniture, a jamb too close to the cameras' near edge) are no
  candidates; when only such borders are left, no border is reachable.
- A point seen in fewer than ``min_sightings`` observations has d = 0: a stereo matcher's stray
  matches (in simulated runs: points metres outside the building, or below the floor)
  would otherwise be the most attractive points of all, every one a trip.
- With ``point_clearance`` > 0, a point whose floor projection lies that close to an obstacle cell
  has d = 0: the upper part of a wall (above the obstacle height, so its cells stay unknown behind
  the wall line) is not open space beyond the border, and would otherwise pull the robot to the
  reachable border nearest to it, however far and useless. Points in unknown space away from
  known obstacles (the floor and walls of a room seen through a door, beyond the explore range)
  still attract.
- ``closest_frontier``: frontier mode always: the closest reachable border point (Yamauchi's
  frontier exploration, the evaluation's baseline; explore_lite also weighs a frontier's size).
- ``nearby`` (finite; the mission's default strategy ``nearby_attraction``): eq. 1 chooses only
  among the points whose border point ``P_b`` costs at most ``nearby`` metres more to reach than
  the closest reachable border point; other points do not attract (power -inf), and without one
  beyond K the robot is in frontier mode. Eq. 1 over all points (``nearby`` inf: the paper, the
  strategy ``attraction``) goes after far points first: in the flat of ``rooms`` a point's d
  reached 9-11 m (points behind walls or outside the building, whose nearest *reachable* border is
  rooms away), so A_P = d - eta G chose borders 15-18 m away over one next to the robot, and the
  robot crossed the flat and came back. Closest-frontier order with eq. 1 among near equals keeps
  the sweep and still prefers the border with the most unknown behind it (docs/exploration.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from enum import StrEnum

import numpy as np
from scipy.spatial import cKDTree

from maps.exploration.grid import Cell, ExplorationMap, borders
from maps.exploration.travel import TravelCost, travel_cost, traversable


class Mode(StrEnum):
    """What goal selection is doing."""

    ATTRACTION = "attraction"  # going for the point with the highest attractive power (eq. 1)
    FRONTIER = "frontier"  # no point has d > K: the closest reachable border point
    DONE = "done"  # no border is reachable
    VERIFY = "verify"  # a goal only: look again at the obstacle cells that close a border (see verification_goal)


@dataclass(frozen=True, slots=True)
class GoalParams:
    """Parameters of goal selection."""

    eta: float = 0.25  # weight of the travel cost in eq. 1, in [0, 0.5]
    k: float = 1.0  # m: a point must lie farther than this beyond the border to attract
    robot_radius: float = 0.26  # m: clearance the path keeps from obstacle cells
    min_frontier: float = 0.3  # m: shorter border pieces are ignored
    margin: float = 0.0  # m: steps with less clearance than robot_radius + margin cost more...
    penalty: float = 0.0  # ...up to (1 + penalty) times their length (see maps.exploration.travel.travel_cost)
    patience: int = 1  # selections in a row without a reachable border before DONE (1: the paper)
    hysteresis: float = 0.0  # m: keep the current goal while it is this close to the best (see the docstring)
    avoid_radius: float = 0.4  # m: border points this close to an avoided target are no candidates
    closest_frontier: bool = False  # always the closest reachable border (the baseline), never eq. 1
    min_sightings: int = 1  # points seen in fewer observations do not attract (stray stereo matches)
    point_clearance: float = 0.0  # m: points whose floor projection is this close to an obstacle cell do not attract
    verify_radius: float = 0.0  # m: > 0: before DONE, look again at what closes a border a disc this size reaches
    look_back: float = 1.0  # m: ...from this far before the first cell the robot's own disc cannot pass
    nearby: float = math.inf  # m: only points whose border costs at most this more than the closest one attract

    def __post_init__(self) -> None:
        if not 0.0 <= self.eta <= 0.5:
            raise ValueError(f"eta must be in [0, 0.5] (eq. 1), got {self.eta}")
        if min(self.k, self.robot_radius, self.min_frontier, self.margin, self.penalty, self.hysteresis,
               self.avoid_radius, self.point_clearance, self.verify_radius, self.look_back, self.nearby) < 0.0:
            raise ValueError("k, robot_radius, min_frontier, margin, penalty, hysteresis, avoid_radius, "
                             "point_clearance, verify_radius, look_back and nearby must not be negative")
        if self.patience < 1:
            raise ValueError(f"patience must be at least 1, got {self.patience}")


@dataclass(frozen=True, slots=True)
class ModeSwitch:
    """The mode of goal selection and the points already spent: a pure state machine.

    ATTRACTION <-> FRONTIER on whether some point has d > K; any mode -> DONE when no border has
    been reachable ``patience`` times in a row (``strikes`` counts them; the mode stays as it
    was meanwhile); DONE stays.
    """

    mode: Mode = Mode.ATTRACTION
    spent: frozenset[int] = field(default_factory=frozenset)
    strikes: int = 0

    def next(self, *, point_beyond_k: bool, border_reachable: bool, patience: int = 1) -> ModeSwitch:
        """The mode after seeing the current evidence."""
        if self.mode is Mode.DONE:
            return self
        if not border_reachable:
            strikes = self.strikes + 1
            return replace(self, mode=Mode.DONE if strikes >= patience else self.mode, strikes=strikes)
        return replace(self, mode=Mode.ATTRACTION if point_beyond_k else Mode.FRONTIER, strikes=0)

    def spend(self, point: int | None) -> ModeSwitch:
        """This switch with ``point`` (an index into the map's points) no longer attracting."""
        return self if point is None else replace(self, spent=self.spent | {int(point)})


@dataclass(frozen=True, slots=True)
class Goal:
    """A goal: drive along ``path`` to ``target`` (the border point P_b).

    ``point`` is the index of P_p in the map's points (None in frontier mode); ``distance`` is
    d(P_p, P_b) (0 in frontier mode), ``cost`` G(v_S, P_b) and ``power`` A_P (NaN in frontier mode).
    A VERIFY goal's ``target`` is where to look from and ``blocked`` the border point it is for.
    """

    mode: Mode
    target: tuple[float, float]
    point: int | None
    distance: float
    cost: float
    power: float
    path: np.ndarray
    blocked: tuple[float, float] | None = None


@dataclass(frozen=True, slots=True)
class Candidates:
    """Everything one selection looked at (for the rerun view and for tests).

    ``border`` (B x 2) reachable border points and their travel cost ``border_cost`` (B,);
    per map point: ``distance`` d to its nearest reachable border point ``nearest`` (index into
    ``border``, -1 without any) and the attractive power ``power`` (eq. 1; -inf without a border, and
    for points whose border point is not ``nearby``).
    """

    border: np.ndarray
    border_cost: np.ndarray
    distance: np.ndarray
    nearest: np.ndarray
    power: np.ndarray
    travel: TravelCost


def attractive_power(distance: np.ndarray, cost: np.ndarray, eta: float) -> np.ndarray:
    """A_P = d(P_p, P_b) - eta * G(v_S, P_b) (eq. 1)."""
    return np.asarray(distance, dtype=np.float64) - eta * np.asarray(cost, dtype=np.float64)  # eq. 1


def goal_travel(m: ExplorationMap, robot: tuple[float, float], params: GoalParams = GoalParams()) -> TravelCost:
    """G(v_S, .) from ``robot`` as goal selection sees it (the disc of ``robot_radius``, ``margin``,
    ``penalty``): one search serves every selection from that place on that map."""
    return travel_cost(m, robot, params.robot_radius, margin=params.margin, penalty=params.penalty)


def candidates(
    m: ExplorationMap,
    robot: tuple[float, float],
    params: GoalParams = GoalParams(),
    avoid: np.ndarray | None = None,
    *,
    travel: TravelCost | None = None,
) -> Candidates:
    """Reachable border points (none within ``avoid_radius`` of an ``avoid`` point, K x 2), and d, P_b
    and A_P (eq. 1) of every map point, seen from ``robot``. ``travel``: :func:`goal_travel` of the
    same map, place and parameters, when the caller has it already."""
    if travel is None:
        travel = goal_travel(m, robot, params)
    min_cells = max(1, int(math.ceil(params.min_frontier / m.frame.resolution)))
    rows, cols = np.nonzero(borders(m, min_cells) & np.isfinite(travel.cost))
    border = m.frame.centre_of(rows, cols)
    if avoid is not None and len(avoid) and len(border):
        keep = cKDTree(np.asarray(avoid, dtype=np.float64).reshape(-1, 2)).query(border)[0] > params.avoid_radius
        rows, cols, border = rows[keep], cols[keep], border[keep]
    border_cost = travel.cost[rows, cols]
    n = len(m.points)
    if len(border) == 0:
        return Candidates(border, border_cost, np.full(n, np.inf), np.full(n, -1), np.full(n, -np.inf), travel)
    distance, nearest = cKDTree(border).query(m.points[:, :2]) if n else (np.zeros(0), np.zeros(0, dtype=np.int64))
    eligible = (m.cell_state(m.points[:, :2]) == Cell.UNKNOWN) & (m.sightings >= params.min_sightings)
    if params.point_clearance > 0.0 and n:
        eligible &= m.frame.sample(m.clearance, m.points[:, :2], np.inf) > params.point_clearance
    distance = np.where(eligible, distance, 0.0)
    power = attractive_power(distance, border_cost[nearest], params.eta)
    if math.isfinite(params.nearby):  # eq. 1 among the border points about as close as the closest
        power = np.where(border_cost[nearest] <= border_cost.min() + params.nearby, power, -np.inf)
    return Candidates(border, border_cost, distance, np.asarray(nearest, dtype=np.int64), power, travel)


def select_goal(
    switch: ModeSwitch,
    m: ExplorationMap,
    robot: tuple[float, float],
    params: GoalParams = GoalParams(),
    *,
    current: Goal | None = None,
    avoid: np.ndarray | None = None,
    travel: TravelCost | None = None,
) -> tuple[ModeSwitch, Goal | None]:
    """The next mode and goal for a robot at ``robot`` (odometry x, y).

    ``current``: the goal being driven to (kept within ``hysteresis``); ``avoid``: targets (K x 2)
    whose border points are no candidates; ``travel``: :func:`goal_travel` of this map and place,
    when the caller has it (a second selection from the same place). No goal: DONE, or (with
    ``patience`` > 1) no border reachable yet again: look around, retry.
    """
    if not np.any(m.cells == Cell.FREE):
        raise ValueError("the exploration map has no explored free cell: mark the robot's footprint first")
    if switch.mode is Mode.DONE:
        return switch, None
    found = candidates(m, robot, params, avoid, travel=travel)
    eligible = (found.distance > params.k) & np.isfinite(found.power)
    if switch.spent:
        eligible[np.fromiter(switch.spent, dtype=np.int64)] = False
    if params.closest_frontier:
        eligible[:] = False
    reachable = len(found.border) > 0
    switch = switch.next(point_beyond_k=bool(eligible.any()), border_reachable=reachable, patience=params.patience)
    if switch.mode is Mode.DONE or not reachable:
        return switch, None
    if switch.mode is Mode.ATTRACTION:
        point = _best_point(found, eligible, current, params.hysteresis)
        b = int(found.nearest[point])
        distance, power = float(found.distance[point]), float(found.power[point])
    else:
        point, b = None, _closest_border(found, current, params.hysteresis, m.frame.resolution)
        distance, power = 0.0, math.nan
    target = (float(found.border[b, 0]), float(found.border[b, 1]))
    goal = Goal(switch.mode, target, point, distance, float(found.border_cost[b]), power, found.travel.path_to(target))
    return switch, goal


def _best_point(found: Candidates, eligible: np.ndarray, current: Goal | None, hysteresis: float) -> int:
    """The eligible point of the highest attractive power, or the current goal's within ``hysteresis``."""
    best = int(np.argmax(np.where(eligible, found.power, -np.inf)))
    keep = current.point if current is not None and current.mode is Mode.ATTRACTION else None
    if keep is not None and keep < len(eligible) and eligible[keep]:
        return int(keep) if found.power[keep] >= found.power[best] - hysteresis else best
    return best


def _closest_border(found: Candidates, current: Goal | None, hysteresis: float, resolution: float) -> int:
    """The reachable border point of the least travel cost, or the current frontier target within ``hysteresis``."""
    best = int(np.argmin(found.border_cost))
    if current is None or current.mode is not Mode.FRONTIER or hysteresis <= 0.0:
        return best
    gap = np.hypot(*(found.border - np.asarray(current.target)).T)
    near = int(np.argmin(gap))
    if gap[near] <= 1.5 * resolution and found.border_cost[near] <= found.border_cost[best] + hysteresis:
        return near
    return best


def verification_goal(
    m: ExplorationMap,
    robot: tuple[float, float],
    params: GoalParams,
    *,
    avoid: np.ndarray | None = None,
    verified: np.ndarray | None = None,
) -> Goal | None:
    """Where to look from, before giving up, at the obstacle cells that close a border.

    For when no border is reachable: among the border points that a disc of ``verify_radius``
    reaches (none within ``avoid_radius`` of ``avoid``) and that are the nearest such border point
    of some detected point in unknown space lying more than ``k`` beyond, seen ``min_sightings``
    times (something seen through the gap), the closest whose narrow path is closed for the robot's own disc at a
    place (``blocked``: the first cell of the path it cannot pass) not within ``look_back`` of one
    already ``verified`` (one look covers that much). The goal is the cell of that path
    ``look_back`` metres before the place (or the last passable one, nearer). Driving there faces
    the cells that closed the way; if they were stereo speckle or smear they clear (the evidence is
    log-odds) and the border becomes reachable; if they stay, the caller adds ``blocked`` to
    ``verified``. None: nothing to verify.
    When no narrow path does (a clump with no gap at all), the same is asked of the path from the
    robot that crosses the least of what closes the way (known cells its disc cannot pass cost
    ``CROSSING_COST`` times their length; :func:`maps.exploration.travel.travel_cost`), those within
    ``look_back`` of a place already verified left closed, so that a wall looked at once sends the
    next try to the next crossing. The goal is again ``look_back`` before the first cell the robot's
    disc cannot pass on it: the nearest place it reaches from which to look at what closes the way.
    A choice of ours (the paper ends at the first selection without a reachable border): in
    simulated runs of a flat with doors, a few cells of smear just inside a doorway, never seen
    again, ended exploration with a room unvisited; in the office, people mapped where they stood
    closed the corridor with no gap for any disc.
    """
    if params.verify_radius <= 0.0 or params.verify_radius >= params.robot_radius:
        return None
    # points near obstacle cells count here (point_clearance 0): the walls of a room seen through a
    # door are what says a room is there; an ineligible point has d = 0 and never passes d > k
    narrow = candidates(m, robot, replace(params, robot_radius=params.verify_radius, point_clearance=0.0), avoid)
    passable = traversable(m, params.robot_radius)
    done = np.zeros((0, 2)) if verified is None else np.asarray(verified, dtype=np.float64).reshape(-1, 2)
    goal = _look_again(m, narrow, passable, done, params)
    if goal is not None:
        return goal
    # no narrow path: the path that crosses the least of what closes the way (a person's blob across
    # a corridor, seen standing there, leaves no gap at all); what was looked at already stays closed
    closed = np.zeros(m.frame.shape, dtype=bool)
    if len(done):
        rows, cols = np.nonzero(~passable & (m.cells != Cell.UNKNOWN))
        near = cKDTree(done).query(m.frame.centre_of(rows, cols))[0] <= params.look_back
        closed[rows[near], cols[near]] = True
    travel = travel_cost(m, robot, params.robot_radius, crossing=CROSSING_COST, closed=closed)
    across = candidates(m, robot, replace(params, point_clearance=0.0), avoid, travel=travel)
    return _look_again(m, across, passable, done, params)


def _look_again(
    m: ExplorationMap, found: Candidates, passable: np.ndarray, done: np.ndarray, params: GoalParams
) -> Goal | None:
    """The VERIFY goal for the closest promising border point of ``found`` whose path is closed for
    the robot's disc (``passable``) at a place not within ``look_back`` of one ``done``; None: none."""
    promising = np.zeros(len(found.border), dtype=bool)  # the nearest border point of a point more than k beyond
    if len(found.border):
        promising[found.nearest[found.distance > params.k]] = True
    order = np.flatnonzero(promising)[np.argsort(found.border_cost[promising], kind="stable")][:MAX_VERIFY_TRIES]
    for b in order:
        path = found.travel.path_to((float(found.border[b, 0]), float(found.border[b, 1])))
        rows, cols = m.frame.cell_of(path)
        ok = passable[rows, cols]
        if ok.all() or not ok[0]:  # nothing closes it, or the robot stands where its disc does not fit
            continue
        first = int(np.argmin(ok))  # the first cell the robot's disc cannot pass
        blocked = (float(path[first, 0]), float(path[first, 1]))
        if len(done) and np.hypot(*(done - np.asarray(blocked)).T).min() <= params.look_back:
            continue
        arc = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))))
        before = np.flatnonzero(arc[:first] <= arc[first] - params.look_back)
        stop = int(before[-1]) if len(before) else first - 1
        target = (float(path[stop, 0]), float(path[stop, 1]))
        return Goal(Mode.VERIFY, target, None, 0.0, float(arc[stop]), math.nan, path[: stop + 1], blocked)
    return None


MAX_VERIFY_TRIES = 200  # border points tried per verification (closest first)
CROSSING_COST = 10.0  # a metre through what closes the way counts as this many of open floor (verification)
