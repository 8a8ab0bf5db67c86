"""People in the evaluations' worlds: ``--option people=N`` of every ``bearings eval`` area.

N people are drawn from the seed alone and added to a copy of the world file the area's episodes
run in (:func:`world_with_people`); nothing else changes, so the same seed gives the same people
and ``people=0`` (the default) leaves the episodes exactly as they were. Each person is, with
even odds:

- **standing** on the way the robot is to go, leaving it a way past (:meth:`_Placer.leaves_a_way`:
  the robot's disc grown by the avoidance's clearance gets from the way 1.5 m before them to the
  way 1.5 m after them, clear of every surface and every other person standing; a person in the
  middle of a hallway too narrow for that would test only that the robot stops); in the rooms
  (``exploration``), standing where they cut none of the floor off (:meth:`_Placer.keeps_floor`: a
  person standing in the only door to two rooms makes them unreachable, and the coverage asked
  for impossible), or
- **crossing** it: walking back and forth across it, square to it, up to :data:`CROSSING` m to
  each side (cut where a wall, box or pillar comes nearer than the person's radius), at a speed
  in :data:`SPEEDS`, resting at each end up to ``--option rest=S`` seconds (:data:`WAIT_S`, 2 s, by
  default: people who pace a corridor with hardly a rest are a wall the robot must time its way
  through, and a longer rest changes only how long each person rests: docs/obstacles-measured.md, stop 43).
  A crossing goes a body's width to each side of the way; a person who finds no place so (a route
  along a corridor 1.5 m wide, 0.5 m on each side of its middle: before, such a route got nobody
  at all) may cross shorter, half a body's width to each side, when, paused at either end, they
  leave the robot a way past as a standing person must.

Where "the way" is depends on the area: the taught route (``ltmap``), the straight lines between
the targets (``roadmap``), or anywhere in the rooms (``exploration``: :func:`in_rooms`, a walker
going to another free point in sight instead of crossing). People keep :data:`KEEP_CLEAR_M` from
the places given to keep clear (where runs start and end), stand where a person fits (their
radius from every surface) and apart from each other; a world with no such room for N people
gets fewer (the count is in the figures: ``people.placed``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from scipy import ndimage

from behaviours.avoidance import AvoidObstacles
from drivers.sim.floor import FloorGrid, rasterise, reached_from
from drivers.sim.scene import Scene
from drivers.sim.world import World, shipped_worlds
from experiments.eval import bounded_option, count_option

MAX_PEOPLE = 20
OPTION = "people"
HELP = (f"N people (0 to {MAX_PEOPLE}, default 0) drawn from the seed, standing on or walking across the way the "
        "robot goes, added to the world the episodes run in")
RADIUS = 0.25  # m: the world file's default person
KEEP_CLEAR_M = 1.0  # m from where runs start and end
SPACING = 2 * RADIUS + 0.2  # m between two people's centres
CROSSING = (1.0, 2.0)  # m to each side of the way a crossing person walks
SPEEDS = (0.5, 1.2)  # m/s
WAIT_S = 2.0  # s: the most a walking person rests at each end of their walk, by default (the 'rest' option)
REST_OPTION = "rest"
MAX_REST = 60.0  # s
REST_HELP = (f"s: the most a walking person rests at each end of their walk (0 to {MAX_REST:g}, default {WAIT_S:g}); "
             "each person's rest is drawn up to it, the people, their ways and speeds stay those of the seed")
WALK = (1.5, 4.0)  # m: how far a walker in a room goes
DRAWS = 500  # positions tried per person
STEP = 0.05  # m: how finely a walk is checked against the surfaces
PASSING = AvoidObstacles.CLEARANCE.default  # m the robot keeps passing a standing person
PAST = 1.5  # m along the way before and after a standing person that the robot must get between
NEAR_END = 0.2  # m: the way's point, or a place this near it, starts and ends the way past
GRID = 0.05  # m: the cells the way past is looked for in


def parse_people(text: str | None) -> int:
    """The ``people`` option: 0 to :data:`MAX_PEOPLE` (default 0); ``ValueError`` otherwise."""
    return count_option("people", text, default=0, maximum=MAX_PEOPLE)


def parse_rest(text: str | None) -> float:
    """The ``rest`` option: 0 to :data:`MAX_REST` seconds (default :data:`WAIT_S`); ``ValueError`` otherwise."""
    return bounded_option(REST_OPTION, text, convert=float, default=WAIT_S, maximum=MAX_REST,
                          expected="a number of seconds", unit=" s")


@dataclass(frozen=True)
class Crowd:
    """The people an evaluation adds, as its options ask: how many per seed (``people``; 0: none,
    the episodes as they were) and the most a walking one rests at each end (``rest``)."""

    count: int = 0
    rest: float = WAIT_S

    @classmethod
    def from_options(cls, extra: Mapping[str, str]) -> Crowd:
        """The ``people`` and ``rest`` options, checked; ``ValueError`` with the problem."""
        return cls(parse_people(extra.get(OPTION)), parse_rest(extra.get(REST_OPTION)))

    def __bool__(self) -> bool:
        return self.count > 0

    def on_ways(self, world: World, ways: Sequence[np.ndarray], seed: int, *,
                keep_clear: Sequence[Sequence[float]]) -> list[Walker]:
        """:func:`on_ways` with this crowd's count and rest."""
        return on_ways(world, ways, self.count, seed, keep_clear=keep_clear, rest=self.rest)

    def in_rooms(self, world: World, grid: FloorGrid, seed: int, *,
                 keep_clear: Sequence[Sequence[float]]) -> list[Walker]:
        """:func:`in_rooms` with this crowd's count and rest."""
        return in_rooms(world, grid, self.count, seed, keep_clear=keep_clear, rest=self.rest)

    def figures(self, people: dict[int, list[Walker]]) -> dict[str, Any]:
        """What the evaluation records of the people placed for this crowd: how many were asked for,
        their longest rest, placed per seed, and where (none when it asked for none)."""
        if not self:
            return {}
        return {"people": self.count, "people.rest": self.rest,
                "people.placed": {str(seed): len(walkers) for seed, walkers in sorted(people.items())},
                "people.paths": {str(seed): [w.entry() for w in walkers] for seed, walkers in sorted(people.items())}}


@dataclass(frozen=True)
class Walker:
    """One person for a world file: where they walk (one point: standing), speed, wait."""

    path: tuple[tuple[float, float], ...]
    speed: float = 1.0
    wait_s: float = 0.0

    def entry(self) -> dict[str, Any]:
        """The person as a world file's ``people:`` entry."""
        out: dict[str, Any] = {"path": [[round(x, 3), round(y, 3)] for x, y in self.path]}
        if len(self.path) > 1:
            out.update(speed=round(self.speed, 3), wait_s=round(self.wait_s, 2))
        return out


class _Placer:
    """What every placement checks: room for a person, apart from the others, clear of given places."""

    def __init__(self, world: World, keep_clear: Sequence[Sequence[float]]) -> None:
        self.world = world
        self.scene = Scene(world)
        self.keep_clear = np.asarray(keep_clear, dtype=np.float64).reshape(-1, 2)
        self.placed: list[Walker] = []
        self.passer = world.robot_radius + PASSING  # the robot's disc grown by the clearance it keeps
        self.standing: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # on a way: (where, before, after)
        self._reached: np.ndarray | None = None  # keeps_floor: the floor reached with nobody standing

    def leaves_a_way(self, p: np.ndarray, before: np.ndarray, after: np.ndarray, extra: Walker | None = None
                     ) -> bool:
        """Whether the robot gets past a person standing at ``p``: from ``before`` to ``after`` (the way
        :data:`PAST` m either side of them) its disc, grown by the clearance it keeps, finds a way
        within a few metres, clear of every surface and of everybody standing (``extra`` too, when
        about to be placed). Walkers move on and are not counted."""
        standing = [np.asarray(w.path[0]) for w in (*self.placed, *([extra] if extra else ())) if len(w.path) == 1]
        corners = np.array([p, before, after])
        x0, y0 = corners.min(axis=0) - (PAST + self.passer)
        x1, y1 = corners.max(axis=0) + (PAST + self.passer)
        shape = (int(math.ceil((y1 - y0) / GRID)), int(math.ceil((x1 - x0) / GRID)))
        free = ~rasterise(self.world, x0, y0, GRID, shape)
        rows, cols = np.mgrid[0 : shape[0], 0 : shape[1]]
        centres = np.stack(((cols + 0.5) * GRID + x0, (rows + 0.5) * GRID + y0), axis=-1)
        for q in (p, *standing):
            free &= np.hypot(*(centres - q).transpose(2, 0, 1)) > RADIUS
        room = ndimage.distance_transform_edt(free, sampling=GRID) > self.passer
        labels, _ = ndimage.label(room)
        ends = []
        for end in (before, after):  # the component nearest the way's point (the robot drove there)
            near = labels * (np.hypot(*(centres - end).transpose(2, 0, 1)) <= NEAR_END)
            found = np.unique(near[near > 0])
            ends.append(set(found.tolist()))
        return bool(ends[0] & ends[1])

    def keeps_floor(self, grid: FloorGrid, p: np.ndarray) -> bool:
        """Whether a person standing at ``p``, with everybody standing already, leaves the robot's
        disc, grown by the clearance it keeps, all the floor of ``grid`` it reached without them, but
        for the floor round them: nobody standing cuts a room off."""
        rows, cols = np.indices(grid.free.shape)
        centres = np.stack(((cols + 0.5) * grid.resolution + grid.x0, (rows + 0.5) * grid.resolution + grid.y0), -1)
        standing = [np.asarray(w.path[0]) for w in self.placed if len(w.path) == 1]
        near = np.min([np.hypot(*(centres - q).transpose(2, 0, 1)) for q in (*standing, p)], axis=0)
        if self._reached is None:
            self._reached = self._reach(grid, ~grid.free)
        lost = self._reached & ~self._reach(grid, ~grid.free | (near <= RADIUS))
        return not np.any(lost & (near > RADIUS + self.passer + 2 * grid.resolution))

    def _reach(self, grid: FloorGrid, occupied: np.ndarray) -> np.ndarray:
        """Where the grown disc's centre goes from the world's start, ``occupied`` in the way."""
        rows, cols, _ = grid.cells_of(np.array([[self.world.start.x, self.world.start.y]]))
        return reached_from(occupied, grid.resolution, self.passer, (int(rows[0]), int(cols[0])))

    def keeps_ways(self, walker: Walker) -> bool:
        """Whether everybody standing on a way still leaves the robot a way past with ``walker`` placed."""
        return len(walker.path) > 1 or all(self.leaves_a_way(p, b, c, walker) for p, b, c in self.standing)

    def fits(self, a: np.ndarray, b: np.ndarray | None = None) -> bool:
        """Whether a person standing at ``a`` (or walking from ``a`` to ``b``) fits: their radius
        from every surface all along, :data:`KEEP_CLEAR_M` from the places to keep clear and
        :data:`SPACING` from everybody placed."""
        b = a if b is None else b
        if not self.apart(a, b):
            return False
        steps = max(1, math.ceil(float(np.hypot(*(b - a))) / STEP))
        return all(self.scene.clearance(*(a + (b - a) * (k / steps))) >= RADIUS for k in range(steps + 1))

    def apart(self, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether the segment a-b keeps clear of the places to keep clear and of everybody placed."""
        if len(self.keep_clear) and _distances(self.keep_clear, a, b).min() < KEEP_CLEAR_M:
            return False
        others = np.array([p for w in self.placed for p in w.path]).reshape(-1, 2)
        return not (len(others) and _distances(others, a, b).min() < SPACING)

    def reach(self, p: np.ndarray, direction: np.ndarray, most: float) -> float:
        """How far (up to ``most``) a person can walk from ``p`` along ``direction`` before a surface."""
        along = 0.0
        while along + STEP <= most and self.scene.clearance(*(p + direction * (along + STEP))) >= RADIUS:
            along += STEP
        return along


def _distances(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of each point to the segment a-b."""
    ab = b - a
    t = np.clip(((points - a) @ ab) / max(float(ab @ ab), 1e-12), 0.0, 1.0)
    return np.hypot(*(points - (a + t[:, None] * ab)).T)


def on_ways(world: World, ways: Sequence[np.ndarray], count: int, seed: int, *,
            keep_clear: Sequence[Sequence[float]], rest: float = WAIT_S) -> list[Walker]:
    """``count`` people standing on or crossing the polylines ``ways`` (world, N x 2 each), drawn
    from ``seed``: a point uniform along all the ways together, then standing or crossing (resting
    up to ``rest`` s at each end)."""
    rng = np.random.default_rng([seed, count, 0x9E09])
    placer = _Placer(world, keep_clear)
    arcs = [np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(way, axis=0).T)))) for way in ways]  # arc lengths
    segments = [(way[i], way[i + 1], w, i) for w, way in enumerate(ways) for i in range(len(way) - 1)
                if arcs[w][i + 1] > arcs[w][i]]  # (start, end, which way, which of its segments)
    if not segments:
        return []
    lengths = np.array([arcs[w][i + 1] - arcs[w][i] for _, _, w, i in segments])
    for person in range(count):
        # short crossings only for a person no other place was found for (and from a stream of their
        # own): where the ways leave room, the people are those drawn before short crossings existed
        for draws, short in ((rng, False), (np.random.default_rng([seed, count, 0x9E0B, person]), True)):
            if _place_on_ways(placer, ways, arcs, segments, lengths, draws, short=short, rest=rest):
                break
    return placer.placed


def _place_on_ways(placer: _Placer, ways: Sequence[np.ndarray], arcs: list[np.ndarray],
                   segments: list[tuple[np.ndarray, np.ndarray, int, int]], lengths: np.ndarray,
                   rng: np.random.Generator, *, short: bool, rest: float) -> bool:
    """One person on or across the ways in up to :data:`DRAWS` draws from ``rng``; whether placed."""
    for _ in range(DRAWS):
        k = int(rng.choice(len(segments), p=lengths / lengths.sum()))
        a, b, w, i = segments[k]
        u = rng.uniform()
        p = a + (b - a) * u
        around = _on_way(ways[w], arcs[w], arcs[w][i] + u * lengths[k], (-PAST, PAST))
        walker = _standing_or_crossing(placer, p, (b - a) / lengths[k], around, rng, short=short, rest=rest)
        if walker is not None and placer.keeps_ways(walker):
            placer.placed.append(walker)
            if len(walker.path) == 1:
                placer.standing.append((p, *around))
            return True
    return False


def _on_way(way: np.ndarray, arc: np.ndarray, s: float, offsets: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """The points of the polyline ``way`` (``arc``: the arc length at each of its points) at arc
    lengths ``s`` plus each of the two ``offsets`` (clipped to its ends)."""
    at = np.clip(s + np.asarray(offsets, dtype=float), 0.0, arc[-1])
    points = np.column_stack((np.interp(at, arc, way[:, 0]), np.interp(at, arc, way[:, 1])))
    return points[0], points[1]


def _standing_or_crossing(placer: _Placer, p: np.ndarray, along: np.ndarray,
                          around: tuple[np.ndarray, np.ndarray], rng: np.random.Generator, *,
                          short: bool = False, rest: float = WAIT_S) -> Walker | None:
    if rng.uniform() < 0.5:
        return Walker(((float(p[0]), float(p[1])),)) if placer.fits(p) and placer.leaves_a_way(p, *around) else None
    if not placer.apart(p, p):  # the crossing passes through p
        return None
    normal = np.array([-along[1], along[0]])
    left = placer.reach(p, normal, rng.uniform(*CROSSING))
    right = placer.reach(p, -normal, rng.uniform(*CROSSING))
    a, b = p - right * normal, p + left * normal
    least = RADIUS if short else 2 * RADIUS  # off the way by a body's width (short: half) on both sides
    if min(left, right) < least or not placer.fits(a, b):
        return None
    if min(left, right) < 2 * RADIUS and not all(placer.leaves_a_way(end, *around) for end in (a, b)):
        return None  # a short crossing (a corridor's width): paused at either end, they leave a way past
    first, last = (a, b) if rng.uniform() < 0.5 else (b, a)
    return Walker(((float(first[0]), float(first[1])), (float(last[0]), float(last[1]))),
                  float(rng.uniform(*SPEEDS)), float(rng.uniform(0.0, rest)))


def in_rooms(world: World, grid: FloorGrid, count: int, seed: int, *,
             keep_clear: Sequence[Sequence[float]], rest: float = WAIT_S) -> list[Walker]:
    """``count`` people on the floor the robot reaches (``grid``), drawn from ``seed``: standing, or
    walking back and forth to another reachable point :data:`WALK` m away in a straight free line."""
    rng = np.random.default_rng([seed, count, 0x9E0A])
    placer = _Placer(world, keep_clear)
    xmin, ymin, xmax, ymax = world.bounds()
    for _ in range(count):
        for _ in range(DRAWS):
            p = np.array([rng.uniform(xmin, xmax), rng.uniform(ymin, ymax)])
            if not grid.reachable_at(p[None, :])[0]:
                continue
            if rng.uniform() < 0.5:
                walker = Walker(((float(p[0]), float(p[1])),)) if placer.fits(p) and placer.keeps_floor(grid, p) \
                    else None
            else:
                heading = rng.uniform(-math.pi, math.pi)
                q = p + rng.uniform(*WALK) * np.array([math.cos(heading), math.sin(heading)])
                on_floor = bool(grid.reachable_at(q[None, :])[0])
                walker = Walker(((float(p[0]), float(p[1])), (float(q[0]), float(q[1]))), float(rng.uniform(*SPEEDS)),
                                float(rng.uniform(0.0, rest))) if on_floor and placer.fits(p, q) else None
            if walker is not None:
                placer.placed.append(walker)
                break
    return placer.placed


def world_with_people(world: str | Path, out: Path, people: Sequence[Walker]) -> Path:
    """A copy of ``world`` (a shipped world's name or a world file) at ``out`` with ``people`` added
    to its own."""
    shipped = shipped_worlds()
    source = Path(shipped[str(world)]) if str(world) in shipped else Path(world)
    data = yaml.safe_load(source.read_text())
    data["people"] = [*data.get("people", []), *(w.entry() for w in people)]
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(yaml.safe_dump(data, sort_keys=False))
    return out


def table_line(figures: Mapping[str, Any]) -> list[str]:
    """The people's line of an area's readable table (none without people)."""
    if not figures.get(OPTION):
        return []
    placed = ", ".join(f"seed {seed}: {n}" for seed, n in figures.get("people.placed", {}).items())
    rest = figures.get("people.rest", WAIT_S)
    resting = f", resting up to {rest:g} s at each end" if rest != WAIT_S else ""
    return [f"people: {figures[OPTION]} asked per seed, standing on or walking across the way{resting} "
            f"({placed} placed)"]
