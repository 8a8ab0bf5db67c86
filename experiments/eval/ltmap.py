"""``bearings eval ltmap``: teach a route, repeat it from the full LT-map and from every pruned tree
height, one row per height (the paper's Table I).

Episodes (all through the sweep runner, in the results folder):

1. **Teach**, one per seed: ``teach_route`` drives the route (:mod:`experiments.eval.ltmap_route`: a
   tour of the world's free floor by default, or ``--option route=x0,y0,...``) from the world's
   start and saves the map to ``maps/<world>_s<seed>.ltmap`` in the results folder.
2. **Repeat**, one per seed and tree height, all submitted together: ``follow_route`` in reverse
   (home) from the teach's true end pose (``--start`` from its report's ground truth), from the full
   map and from the map pruned by 1, 2, ... levels down to a single level. The heights, their
   sizes and the byte budget that gives each are read from the saved map
   (:func:`maps.ltmap.file.load_ltmap`, the same ``prune_level`` steps ``PruneMap`` takes): the
   repeat of height h gets ``budget`` = the bytes of the map cut to h, so ``PruneMap`` cuts exactly
   those levels. ``min_landmarks`` (pruning deletes viewframes left with fewer) is the paper's 50,
   or half the median viewframe when the map's viewframes hold fewer than 100 landmarks (the ideal
   sensor: as ``FollowRoute`` reads "fewer than 50 landmarks"); ``--option min_landmarks=N``
   overrides it. A repeat's ``--max-time`` is 120 s plus 4 times the teach's (or ``--max-time``).

Figures (simulator ground truth, evaluation only), per repeat:

- ``viewframe_error_m``: mean over the viewframes the repeat reached of the distance between the
  robot's true position when it switched past the viewframe (``ltmap.reached`` times) and its true
  position when the viewframe was taught (``ltmap.taught`` times of the teach, through the repeat's
  ``viewframe_source`` after pruning; a merged viewframe counts as its earliest source). It includes
  the switching radius: a viewframe is passed when it is near enough, not when it is stood on.
- ``path_error_m``: mean distance of the repeat's true trajectory (decimated as in the report) to
  the teach's true trajectory (a polyline); searches for a lost trail count too.
- ``goal_error_m``: distance from where the repeat ended to the route's start (where the teach began).
- ``collisions``, ``safety_stops``, ``min_clearance_m``: the run's contacts (ground truth), the
  collision monitor's stops, the true smallest clearance when the simulator reports it
  (:func:`~experiments.eval.figures.safety_figures`).
- ``reached`` (the goal): the mission ended in SUCCESS (its last viewframe switched), without a
  collision, *and* ``goal_error_m`` <= the goal tolerance: the robot's diameter or the mean spacing of the taught
  viewframes (true places, consecutive), whichever is larger, per seed; the map tells places
  apart no finer than its spacing (indoors a few decimetres, outdoors metres, where far landmarks
  change slowly). ``--option goal_tolerance=M`` fixes it instead.
- ``viewframes_reached``: fraction of the map's viewframes the repeat switched past.
- ``estimates_pct``: per rule, the percentage of the repeat's estimates it made (``FollowRoute``'s
  ``ltmap.estimates``: a rung of Z-infinity's far-threshold ladder, the compass, no rotation, lost).
- ``bytes_per_m``: the map's bytes at this height per metre of the taught route (true length).

Maps are written by the teach episodes into the results folder and read by the repeats and by
this module: on a Dask cluster (``--cluster``) that folder (``-o DIR``) must be one the workers and
this machine share.

People (``--option people=N``, :mod:`experiments.eval.people`): N people drawn from the seed,
standing on the taught route or walking across it, none within 1 m of its start or end, are added
to a copy of the world file (``people/s<seed>/<world>.yaml`` in the results folder) that the
seed's repeats run in; the teach runs in the world as it is (the route is taught, then repeated
home with people in it). The figures record the people placed (``people.placed``, ``people.paths``).

A row (per number of levels cut, 0 = the full tree; its ``height`` is the same for every seed
unless seeds taught trees of different heights, then the range) holds the means over its seeds,
``goal_reached`` of ``seeds``, and over its repeats the collisions and safety stops summed and the
smallest clearance. A seed whose teach failed has no repeats (``teach_failed``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from drivers.sim.simulation import path_distances
from drivers.sim.world import World, load_world
from experiments.eval import EvalOptions
from experiments.eval import people as crowd
from experiments.eval.figures import cell, mean_present, safety_figures, safety_totals
from experiments.eval.ltmap_route import Route, back_route, default_route, given_route, parse_route
from experiments.eval.ltmap_table import estimate_shares, memory_limits, row_figures
from experiments.eval.ltmap_table import format_table as format_table  # the area's table (experiments.eval)
from experiments.eval.trajectory import TrueTrajectory
from experiments.sweep import Episode, run_sweep
from experiments.sweep.episode import start_argument
from experiments.sweep.table import read_report
from maps.ltmap.file import load_ltmap
from maps.ltmap.prune import DEFAULT_MIN_LANDMARKS
from maps.ltmap.tree import LandmarkTree
from perception.geometry import Pose2D

DESCRIPTION = "teach and repeat: viewframe and path error, goal reached per LT-map tree height (Table I)"
OPTIONS = {
    "camera": "the camera the missions read: panorama (rendered images, ORB; default) or landmarks (ideal bearings); "
              "any panorama or bearings camera of the world",
    "route": "tour (default: a tour of the free floor), back (out along the tour and back past its bend: a route "
             "that revisits places) or the taught waypoints x0,y0,x1,y1,... (m, odometry frame of the start pose)",
    "gap_filling": "on (default) or off: the teach shifts landmarks found again to a common node (maps.ltmap.gaps)",
    "min_landmarks": "pruning deletes viewframes left with fewer landmarks (default: 50, or half the median "
                     "viewframe of a map with small viewframes)",
    "goal_tolerance": "m: the goal is reached when the repeat succeeds and ends this close to the route's start "
                      "(default: the robot's diameter or the taught viewframes' spacing, whichever is larger)",
    "rotation": "how the repeat estimates its rotation: zinf (Z-infinity, the paper; default) or compass (the "
                "median bearing change of every landmark: the comparison for worlds with near landmarks)",
    "odometry": "off (default: the paper) or on: a repeat lost after reaching a viewframe drives by the taught "
                "odometry through the next places, up to 4 m on, before it counts as lost (follow_route's 'odometry')",
    "cuts": "repeat from the full map and at most this many levels cut (default: every level down to one; 0: "
            "the full map alone, e.g. to measure obstacles or people in a quarter of the time)",
    crowd.OPTION: crowd.HELP + " (the repeats': on the taught route or across it)",
    crowd.REST_OPTION: crowd.REST_HELP,
}
ROTATIONS = ("zinf", "compass")
TEACH, FOLLOW = "teach_route", "follow_route"
TOUR, BACK = "tour", "back"
ON_OFF = {"on": True, "off": False}
CAMERA_KINDS = ("panorama", "bearings")
SMALL_VIEWFRAME = 2 * DEFAULT_MIN_LANDMARKS  # landmarks: below this, min_landmarks is half the median viewframe
ODOMETRY_REACH = 4.0  # m: follow_route's 'odometry' with --option odometry=on
REPEAT_TIME = (120.0, 4.0)  # s: a repeat's --max-time = a + b * the teach's sim time
MAPS = "maps"


@dataclass(frozen=True)
class Settings:
    """The area's options, checked."""

    camera: str
    route: Route
    min_landmarks: int | None  # None: from the map (module docstring)
    goal_tolerance: float | None  # m; None: per seed from the robot and the map (module docstring)
    rotation: str = "zinf"  # FollowRoute's rotation estimate (ROTATIONS)
    gap_filling: bool = True  # LearnRoute's gap filling (maps.ltmap.gaps)
    people: crowd.Crowd = crowd.Crowd()  # people in the repeats' world
    cuts: int | None = None  # at most this many levels cut (None: every level)
    odometry: bool = False  # FollowRoute drives by the taught odometry while lost


def check_world(world: str) -> World:
    """The world, loaded (``InputError`` when it is not one) and with a camera the missions can read."""
    loaded = load_world(world)
    if not any(spec.kind in CAMERA_KINDS for spec in loaded.cameras):
        raise ValueError(f"world {loaded.name!r} has no panorama or bearings camera to teach a route with")
    return loaded


def check_options(world: str, extra: Mapping[str, str]) -> Settings:
    """The options (``OPTIONS``) checked against the world; ``ValueError`` with the problem."""
    loaded = load_world(world)
    camera = extra.get("camera", "panorama")
    kinds = {spec.name: spec.kind for spec in loaded.cameras}
    if kinds.get(camera) not in CAMERA_KINDS:
        usable = ", ".join(n for n, k in kinds.items() if k in CAMERA_KINDS) or "none"
        raise ValueError(f"camera: {camera!r} is not a panorama or bearings camera of world {loaded.name!r} "
                         f"(usable: {usable})")
    route = _route(loaded, extra.get("route", TOUR))
    min_landmarks = None
    if "min_landmarks" in extra:
        min_landmarks = _number(extra["min_landmarks"], "min_landmarks", int)
        if min_landmarks < 0:
            raise ValueError(f"min_landmarks must be >= 0, got {min_landmarks}")
    tolerance = None
    if "goal_tolerance" in extra:
        tolerance = _number(extra["goal_tolerance"], "goal_tolerance", float)
        if not (math.isfinite(tolerance) and tolerance > 0):
            raise ValueError(f"goal_tolerance must be a positive number of metres, got {extra['goal_tolerance']!r}")
    rotation = extra.get("rotation", "zinf")
    if rotation not in ROTATIONS:
        raise ValueError(f"rotation must be one of {', '.join(ROTATIONS)}, got {rotation!r}")
    cuts = None
    if "cuts" in extra:
        cuts = _number(extra["cuts"], "cuts", int)
        if cuts < 0:
            raise ValueError(f"cuts must be >= 0 (0: the full map alone), got {cuts}")
    return Settings(camera, route, min_landmarks, tolerance, rotation, _on_off(extra, "gap_filling"),
                    crowd.Crowd.from_options(extra), cuts, _on_off(extra, "odometry", "off"))


def _on_off(extra: Mapping[str, str], name: str, default: str = "on") -> bool:
    """An on/off option; ``ValueError`` for anything else."""
    value = extra.get(name, default)
    if value not in ON_OFF:
        raise ValueError(f"{name} must be on or off, got {value!r}")
    return ON_OFF[value]


def _route(world: World, text: str) -> Route:
    """The route an option names: the tour, out and back along it, or given waypoints."""
    if text == TOUR:
        return default_route(world)
    if text == BACK:
        return back_route(world)
    return given_route(world, parse_route(text))


def _number(text: str, name: str, kind: type[int] | type[float]) -> Any:
    try:
        return kind(text)
    except ValueError:
        raise ValueError(f"{name}: {'an integer' if kind is int else 'a number'} expected, got {text!r}") from None


# ------------------------------------------------------------------------------------------------
# The map's heights


@dataclass(frozen=True)
class Level:
    """The map cut by ``cut`` levels: its shape and the budget that makes ``PruneMap`` cut them."""

    cut: int
    height: int
    viewframes: int
    landmarks: int
    bytes: int
    fraction: float  # of the full map's bytes


def min_landmarks_for(tree: LandmarkTree, given: int | None) -> int:
    """``given``, or the paper's 50, or half the median viewframe of a map of small viewframes."""
    if given is not None:
        return given
    nodes = tree.landmark_nodes
    sizes = [int(np.isin(nodes, tree.branch_nodes(i)).sum()) for i in range(tree.viewframe_count)]
    median = float(np.median(sizes)) if sizes else 0.0
    return DEFAULT_MIN_LANDMARKS if median >= SMALL_VIEWFRAME else max(1, math.ceil(median / 2))


def levels(tree: LandmarkTree, min_landmarks: int) -> list[Level]:
    """The full map and every pruned height down to a single level (as ``PruneMap`` prunes)."""
    work, full = tree.copy(), tree.memory_bytes()
    out: list[Level] = []
    for cut in range(tree.height + 1):
        if cut:
            work.prune_level(min_landmarks)
        size = work.memory_bytes()
        if out and size >= out[-1].bytes:  # no smaller: a budget could not tell it from the last
            break
        out.append(Level(cut, work.height, work.viewframe_count, work.landmark_count, size, size / full))
    return out


# ------------------------------------------------------------------------------------------------
# Episodes


def teach_episode(world: str, seed: int, settings: Settings, folder: Path, max_time_s: float | None) -> Episode:
    path = folder / MAPS / f"{Path(world).stem}{'' if settings.gap_filling else '_nogaps'}_s{seed:04d}.ltmap"
    route = [round(v, 3) for v in settings.route.odometry]
    inputs: dict[str, Any] = {"map": str(path), "camera": settings.camera, "route": route}
    if not settings.gap_filling:  # only when not the default: the ids of the default's results stay
        inputs["gap_filling"] = False
    return Episode(TEACH, world, seed, inputs, max_time_s)


def follow_episode(teach: Episode, report: Mapping[str, Any], level: Level, min_landmarks: int,
                   max_time_s: float | None, rotation: str = "zinf", world: str | None = None,
                   odometry: bool = False) -> Episode:
    """The repeat of ``teach``'s map cut by ``level.cut`` levels, from the teach's true end pose, in
    ``world`` (default: the teach's)."""
    end = report["ground_truth"]["final_pose"]
    start = start_argument(Pose2D(end["x"], end["y"], end["theta"]))
    inputs: dict[str, Any] = {"map": teach.inputs["map"], "camera": teach.inputs["camera"], "direction": "reverse",
                              "min_landmarks": min_landmarks}
    if level.cut:
        inputs["budget"] = level.bytes
    if rotation != "zinf":  # only when not the default: the ids of earlier results stay what they were
        inputs["rotation"] = rotation
    if odometry:  # only when not the default: the ids of earlier results stay what they were
        inputs["odometry"] = ODOMETRY_REACH
    if max_time_s is None:
        a, b = REPEAT_TIME
        max_time_s = float(math.ceil((a + b * float(report.get("sim_time_s", 0.0))) / 10.0) * 10.0)
    return Episode(FOLLOW, world or teach.world, teach.seed, inputs, max_time_s, start)


# ------------------------------------------------------------------------------------------------
# Figures


@dataclass(frozen=True)
class Run:
    """A run's report with its true trajectory, read once: a teach's serves every repeat of its map."""

    report: Mapping[str, Any]
    truth: TrueTrajectory

    @classmethod
    def of(cls, report: Mapping[str, Any]) -> Run:
        return cls(report, TrueTrajectory(report["ground_truth"]))


def goal_tolerance(teach: Run, robot_radius: float, given: float | None) -> float:
    """``given``, or the robot's diameter or the taught viewframes' mean spacing, whichever is larger."""
    if given is not None:
        return given
    taught = teach.report.get("ltmap", {}).get("taught", [])
    places = np.array([teach.truth.position(float(e["time_s"])) for e in taught])
    spacing = float(np.hypot(*np.diff(places, axis=0).T).mean()) if len(places) > 1 else 0.0
    return max(2.0 * robot_radius, spacing)


def viewframe_errors(teach: Run, repeat: Run) -> list[float]:
    """Per viewframe the repeat reached, the distance from where it was taught (module docstring)."""
    taught = {int(e["viewframe"]): float(e["time_s"]) for e in teach.report["ltmap"].get("taught", [])}
    section = repeat.report.get("ltmap", {})
    source = section.get("viewframe_source") or list(range(int(section.get("viewframes", 0))))
    out = []
    for entry in section.get("reached", []):
        v = int(entry["viewframe"])
        if 0 <= v < len(source) and int(source[v]) in taught:
            now, then = repeat.truth.position(float(entry["time_s"])), teach.truth.position(taught[int(source[v])])
            out.append(float(np.hypot(*(now - then))))
    return out


def taught_length(teach: Run) -> float:
    """The true length (m) of the taught route: the report's, else its decimated trajectory's."""
    given = teach.report["ground_truth"].get("trajectory_length_m")
    return float(given) if given is not None else float(teach.truth.length[-1])


def repeat_figures(teach: Run, repeat: Mapping[str, Any] | None, level: Level,
                   tolerance: float) -> dict[str, Any]:
    """The figures of one repeat (module docstring); a repeat without a report reached nothing."""
    out: dict[str, Any] = {"cut": level.cut, "height": level.height, "viewframes": level.viewframes,
                           "landmarks": level.landmarks, "bytes": level.bytes, "memory_fraction": level.fraction}
    if repeat is None or "ground_truth" not in repeat:
        return {**out, "status": "ERROR", "reached": False}
    run = Run.of(repeat)
    section = repeat.get("ltmap", {})
    errors = viewframe_errors(teach, run)
    then, now = teach.truth.xy, run.truth.xy
    goal_error = float(np.hypot(*(now[-1] - then[0])))
    reached = {int(e["viewframe"]) for e in section.get("reached", [])}
    safety = safety_figures(repeat)
    out.update({
        "status": repeat["status"],
        "reason": repeat.get("reason", ""),
        "viewframe_error_m": float(np.mean(errors)) if errors else None,
        "path_error_m": float(path_distances(now, then).mean()) if len(then) > 1 else None,
        "goal_error_m": goal_error,
        **safety,
        "reached": bool(repeat["status"] == "SUCCESS" and safety["collisions"] == 0 and goal_error <= tolerance),
        "viewframes_reached": len(reached) / max(level.viewframes, 1),
        "recoveries": int(section.get("recoveries", 0)),
        "estimates_pct": estimate_shares(section.get("estimates") or {}),
        "bytes_per_m": level.bytes / length if (length := taught_length(teach)) > 0 else None,
        "sim_time_s": float(repeat.get("sim_time_s", 0.0)),
        "map_as_expected": section.get("height") == level.height and section.get("bytes") == level.bytes,
    })
    return out


# ------------------------------------------------------------------------------------------------
# The evaluation


def _teach_phase(options: EvalOptions, settings: Settings, folder: Path,
                 resume: bool) -> dict[int, tuple[Episode, dict[str, Any] | None]]:
    (folder / MAPS).mkdir(parents=True, exist_ok=True)
    episodes = {seed: teach_episode(options.world, seed, settings, folder, options.max_time_s)
                for seed in options.seeds}
    run_sweep(list(episodes.values()), executor=options.executor, results_dir=folder, timeout_s=options.timeout_s,
              progress=options.progress, resume=resume)
    return {seed: (episode, read_report(folder, episode.id)) for seed, episode in episodes.items()}


def repeat_worlds(world: str, loaded: World, settings: Settings, seeds: list[int],
                  folder: Path) -> tuple[dict[int, str], dict[int, list[crowd.Walker]]]:
    """Per seed, the world its repeats run in (with ``settings.people`` people on or across the
    route: module docstring) and those people; the world itself when there are none."""
    if not settings.people:
        return {seed: world for seed in seeds}, {}
    route = settings.route.world_xy
    people = {seed: settings.people.on_ways(loaded, [route], seed, keep_clear=[route[0], route[-1]])
              for seed in seeds}
    worlds = {seed: str(crowd.world_with_people(world, folder / "people" / f"s{seed:04d}" / f"{Path(world).stem}.yaml",
                                          people[seed])) for seed in seeds}
    return worlds, people


def _taught(teach: Episode, report: dict[str, Any] | None) -> LandmarkTree | str:
    """The saved map of a teach that succeeded, else why there is none."""
    path = Path(teach.inputs["map"])
    if report is None:
        return "ERROR: the teach gave no report"
    if report.get("status") != "SUCCESS":
        return f"{report.get('status')}: {report.get('reason', '')}"
    if not path.exists():  # on a cluster, workers must see the results folder (module docstring)
        return f"the teach succeeded but its map {path} is not here"
    return load_ltmap(path)


def run(options: EvalOptions, *, resume: bool = False) -> dict[str, Any]:
    """Teach on every seed, repeat from every tree height, compute the Table-I figures."""
    world, settings = options.checked or (check_world(options.world), check_options(options.world, options.extra))
    folder = Path(options.results_dir).resolve()
    repeat_world, people = repeat_worlds(options.world, world, settings, options.seeds, folder)
    teaches = _teach_phase(options, settings, folder, resume)
    plan: list[tuple[Episode, Run, Level]] = []
    failed, teach_rows = [], []
    tolerance: dict[int, float] = {}
    for seed, (teach, report) in sorted(teaches.items()):
        tree = _taught(teach, report)
        if isinstance(tree, str) or report is None:
            failed.append({"seed": seed, "problem": str(tree)})
            continue
        taught = Run.of(report)  # read once for all the repeats of this map
        minimum = min_landmarks_for(tree, settings.min_landmarks)
        tolerance[seed] = goal_tolerance(taught, world.robot_radius, settings.goal_tolerance)
        teach_rows.append({"seed": seed, "viewframes": tree.viewframe_count, "landmarks": tree.landmark_count,
                           "height": tree.height, "bytes": tree.memory_bytes(), "min_landmarks": minimum,
                           "goal_tolerance_m": tolerance[seed],
                           "path_length_m": report["ground_truth"]["trajectory_length_m"],
                           "shifted": report.get("ltmap", {}).get("shifted"),
                           "loop_closures": report.get("ltmap", {}).get("loop_closures"),
                           "sim_time_s": report.get("sim_time_s"), **safety_figures(report)})
        plan += [(follow_episode(teach, report, level, minimum, options.max_time_s, settings.rotation,
                                 repeat_world[seed], settings.odometry), taught, level)
                 for level in levels(tree, minimum)[:None if settings.cuts is None else settings.cuts + 1]]
    if plan:  # every repeat at once: the pool runs them in parallel
        run_sweep([episode for episode, _, _ in plan], executor=options.executor, results_dir=folder,
                  timeout_s=options.timeout_s, progress=options.progress, resume=True)
    runs = []
    for episode, taught, level in plan:
        figures = repeat_figures(taught, read_report(folder, episode.id), level, tolerance[episode.seed])
        runs.append({"seed": episode.seed, **figures})
    out = summarise(world, settings, len(options.seeds), teach_rows, failed, runs)
    return {**out, **settings.people.figures(people)}


def summarise(world: World, settings: Settings, seeds: int, teach_rows: list[dict[str, Any]],
              failed: list[dict[str, Any]], runs: list[dict[str, Any]]) -> dict[str, Any]:
    """The named figures: the route, the teaching, one row per tree height, headline figures."""
    by_cut: dict[int, list[dict[str, Any]]] = {}
    for r in runs:
        by_cut.setdefault(r["cut"], []).append(r)
    rows = [row_figures(by_cut[cut]) for cut in sorted(by_cut)]
    out: dict[str, Any] = {
        "world": world.name,
        "camera": settings.camera,
        "rotation": settings.rotation,
        "odometry": settings.odometry,
        "seeds": seeds,
        "route_source": settings.route.source,
        "route_length_m": settings.route.length_m,
        "route_margin_m": settings.route.margin_m,
        "route": [round(v, 3) for v in settings.route.odometry],
        "route_world": np.round(settings.route.world_xy, 3).tolist(),
        "goal_tolerance_m": mean_present([t["goal_tolerance_m"] for t in teach_rows]),
        "criterion": (f"SUCCESS without a collision within {settings.goal_tolerance:g} m of the route's start"
                      if settings.goal_tolerance is not None else
                      "SUCCESS without a collision within the robot's diameter or the viewframe spacing (the larger; "
                      f"mean {cell(mean_present([t['goal_tolerance_m'] for t in teach_rows]), 2)} m) of the route's "
                      "start"),
        "taught": len(teach_rows),
        "teach_failed": failed,
        "teach.viewframes": mean_present([t["viewframes"] for t in teach_rows]),
        "teach.height": mean_present([t["height"] for t in teach_rows]),
        "teach.bytes": mean_present([t["bytes"] for t in teach_rows]),
        "teach.path_length_m": mean_present([t["path_length_m"] for t in teach_rows]),
        "gap_filling": settings.gap_filling,
        "teach.shifted": mean_present([t.get("shifted") for t in teach_rows]),
        "teach.loop_closures": mean_present([t.get("loop_closures") for t in teach_rows]),
        **{f"teach.{k}": v for k, v in safety_totals(teach_rows).items()},
        "min_landmarks": sorted({t["min_landmarks"] for t in teach_rows}),
        "repeats": len(runs),
    }
    if rows:
        full = rows[0]
        out.update({f"full.{k}": full[k] for k in ("viewframes", "landmarks", "viewframe_error_m", "path_error_m",
                                                   "path_error_reached_m", "goal_error_m", "goal_reached",
                                                   "collisions", "safety_stops", "min_clearance_m")})
        out.update({f"repeats.{k}": v for k, v in safety_totals(runs).items()})
        out.update(memory_limits(rows))
    out["rows"] = rows
    out["teaches"] = teach_rows
    out["runs"] = sorted(runs, key=lambda r: (r["cut"], r["seed"]))
    if any(not r.get("map_as_expected", True) for r in runs):
        out["warning"] = "some repeats followed a map other than the height planned (see runs[].map_as_expected)"
    return out
