"""``bearings eval roadmap``: learn a roadmap from a few target images, then navigate to its targets
from unknown start poses (docs/design.md's method 2, ``docs/roadmap.md``).

Episodes (all through the sweep runner, in the results folder), per seed:

0. **The learning's room**: the method learns the targets of the room it starts in and navigates
   in it (docs/roadmap.md), so the targets and starts it is evaluated on are drawn there:
   :func:`~experiments.eval.roadmap_world.learning_room`, the reachable floor in sight of where the
   learning starts, cut at the doors (the whole floor of a one-room world such as the lab);
   placed targets 0.45 m or more from its exits, never in a doorway.
1. **Target images**: one front-camera image per target, made with ``bearings sim snapshot`` at the
   target poses (lighting of the seed) into ``seeds/<world>_s<seed>/targets/``. The targets are
   either the world's **named poses** where the robot can stand (by default those in the
   learning's room; ``--option targets=a,b,c`` chooses any the robot can reach from the start;
   at least 2), or ``t1``..``tN`` **placed** in the learning's room (``--option targets=N``, 2 to
   12; the default, 4 of them (fewer when the room has no space for 4 for every seed, down to 2), when the room
   holds fewer than 2 usable named poses): drawn from
   the seed by :func:`~experiments.eval.roadmap_world.place_targets` (reachable, 0.7 m clear when
   there is room, else 0.45 m, 1.5 m apart, the front camera facing at least two surfaces 1-5 m
   away on every ray across its view, preferring an axis 2-4 m long and the view with the most
   reachable floor in it: one the search can find). Placed
   targets are added to a copy of the world file, ``seeds/<world>_s<seed>/<world>.yaml``, and that
   seed's snapshots, learn and goto episodes all run in the copy (self-contained, resumable).
2. **Learn**: ``learn_targets`` from the world's start with that folder; it writes the roadmap to
   ``seeds/<world>_s<seed>/<world>.roadmap``. A start where the room estimation's dodecagon would
   touch a surface (a hallway) is moved to the nearest reachable pose where it fits
   (:func:`~experiments.eval.roadmap_world.learn_start`; the run's ``--start``).
3. **Goto**: ``goto_target`` from ``--option starts=N`` random start poses in the learning's room
   (default 5; :func:`~experiments.eval.roadmap_world.random_starts`: uniform, at least 0.45 m
   clear of every surface, any heading, drawn from the seed alone), each to a goal
   drawn (from the seed) among the targets the learning found, with the roadmap it wrote. They
   run when the learning left a roadmap file (a graph that is not connected included: its
   navigations are measured too), all seeds' together.

Figures (simulator ground truth, evaluation only):

- where the targets came from, ``targets.source`` (``"named poses"`` or ``"placed"``), and where
  they are, ``targets.poses`` (per seed, ``[x m, y m, theta deg]`` in the world frame); those a wall
  hides from where the learning starts, ``targets.out_of_sight`` (per seed: the method learns the
  room it starts in, :func:`~experiments.eval.roadmap_world.out_of_sight`);
- per target found: its estimated pose (the report's ``roadmap.targets``, reference frame) against
  its true pose expressed in the TRUE reference frame, the robot's true pose at the report's
  ``roadmap.room.reference_stamp`` (:class:`~experiments.eval.trajectory.TrueTrajectory`: exact,
  the robot stands still when it takes an image); position (m) and heading (deg) errors; within
  the issue's thresholds when <= 0.15 m and <= 5 deg;
- per learn: targets found, whether the graph is connected, its edges, sim and wall time; it
  **succeeded** when the mission did, without a collision;
- per goto: the report's true final pose against the goal's true pose; **reached** when the
  mission succeeded without a collision and ended within 0.15 m and 5 deg of it;
- per run: ``collisions`` (ground truth), ``safety_stops`` (the collision monitor's),
  ``min_clearance_m`` (ground truth, when the simulator reports it), summed (the smallest
  clearance) over the learns and over the gotos.

People (``--option people=N``, :mod:`experiments.eval.people`): N people drawn from the seed,
standing on or walking across the straight lines between the seed's targets, none within 1 m of a
target, the start or a navigation's start, are added to a copy of the seed's world file
(``seeds/<world>_s<seed>/people/<world>.yaml``) that the seed's navigations run in; the target
images and the learning see the world as it is. The figures record the people placed
(``people.placed``, ``people.paths``).

An episode that fails, crashes or times out is a run with its status and reason (``failures``);
a learn without a report found nothing and has no navigations. Roadmap files are written by the
learn episodes and read by the goto episodes: on a Dask cluster the results folder must be shared.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from drivers.sim.floor import FloorGrid
from drivers.sim.world import World, load_world
from experiments.eval import EvalOptions, count_option
from experiments.eval import people as crowd
from experiments.eval.figures import cell, interval_cell, mean_present, safety_cells, safety_figures, safety_totals
from experiments.eval.roadmap_world import (
    away_from_exits,
    learn_start,
    learning_room,
    out_of_sight,
    place_targets,
    pose_error,
    random_starts,
    reachable_grid,
    target_errors,
    usable_poses,
    world_path,
    world_with,
    write_target_images,
)
from experiments.eval.trajectory import TrueTrajectory
from experiments.sweep import Episode, run_sweep
from experiments.sweep.episode import SweepInputError, absolute_if_file, start_argument
from experiments.sweep.table import read_report
from perception.geometry import Pose2D

DEFAULT_STARTS, MAX_STARTS = 5, 1000
DESCRIPTION = "learn a roadmap from target images, navigate to them: target pose errors, graph, goto reached"
OPTIONS = {
    "targets": "the named poses of the world to take target images at, a,b,c (at least 2), or a count N (2 to 12) "
               "of targets placed in the free space of the learning's room from the seed (default: every named pose "
               "the robot can stand at in the room the learning starts in; 4 placed there, or as many as it "
               "holds, when fewer than 2)",
    "starts": f"random start poses per seed to navigate from (default {DEFAULT_STARTS}; 0: learning only)",
    crowd.OPTION: crowd.HELP + " (the navigations': between the targets)",
    crowd.REST_OPTION: crowd.REST_HELP,
}
LEARN, GOTO = "learn_targets", "goto_target"
POSITION_OK, HEADING_OK = 0.15, 5.0  # m, deg: the thresholds for a target and a navigation
CAMERAS = {"front": "pinhole", "stereo": "stereo"}  # what learn_targets reads (name: kind)
SEEDS = "seeds"
NAMED, PLACED = "named poses", "placed"  # where the targets come from (the figures' targets.source)
DEFAULT_PLACED, MIN_TARGETS, MAX_TARGETS = 4, 2, 12


@dataclass(frozen=True)
class Settings:
    """The area's options, checked: the target names (``t1``..``tN`` when placed), how many starts,
    and where the targets come from (``NAMED`` or ``PLACED``)."""

    targets: tuple[str, ...]
    starts: int
    source: str = NAMED
    people: crowd.Crowd = crowd.Crowd()  # people in the navigations' world
    fewer: bool = field(default=False, compare=False)  # the default count of placed targets: fewer if a seed needs


@dataclass(frozen=True)
class SeedTargets:
    """One seed's targets: the world its episodes run in (the world itself, or the copy with the
    placed targets as named poses) and the targets' true poses (world frame)."""

    world: str
    poses: dict[str, Pose2D]


@dataclass(frozen=True)
class GotoPlan:
    """One navigation: its episode, the true start pose and the goal target."""

    episode: Episode
    start: Pose2D
    goal: str


# ------------------------------------------------------------------------------------------------
# Checks


def check_world(world: str) -> World:
    """The world, loaded, with the cameras ``learn_targets`` reads, and enclosed (an open world would
    only fail in the room estimate, after placing targets for minutes). Its named poses do not
    matter here: without 2 usable ones the targets are placed in the free space (``check_options``)."""
    loaded = load_world(world)
    kinds = {spec.name: spec.kind for spec in loaded.cameras}
    missing = [f"{name} ({kind})" for name, kind in CAMERAS.items() if kinds.get(name) != kind]
    if missing:
        raise ValueError(f"world {loaded.name!r} has no {' or '.join(missing)} camera: learn_targets needs them")
    if not reachable_grid(loaded).bounded:
        raise ValueError(f"world {loaded.name!r} is open (its reachable floor runs off the map): the roadmap's room "
                         "estimate needs one enclosed room, seen all around from the dodecagon")
    return loaded


def check_options(world: str, extra: Mapping[str, str]) -> Settings:
    """The options (``OPTIONS``) checked against the world; ``ValueError`` with the problem. Placed
    targets are placed for seed 0 here, so that a world without room for them is refused before
    any episode runs."""
    loaded = load_world(world)
    grid = reachable_grid(loaded)
    start = learn_start(loaded, grid)  # ValueError: no room for the dodecagon
    room = learning_room(loaded, grid, start)
    targets, source = choose_targets(extra.get("targets"), loaded, usable_poses(loaded, grid),
                                     usable_poses(loaded, room))
    fewer = source == PLACED and extra.get("targets") is None  # the default count: as many as fit
    if source == PLACED:
        targets, _ = placeable(loaded, targets, away_from_exits(room, grid), fewer=fewer)
    starts = parse_starts(extra.get("starts"))
    if starts:
        random_starts(loaded, 1, 0, grid=room)  # ValueError: nowhere clear enough to start from
    return Settings(targets, starts, source, crowd.Crowd.from_options(extra), fewer=fewer)


def choose_targets(text: str | None, world: World, usable: Mapping[str, Pose2D],
                   in_room: Mapping[str, Pose2D]) -> tuple[tuple[str, ...], str]:
    """The target names and their source from the ``targets`` option: a count N (digits) places
    ``t1``..``tN``; names are named poses (``usable``: anywhere the robot can stand and reach);
    none: the usable named poses in the room the learning starts in (``in_room``), or
    ``DEFAULT_PLACED`` placed targets when there are fewer than 2 of them."""
    if text is None:
        if len(in_room) >= MIN_TARGETS:
            return tuple(sorted(in_room)), NAMED
        return placed_names(DEFAULT_PLACED), PLACED
    if text.strip().isdigit():
        count = int(text)
        if not MIN_TARGETS <= count <= MAX_TARGETS:
            raise ValueError(f"targets: a count must be {MIN_TARGETS} to {MAX_TARGETS}, got {count}")
        return placed_names(count), PLACED
    names = parse_targets(text, world, usable)
    if len(names) < MIN_TARGETS:
        raise ValueError(f"targets: at least {MIN_TARGETS} are needed, {text!r} gives {len(names)}")
    return names, NAMED


def placeable(world: World, names: tuple[str, ...], room: FloorGrid, *, fewer: bool,
              seeds: Sequence[int] = (0,)) -> tuple[tuple[str, ...], dict[int, dict[str, Pose2D]]]:
    """``names`` when every one of ``seeds`` places them all in the learning's room; with ``fewer``
    (the default count, not one the user gave) as many as they all place, down to ``MIN_TARGETS``
    (`clinic`'s room holds 3, `flat`'s 3 for seed 0 and 2 for seed 1); else ``ValueError`` with
    the problem. With the names, each seed's placed poses (placing takes a second or more: done once)."""
    count = len(names)
    while True:
        try:
            placed = {seed: place_targets(world, count, seed, grid=room) for seed in seeds}
            return placed_names(count), placed
        except ValueError:
            if not fewer or count <= MIN_TARGETS:
                raise
            count -= 1


def placed_names(count: int) -> tuple[str, ...]:
    """``t1``..``tN``: the names of placed targets."""
    return tuple(f"t{k}" for k in range(1, count + 1))


def parse_starts(text: str | None) -> int:
    """The ``starts`` option: 0 to ``MAX_STARTS`` (default ``DEFAULT_STARTS``)."""
    return count_option("starts", text, default=DEFAULT_STARTS, maximum=MAX_STARTS)


def parse_targets(text: str, world: World, usable: Mapping[str, Pose2D]) -> tuple[str, ...]:
    """``a,b,c``: distinct named poses of ``world`` that are usable as targets."""
    names = [n.strip() for n in text.split(",")]
    if any(not n for n in names):
        raise ValueError(f"targets: expected NAME,NAME,..., got {text!r}")
    for name in names:
        if name not in world.poses:
            raise ValueError(f"targets: world {world.name!r} has no named pose {name!r} "
                             f"(its named poses: {', '.join(sorted(world.poses)) or 'none'})")
        if name not in usable:
            raise ValueError(f"targets: the named pose {name!r} of world {world.name!r} is not where the robot can "
                             "stand and reach from the start")
    if len(set(names)) != len(names):
        raise ValueError(f"targets: a name is listed twice in {text!r}")
    return tuple(names)


# ------------------------------------------------------------------------------------------------
# Episodes


def seed_folder(folder: Path, world: str, seed: int) -> Path:
    """Where a seed's target images, roadmap file and world copy go (other seeds never share them)."""
    return folder / SEEDS / f"{Path(world).stem}_s{seed:04d}"


def seed_targets(world: str, loaded: World, settings: Settings, seed: int, folder: Path,
                 grid: FloorGrid | None = None, *, placed: Mapping[str, Pose2D] | None = None) -> SeedTargets:
    """The seed's targets. Named poses: the world as it is. Placed: ``placed`` when :func:`placeable`
    placed them already, else ``place_targets`` from the seed, written as named poses into a copy of
    the world file in the seed's folder (same file name, so the world keeps its name and the
    episodes' ids their world part); ``SweepInputError`` when the world has no room for them with
    this seed."""
    if settings.source == NAMED:
        return SeedTargets(world, {name: loaded.poses[name] for name in settings.targets})
    try:
        poses = dict(placed) if placed is not None else place_targets(loaded, len(settings.targets), seed, grid=grid)
    except ValueError as exc:
        raise SweepInputError(f"seed {seed}: {exc}") from None
    here = seed_folder(folder, world, seed)
    here.mkdir(parents=True, exist_ok=True)
    copy = world_with(world, here / f"{Path(world_path(world)).stem}.yaml", poses=poses)
    return SeedTargets(str(copy), poses)


def learn_episode(world: str, seed: int, folder: Path, max_time_s: float | None, start: Pose2D | None = None
                  ) -> Episode:
    """``learn_targets`` with the seed's target images, from ``start`` (None: the world's start;
    :func:`~experiments.eval.roadmap_world.learn_start` says where the room estimation fits)."""
    here = seed_folder(folder, world, seed)
    inputs = {"targets": str(here / "targets"), "roadmap": str(here / f"{Path(world).stem}.roadmap")}
    where = None if start is None else start_argument(start)
    return Episode(LEARN, world, seed, inputs, max_time_s, where)


def goto_plans(learn: Episode, world: World, found: Sequence[str], starts: int,
               max_time_s: float | None, grid: FloorGrid | None = None, run_in: str | None = None) -> list[GotoPlan]:
    """The seed's navigations: random starts (``random_starts``), goals drawn among ``found``; the
    mission's own ``seed`` (its random moves) is the navigation's number. They run in the world
    file ``run_in`` (default: the learning's)."""
    poses = random_starts(world, starts, learn.seed, grid=grid)
    rng = np.random.default_rng([learn.seed, 0x60A2])
    goals = [found[int(i)] for i in rng.integers(len(found), size=starts)] if found else []
    plans = []
    for k, (start, goal) in enumerate(zip(poses, goals, strict=True)):
        where = start_argument(start)
        inputs = {"roadmap": learn.inputs["roadmap"], "target": goal, "seed": k}
        plans.append(GotoPlan(Episode(GOTO, run_in or learn.world, learn.seed, inputs, max_time_s, where), start, goal))
    return plans


def navigation_worlds(loaded: World, settings: Settings, targets: Mapping[int, SeedTargets], folder: Path,
                      grid: FloorGrid | None) -> tuple[dict[int, str], dict[int, list[crowd.Walker]]]:
    """Per seed, the world its navigations run in (with ``settings.people`` people between the
    targets: module docstring) and those people; the seed's world itself when there are none."""
    if not settings.people:
        return {seed: t.world for seed, t in targets.items()}, {}
    worlds, people = {}, {}
    for seed, t in targets.items():
        spots = [(p.x, p.y) for p in t.poses.values()]
        ways = [np.array([a, b]) for i, a in enumerate(spots) for b in spots[i + 1:]]
        clear = [*spots, (loaded.start.x, loaded.start.y),
                 *((p.x, p.y) for p in random_starts(loaded, settings.starts, seed, grid=grid))]
        people[seed] = settings.people.on_ways(loaded, ways, seed, keep_clear=clear)
        here = seed_folder(folder, t.world, seed) / "people" / f"{Path(world_path(t.world)).stem}.yaml"
        worlds[seed] = str(crowd.world_with_people(t.world, here, people[seed]))
    return worlds, people


def _outcome(report: Mapping[str, Any] | None, row: Mapping[str, Any] | None) -> dict[str, Any]:
    """Status and reason of an episode: its report's, else its sweep row's (a crash, a timeout)."""
    if report is not None:
        return {"status": report.get("status", "ERROR"), "reason": report.get("reason", "")}
    if row is not None:
        return {"status": row.get("status", "ERROR"), "reason": row.get("reason", "no report")}
    return {"status": "ERROR", "reason": "the episode gave no report"}


# ------------------------------------------------------------------------------------------------
# Figures


def reference_truth(report: Mapping[str, Any]) -> Pose2D | None:
    """The robot's true pose when the learn run took its reference image (None: it never did)."""
    stamp = report.get("roadmap", {}).get("room", {}).get("reference_stamp")
    if stamp is None or not math.isfinite(float(stamp)) or "ground_truth" not in report:
        return None
    return TrueTrajectory(report["ground_truth"]).at(float(stamp))


def learn_figures(seed: int, report: Mapping[str, Any] | None, row: Mapping[str, Any] | None,
                  truth: Mapping[str, Pose2D]) -> dict[str, Any]:
    """The figures of one learn run against the true poses of its targets (``truth``)."""
    out: dict[str, Any] = {"episode": "learn", "seed": seed, **_outcome(report, row), "targets": len(truth),
                           "found": 0, "target_errors": {}, "within": 0, "connected": False, "edges": 0,
                           "sim_time_s": None, "wall_time_s": row.get("elapsed_s") if row else None,
                           **safety_figures(report)}
    if report is None:
        return out
    section = report.get("roadmap", {})
    reference = reference_truth(report)
    errors = target_errors(report, truth, reference) if reference is not None else {}
    out.update({
        "found": len(errors),
        "target_errors": {n: {"position_m": round(d, 4), "heading_deg": round(a, 3)} for n, (d, a) in errors.items()},
        "within": sum(d <= POSITION_OK and a <= HEADING_OK for d, a in errors.values()),
        "connected": bool(section.get("connected", False)),
        "edges": len(section.get("edges", [])),
        "dropped": len(section.get("dropped", [])),
        "sim_time_s": report.get("sim_time_s"),
        "wall_time_s": report.get("wall_time_s", out["wall_time_s"]),
    })
    return out


def goto_figures(plan: GotoPlan, report: Mapping[str, Any] | None, row: Mapping[str, Any] | None,
                 goal_truth: Pose2D) -> dict[str, Any]:
    """The figures of one navigation: its true final pose against the goal's true pose."""
    start = plan.start
    out: dict[str, Any] = {"episode": "goto", "seed": plan.episode.seed, "number": plan.episode.inputs["seed"],
                           "start": [round(start.x, 3), round(start.y, 3), round(math.degrees(start.theta), 1)],
                           "goal": plan.goal, **_outcome(report, row), "reached": False, "error_m": None,
                           "error_deg": None, "sim_time_s": None, "wall_time_s": row.get("elapsed_s") if row else None,
                           **safety_figures(report)}
    if report is None or "ground_truth" not in report:
        return out
    final = report["ground_truth"]["final_pose"]
    distance, heading = pose_error(Pose2D(final["x"], final["y"], final["theta"]), goal_truth)
    navigation = report.get("roadmap", {}).get("navigation", {})
    out.update({
        "error_m": round(distance, 4), "error_deg": round(heading, 3),
        "reached": bool(out["status"] == "SUCCESS" and out["collisions"] == 0 and distance <= POSITION_OK
                        and heading <= HEADING_OK),
        "visited": navigation.get("visited"), "random_moves": navigation.get("random_moves"),
        "sim_time_s": report.get("sim_time_s"), "wall_time_s": report.get("wall_time_s", out["wall_time_s"]),
    })
    return out


def _worst(values: Sequence[Any]) -> float | None:
    present = [float(v) for v in values if v is not None]
    return max(present) if present else None


def pose_rows(poses: Mapping[int, Mapping[str, Pose2D]]) -> dict[str, dict[str, list[float]]]:
    """Per seed (a string: a JSON key), each target's true pose as ``[x m, y m, theta deg]``."""
    return {str(seed): {name: [round(p.x, 3), round(p.y, 3), round(math.degrees(p.theta), 1)]
                        for name, p in by_name.items()} for seed, by_name in sorted(poses.items())}


def summarise(world: str, settings: Settings, learns: list[dict[str, Any]], gotos: list[dict[str, Any]],
              poses: Mapping[int, Mapping[str, Pose2D]] | None = None) -> dict[str, Any]:
    """The named figures of the whole evaluation from its runs' figures (one flat object); ``poses``:
    each seed's target poses (world frame), recorded with where they came from."""
    errors = [e for run in learns for e in run["target_errors"].values()]
    measured = [g for g in gotos if g["error_m"] is not None]
    reached = sum(g["reached"] for g in gotos)
    out: dict[str, Any] = {
        "world": world,
        "seeds": len(learns),
        "targets": list(settings.targets),
        "targets.source": settings.source,
        "targets.poses": pose_rows(poses or {}),
        "starts": settings.starts,
        "criterion": f"within {POSITION_OK:g} m and {HEADING_OK:g} deg (a goto: and SUCCESS); a run: no collision",
        "learn.succeeded": sum(run["status"] == "SUCCESS" and not run.get("collisions") for run in learns),
        "targets.found": sum(run["found"] for run in learns),
        "targets.total": len(settings.targets) * len(learns),
        "targets.within": sum(run["within"] for run in learns),
        "targets.position_error_worst_m": _worst([e["position_m"] for e in errors]),
        "targets.position_error_mean_m": mean_present([e["position_m"] for e in errors]),
        "targets.heading_error_worst_deg": _worst([e["heading_deg"] for e in errors]),
        "targets.heading_error_mean_deg": mean_present([e["heading_deg"] for e in errors]),
        "graph.connected_rate": sum(run["connected"] for run in learns) / len(learns) if learns else None,
        "graph.edges_mean": mean_present([run["edges"] for run in learns]),
        "goto.planned": settings.starts * len(learns),
        "goto.run": len(gotos),
        "goto.reached": reached,
        "goto.reached_rate": reached / len(gotos) if gotos else None,
        "goto.error_worst_m": _worst([g["error_m"] for g in measured]),
        "goto.error_mean_m": mean_present([g["error_m"] for g in measured]),
        "goto.heading_error_worst_deg": _worst([g["error_deg"] for g in measured]),
        "goto.heading_error_mean_deg": mean_present([g["error_deg"] for g in measured]),
        "learn.sim_time_s": mean_present([run["sim_time_s"] for run in learns]),
        "learn.wall_time_s": mean_present([run["wall_time_s"] for run in learns]),
        **{f"learn.{k}": v for k, v in safety_totals(learns).items()},
        **{f"goto.{k}": v for k, v in safety_totals(gotos).items()},
    }
    out["failures"] = [_failure(run) for run in [*learns, *gotos] if run["status"] != "SUCCESS"]
    out["runs"] = [*learns, *gotos]
    return out


def _moved_start(world: World, grid: FloorGrid) -> Pose2D | None:
    """The learning's start when the world's own has no room for the room estimation (None: it has;
    ``SweepInputError`` when no place has)."""
    try:
        start = learn_start(world, grid)
    except ValueError as exc:
        raise SweepInputError(str(exc)) from None
    return None if (start.x, start.y, start.theta) == (world.start.x, world.start.y, world.start.theta) else start


def _failure(run: Mapping[str, Any]) -> dict[str, Any]:
    what = f"goto {run['number']} to {run['goal']}" if run["episode"] == "goto" else "learn"
    return {"seed": run["seed"], "episode": what, "status": run["status"], "reason": run["reason"]}


# ------------------------------------------------------------------------------------------------
# The evaluation


def _learn_phase(options: EvalOptions, targets: Mapping[int, SeedTargets], settings: Settings, folder: Path,
                 resume: bool, start: Pose2D | None) -> tuple[dict[int, Episode], dict[str, dict[str, Any]]]:
    episodes = {seed: learn_episode(targets[seed].world, seed, folder, options.max_time_s, start)
                for seed in options.seeds}
    for seed, episode in episodes.items():
        write_target_images(targets[seed].world, settings.targets, Path(episode.inputs["targets"]), seed=seed)
    rows = run_sweep(list(episodes.values()), executor=options.executor, results_dir=folder,
                     timeout_s=options.timeout_s, progress=options.progress, resume=resume)
    return episodes, {row["id"]: row for row in rows}


def run(options: EvalOptions, *, resume: bool = False) -> dict[str, Any]:
    """Target images, a learn run per seed, navigations from random starts; the named figures."""
    loaded, settings = options.checked or (check_world(options.world), check_options(options.world, options.extra))
    world = absolute_if_file(options.world)  # episodes run in other processes
    folder = Path(options.results_dir).resolve()
    grid = reachable_grid(loaded)
    moved = _moved_start(loaded, grid)
    room = learning_room(loaded, grid, moved or loaded.start)  # once: every seed's starts
    inner = away_from_exits(room, grid) if settings.source == PLACED else room
    placed: dict[int, dict[str, Pose2D]] = {}
    if settings.fewer:  # as many as every seed places (check_options tried seed 0)
        try:
            names, placed = placeable(loaded, settings.targets, inner, fewer=True, seeds=options.seeds)
        except ValueError as exc:
            raise SweepInputError(str(exc)) from None
        settings = replace(settings, targets=names)
    targets = {seed: seed_targets(world, loaded, settings, seed, folder, inner, placed=placed.get(seed))
               for seed in options.seeds}
    truth = {seed: t.poses for seed, t in targets.items()}
    navigate_in, people = navigation_worlds(loaded, settings, targets, folder, room)
    hidden = {seed: out_of_sight(loaded, moved or loaded.start, t.poses) for seed, t in targets.items()}
    episodes, rows = _learn_phase(options, targets, settings, folder, resume, moved)
    learns, plans = [], []
    for seed, episode in sorted(episodes.items()):
        figures = learn_figures(seed, read_report(folder, episode.id), rows.get(episode.id), truth[seed])
        learns.append(figures)
        found = sorted(figures["target_errors"])
        if settings.starts and found and Path(episode.inputs["roadmap"]).is_file():
            plans += goto_plans(episode, loaded, found, settings.starts, options.max_time_s, room, navigate_in[seed])
    rows = {}
    if plans:  # every navigation at once: the pool runs them in parallel
        done = run_sweep([p.episode for p in plans], executor=options.executor, results_dir=folder,
                         timeout_s=options.timeout_s, progress=options.progress, resume=True)
        rows = {row["id"]: row for row in done}
    gotos = [goto_figures(p, read_report(folder, p.episode.id), rows.get(p.episode.id), truth[p.episode.seed][p.goal])
             for p in plans]
    out = summarise(loaded.name, settings, learns, gotos, truth)
    out["targets.out_of_sight"] = {str(seed): list(names) for seed, names in hidden.items()}
    return {**out, **settings.people.figures(people)}


# ------------------------------------------------------------------------------------------------
# The table


def _pair(metres: Any, degrees: Any) -> str:
    return f"{cell(metres)} m, {cell(degrees, 2)} deg"


def format_table(figures: Mapping[str, Any]) -> str:
    """The headline figures, then one line per run."""
    f = figures
    rate = f["goto.reached_rate"]
    lines = [
        f"roadmap in {f['world']}: {f['seeds']} seed(s), targets {', '.join(f['targets'])} "
        f"({f.get('targets.source', NAMED)}), {f['starts']} goto start(s) per seed; {f['criterion']}",
        f"learn: {f['learn.succeeded']} of {f['seeds']} succeeded; sim {cell(f['learn.sim_time_s'], 0)} s, wall "
        f"{cell(f['learn.wall_time_s'], 0)} s (means); {safety_cells(_prefixed(f, 'learn.'))}",
        f"targets found {f['targets.found']} of {f['targets.total']}, within {f['targets.within']}; error worst "
        f"{_pair(f['targets.position_error_worst_m'], f['targets.heading_error_worst_deg'])}, mean "
        f"{_pair(f['targets.position_error_mean_m'], f['targets.heading_error_mean_deg'])}",
        f"graph connected {cell(f['graph.connected_rate'], 2)} of the seeds, {cell(f['graph.edges_mean'], 1)} "
        "edges (mean)",
        f"goto reached {f['goto.reached']} of {f['goto.run']} run ({f['goto.planned']} planned, rate "
        f"{cell(rate, 2)}, {interval_cell(f['goto.reached'], f['goto.run'])}); error worst "
        f"{_pair(f['goto.error_worst_m'], f['goto.heading_error_worst_deg'])}, mean "
        f"{_pair(f['goto.error_mean_m'], f['goto.heading_error_mean_deg'])}; {safety_cells(_prefixed(f, 'goto.'))}",
        "",
        f"{'seed':>4} {'run':<18} {'status':<8} {'result':<38} {'error':<24} {'sim s':>7} {'wall s':>7}  obstacles",
    ]
    lines += [_run_line(run) for run in f["runs"]]
    if f.get("targets.source") == PLACED:
        lines += [f"seed {seed} placed targets: " + ", ".join(f"{n} ({x:g}, {y:g}, {deg:g} deg)"
                                                               for n, (x, y, deg) in by_name.items())
                  for seed, by_name in f["targets.poses"].items()]
    lines += [f"seed {seed}: {', '.join(names)} out of sight of where the learning starts, behind a wall: the "
              "roadmap learns the targets of the room it starts in (without --option targets it takes those)"
              for seed, names in f.get("targets.out_of_sight", {}).items() if names]
    lines += crowd.table_line(f)
    lines += [f"seed {x['seed']} {x['episode']}: {x['status']}: {x['reason']}" for x in f["failures"]]
    return "\n".join(lines)


def _run_line(run: Mapping[str, Any]) -> str:
    if run["episode"] == "learn":
        what = "learn"
        result = (f"found {run['found']}/{run['targets']}, within {run['within']}, "
                  f"{'connected' if run['connected'] else 'not connected'} {run['edges']} edges")
        errors = list(run["target_errors"].values())
        error = "-" if not errors else "worst " + _pair(max(e["position_m"] for e in errors),
                                                        max(e["heading_deg"] for e in errors))
    else:
        what = f"goto {run['number']} -> {run['goal']}"
        result = "reached" if run["reached"] else "not reached"
        error = _pair(run["error_m"], run["error_deg"]) if run["error_m"] is not None else "-"
    return (f"{run['seed']:>4} {what:<18} {run['status']:<8} {result:<38} {error:<24} "
            f"{cell(run['sim_time_s'], 0):>7} {cell(run['wall_time_s'], 0):>7}  {safety_cells(run)}")


def _prefixed(figures: Mapping[str, Any], prefix: str) -> dict[str, Any]:
    return {k[len(prefix):]: v for k, v in figures.items() if k.startswith(prefix)}
