"""``bearings eval exploration``: explored floor against path length and time, four ways.

Four variants of the shipped ``explore`` mission, each over the same seeds (and with each
localisation the ``localisation`` option names, see below):

- ``method``: the mission's default, attractive power (eq. 1) among the borders about as close as
  the closest (``nearby_attraction``), frontier mode otherwise, the cameras watching interest edges;
- ``baseline``: the closest reachable border always (classic frontier exploration), cameras fixed
  straight ahead;
- ``fixed``: the method's goal selection with the cameras fixed straight ahead (so method vs fixed
  measures the gaze, fixed vs baseline the goal selection);
- ``eq1``: eq. 1 over all points, as the paper writes it, the cameras watching interest edges.

Two more run when named (``--option variants=method,gaze_before,...``: the variants to run, the
method always among them): ``gaze_before``, the method with the gaze's earlier rules (a watched
point dropped once its bearing passes 90 degrees, ``leave: pan_limit``; the head turned back to
straight ahead, ``turn_back: front``), so method vs gaze_before measures eq. 3 and eq. 4; and
``closest_edges``, the closest reachable border with the cameras watching interest edges (the
goal selection alone against the method's).

The measure (ground truth, evaluation only). The reference is the world's reachable floor
(:func:`drivers.sim.floor.reachable_floor`: where the robot's centre can go from the start). What
was *explored* is what the cameras actually saw: every stereo observation is in the run report as
a virtual range scan (``exploration.scans``: time, pan, tilt, free range per 1-degree bin), and is
drawn again here at the robot's TRUE pose at that time (interpolated in the report's ground-truth
trajectory), together with the disc the robot's body covered along that trajectory. That counts
floor the robot saw, wherever its own map put it; a scan whose range was cut short by a false
obstacle counts less, and floor its map shows at a drifted place does not count twice. Coverage
is the fraction of reachable cells so explored. For comparison, ``coverage_map`` places the
robot's own final map (odometry frame) at the true start pose (its error is the localisation's),
and ``map_on_obstacles_m2`` is how much of that map's explored floor lies on walls and furniture.

Figures per variant (means over seeds unless named otherwise): final ``coverage``, its minimum,
``ok`` (episodes that ended by themselves with coverage >= 0.95 and no collision), ``done``,
``collisions`` and ``safety_stops`` (summed over the runs), ``min_clearance_m`` (the smallest, when
the simulator reports it), ``path_length_m`` and ``sim_time_s``, coverage after 5, 10, 20 and 40 m of path
and after 60, 120 and 240 s, and the path length and time to reach 50, 80, 90 and 95 % (None when
not reached by some episode). Comparisons: ratios of the method's coverage after 10 and 20 m and
120 s, of its path and time to 90 and 95 % and of its path length to the three others' (below 1
for a path or a time: the method's is shorter).

Localisation (option ``localisation``): ``visual`` (the default) runs the mission as shipped, its pose
from the stereo pair's own features; ``ideal`` gives it the simulator's identified landmarks (the
oracle no robot has); ``visual,ideal`` runs both, the ideal columns named ``VARIANT/ideal``, so the
table shows what the oracle was worth (and ``VARIANT_visual_vs_ideal`` ratios of the map's area on
obstacles and of the path). The pose figures compare the localisation's pose (the report's
``exploration.localisation``: its final pose and a track of one row a second) with the truth at
the same time, the odometry frame placed at the true start: ``pose_error_m`` and
``heading_error_deg`` at the end, their maxima over the run, the position error after 60, 120 and
240 s, the final ``pose_sigma_m`` the localisation gave itself, and ``pose_ok`` (episodes that end
within 0.10 m and 2 degrees).

People (``--option people=N``, :mod:`experiments.eval.people`): N people drawn from the seed,
standing in the rooms or walking back and forth between two points of the floor the robot
reaches, none within 1 m of the start, are added to a copy of the world file
(``people/s<seed>/<world>.yaml`` in the results folder) that every variant of that seed runs in.
The reference floor stays the world's (people move: they hide no floor for good). The figures
record the people placed (``people.placed``, ``people.paths``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from drivers.sim.floor import FloorGrid, reachable_floor
from drivers.sim.world import load_world
from experiments.eval import EvalOptions
from experiments.eval import people as crowd
from experiments.eval.figures import interval_text, safety_figures, safety_totals, success_interval
from experiments.eval.trajectory import TrueTrajectory
from experiments.sweep import Episode, run_sweep
from experiments.sweep.table import read_report
from maps.exploration.codec import unpack_cells
from maps.exploration.grid import GridFrame
from maps.exploration.head import StereoHead
from maps.exploration.integrate import scan_cells
from perception.geometry import Pose2D, frame_to_parent, wrap_angle

DESCRIPTION = "explored floor against path length and time: the method, closest frontier, cameras fixed, eq. 1"
MISSION = "explore"
VARIANTS: dict[str, dict[str, str]] = {
    "method": {"strategy": "nearby_attraction", "gaze": "edges"},
    "baseline": {"strategy": "closest_frontier", "gaze": "fixed"},
    "fixed": {"strategy": "nearby_attraction", "gaze": "fixed"},
    "eq1": {"strategy": "attraction", "gaze": "edges"},
    "gaze_before": {"strategy": "nearby_attraction", "gaze": "edges", "leave": "pan_limit", "turn_back": "front"},
    "closest_edges": {"strategy": "closest_frontier", "gaze": "edges"},
}
DEFAULT_VARIANTS = ("method", "baseline", "fixed", "eq1")
DISTANCES = (5.0, 10.0, 20.0, 40.0)  # m of path: coverage reached by then
TIMES = (60.0, 120.0, 240.0)  # s
LEVELS = (0.5, 0.8, 0.9, 0.95)  # coverage: path length and time to reach it
RESOLUTION = 0.05  # m: the reference floor grid
GOAL = 0.95  # the criterion
OPTIONS = {
    "localisation": "how the robot localises: visual (the stereo pair's own features; default), ideal (the "
                    "simulator's identified landmarks, an oracle), or visual,ideal (both, side by side)",
    crowd.OPTION: crowd.HELP + " (in the rooms)",
    crowd.REST_OPTION: crowd.REST_HELP,
    "variants": f"the variants to run, comma-separated ({', '.join(VARIANTS)}; default "
                f"{','.join(DEFAULT_VARIANTS)}; the method always runs)",
}
LOCALISATIONS = {"visual": "stereo", "ideal": "landmarks"}  # -> the mission's localisation input (a camera)
POSE_GOAL = (0.10, 2.0)  # m, deg: the localisation's error at the end of a run


@dataclass(frozen=True)
class Settings:
    """The area's options, checked: people per seed, the variants to run (the method first) and the
    localisations to run each with."""

    people: crowd.Crowd = crowd.Crowd()  # people in the rooms
    variants: tuple[str, ...] = DEFAULT_VARIANTS
    localisations: tuple[str, ...] = ("visual",)  # LOCALISATIONS' names, each a set of columns


def check_world(world: str) -> FloorGrid:
    """The reachable floor of ``world``; ``ValueError`` when it has none to measure against."""
    floor = reachable_floor(load_world(world), resolution=RESOLUTION)
    if not floor.bounded:
        raise ValueError(f"world {world!r} is open (its reachable floor runs off the map): nothing to explore "
                         "to the end")
    return floor


def check_options(world: str, extra: Mapping[str, str]) -> Settings:
    """The options (``OPTIONS``) checked: the variants, the localisations (against the world's cameras)
    and the number of people; ``ValueError`` with the problem."""
    text = extra.get("variants")
    named = [n.strip() for n in text.split(",") if n.strip()] if text is not None else list(DEFAULT_VARIANTS)
    unknown = [n for n in named if n not in VARIANTS]
    if unknown or not named:
        raise ValueError(f"variants={text!r}: {', '.join(unknown) or 'none named'} "
                         f"(known: {', '.join(VARIANTS)})")
    variants = ("method", *dict.fromkeys(n for n in named if n != "method"))
    names = tuple(dict.fromkeys(n.strip() for n in extra.get("localisation", "visual").split(",")))
    unknown = [n for n in names if n not in LOCALISATIONS]
    if unknown or not names:
        raise ValueError(f"localisation must be visual, ideal or visual,ideal, got {extra.get('localisation')!r}")
    cameras = {spec.name for spec in load_world(world).cameras}
    for name in names:
        if LOCALISATIONS[name] not in cameras:
            raise ValueError(f"localisation {name} needs the camera {LOCALISATIONS[name]!r}, which world {world!r} "
                             f"does not have (cameras: {', '.join(sorted(cameras))})")
    return Settings(crowd.Crowd.from_options(extra), variants=variants, localisations=names)


def column(variant: str, localisation: str) -> str:
    """A table column: the variant, with ``/ideal`` for the ideal localisation."""
    return variant if localisation == "visual" else f"{variant}/{localisation}"


def episodes(world: str | Mapping[int, str], seeds: Sequence[int], max_time_s: float | None = None,
             variants: Sequence[str] = DEFAULT_VARIANTS, localisations: Sequence[str] = ("visual",)) -> list[Episode]:
    """The evaluation's runs: every variant named on every seed (in ``world``, or per seed ``world[seed]``),
    with every localisation."""
    where = world if isinstance(world, Mapping) else dict.fromkeys(seeds, world)
    return [Episode(MISSION, where[seed], seed, {**VARIANTS[name], "localisation": LOCALISATIONS[loc]}, max_time_s)
            for loc in localisations for name in variants for seed in seeds]


def seed_worlds(world: str, asked: crowd.Crowd, seeds: Sequence[int], floor: FloorGrid,
                folder: Path) -> tuple[dict[int, str], dict[int, list[crowd.Walker]]]:
    """Per seed, the world its runs go in (with the people ``asked`` for in the rooms: module docstring)
    and those people; the world itself when none were."""
    if not asked:
        return dict.fromkeys(seeds, world), {}
    loaded = load_world(world)
    start = [(loaded.start.x, loaded.start.y)]
    people = {seed: asked.in_rooms(loaded, floor, seed, keep_clear=start) for seed in seeds}
    worlds = {seed: str(crowd.world_with_people(world, folder / "people" / f"s{seed:04d}" / f"{Path(world).stem}.yaml",
                                                people[seed])) for seed in seeds}
    return worlds, people


def variant_of(inputs: dict[str, Any]) -> str:
    """The column (:func:`column`) of the variant whose inputs are exactly ``inputs`` besides the
    localisation."""
    given = {k: str(v) for k, v in inputs.items() if v is not None and k != "localisation"}
    camera = str(inputs.get("localisation", LOCALISATIONS["visual"]))
    localisation = next((k for k, v in LOCALISATIONS.items() if v == camera), None)
    for name, values in VARIANTS.items():
        if localisation is not None and given == values:
            return column(name, localisation)
    raise KeyError(f"no variant has the inputs {inputs}")


# ------------------------------------------------------------------------------------------------
# What was seen, at the true poses


def seen_floor(report: dict[str, Any], floor: FloorGrid, robot_radius: float) -> tuple[np.ndarray, np.ndarray]:
    """The cells (bool, the floor grid's) seen at the true poses, and the coverage curve as rows of
    (time s, true path length m, coverage of the reachable floor), in time order."""
    exploration, truth = report.get("exploration", {}), report["ground_truth"]
    trajectory = TrueTrajectory(truth)
    frame = GridFrame(floor.x0, floor.y0, floor.resolution, *floor.reachable.shape)
    seen = np.zeros(frame.shape, dtype=np.uint8)
    disc = int(round(robot_radius / floor.resolution))
    events: list[tuple[float, int, Any]] = [(float(t), 0, i) for i, t in enumerate(trajectory.t)]
    scans = exploration.get("scans", [])
    events += [(float(row[0]), 1, row) for row in scans]
    header = exploration.get("scan", {})
    head = StereoHead(tuple(header["ptu"]), tuple(header["camera"]), header["vertical_fov"],
                      header["horizontal_fov"]) if scans else StereoHead()
    edges = np.linspace(-head.horizontal_fov / 2.0, head.horizontal_fov / 2.0, int(header.get("bins", 1)) + 1)
    total = max(int(np.count_nonzero(floor.reachable)), 1)
    curve = []
    for t, kind, item in sorted(events, key=lambda e: (e[0], e[1])):
        if kind == 0:  # the robot's body covers the floor it stands on
            if disc == 0:
                continue
            rows, cols, _ = floor.cells_of(trajectory.xy[item])
            cv2.circle(seen, (int(cols[0]), int(rows[0])), disc, 1, -1)
        else:
            view = head.view(trajectory.interpolated(t), float(item[1]), float(item[2]))
            seen |= scan_cells(frame, view, edges, np.asarray(item[3:], dtype=np.float64)).astype(np.uint8)
            curve.append((t, trajectory.path_length(t), np.count_nonzero(seen.astype(bool) & floor.reachable) / total))
    coverage = np.count_nonzero(seen.astype(bool) & floor.reachable) / total
    curve.append((float(trajectory.t[-1]), float(trajectory.length[-1]), coverage))
    return seen.astype(bool), np.asarray(curve, dtype=np.float64).reshape(-1, 3)


def map_in_world(report: dict[str, Any]) -> np.ndarray:
    """The robot's own explored cells (N x 2 points, nine per cell) placed in the world at the true start pose."""
    m = report.get("exploration", {}).get("map")
    if not m:
        return np.zeros((0, 2))
    explored = unpack_cells(m["explored"], m["rows"], m["cols"])
    frame = GridFrame(m["x0"], m["y0"], m["resolution"], m["rows"], m["cols"])
    rows, cols = np.nonzero(explored)
    sub = (np.arange(3) - 1.0) / 3.0  # 3 x 3 points per cell: a rotated grid of the same size leaves no holes
    offsets = np.array([(a, b) for a in sub for b in sub]) * frame.resolution
    local = (frame.centre_of(rows, cols)[:, None, :] + offsets[None, :, :]).reshape(-1, 2)
    _, x0, y0, th0 = report["ground_truth"]["trajectory"][0]
    return frame_to_parent(Pose2D(x0, y0, th0), local)


def pose_errors(report: dict[str, Any]) -> dict[str, Any]:
    """The localisation's pose against the truth (module docstring); empty without a pose track."""
    located = report.get("exploration", {}).get("localisation", {})
    track = np.asarray(located.get("track", []), dtype=np.float64).reshape(-1, 6)
    final = located.get("final_pose")
    if not len(track) or not final:
        return {}
    trajectory = TrueTrajectory(report["ground_truth"])
    start = trajectory.at(0.0)

    def error(t: float, x: float, y: float, theta: float) -> tuple[float, float]:
        truth = trajectory.at(t)
        world = frame_to_parent(start, np.array([[x, y]]))[0]
        return (math.hypot(world[0] - truth.x, world[1] - truth.y),
                math.degrees(abs(wrap_angle(theta + start.theta - truth.theta))))

    over_time = np.array([error(*row[:4]) for row in track])
    end = error(final["t"], final["x"], final["y"], final["theta"])
    out: dict[str, Any] = {
        "pose_error_m": end[0], "heading_error_deg": end[1],
        "pose_error_max_m": float(max(over_time[:, 0].max(), end[0])),
        "heading_error_max_deg": float(max(over_time[:, 1].max(), end[1])),
        "pose_sigma_m": float(located.get("position_sigma_m", math.nan)),
        "pose_ok": bool(end[0] <= POSE_GOAL[0] and end[1] <= POSE_GOAL[1]),
    }
    for t in TIMES:
        before = np.flatnonzero(track[:, 0] <= t)
        out[f"pose_error_at_{t:g}s_m"] = float(over_time[before[-1], 0]) if len(before) else None
    return out


def _first(curve: np.ndarray, level: float, column: int) -> float | None:
    hit = np.flatnonzero(curve[:, 2] >= level)
    return float(curve[hit[0], column]) if len(hit) else None


def episode_figures(report: dict[str, Any] | None, floor: FloorGrid, robot_radius: float) -> dict[str, Any]:
    """Figures of one run (see the module docstring); an episode without a report has coverage 0."""
    if report is None or "ground_truth" not in report:
        return {"status": "ERROR", "coverage": 0.0, "ok": False, "done": False}
    truth = report["ground_truth"]
    seen, curve = seen_floor(report, floor, robot_radius)
    placed = map_in_world(report)
    rows, cols, inside = floor.cells_of(placed)
    cells = np.unique(rows[inside] * floor.free.shape[1] + cols[inside])
    on_obstacles = int(np.count_nonzero(~floor.free.ravel()[cells]))
    coverage = float(curve[-1, 2])
    done = report["status"] == "SUCCESS"
    out: dict[str, Any] = {
        "status": report["status"],
        "reason": report.get("reason", ""),
        "done": done,
        "coverage": coverage,
        "coverage_map": floor.coverage(placed) if len(placed) else 0.0,
        "map_on_obstacles_m2": on_obstacles * floor.resolution**2,
        **safety_figures(report),
        "path_length_m": float(truth["trajectory_length_m"]),
        "sim_time_s": float(report.get("sim_time_s", truth.get("sim_time_s", 0.0))),
        "odometry_drift_m": float(truth.get("odometry_drift_m", math.nan)),
        "wall_time_s": float(report.get("wall_time_s", math.nan)),
    }
    out["ok"] = bool(done and coverage >= GOAL and out["collisions"] == 0)
    out.update(pose_errors(report))
    for d in DISTANCES:
        out[f"coverage_at_{d:g}m"] = _coverage_when(curve, d, 1)
    for t in TIMES:
        out[f"coverage_at_{t:g}s"] = _coverage_when(curve, t, 0)
    for level in LEVELS:
        out[f"path_to_{level * 100:g}pct_m"] = _first(curve, level, 1)
        out[f"time_to_{level * 100:g}pct_s"] = _first(curve, level, 0)
    exploration = report.get("exploration", {})
    for key in ("goal_count", "mode_switch_count", "gaze_watching_fraction", "gaze_look_ahead_fraction", "stuck",
                "goals_abandoned"):
        if key in exploration:
            out[key] = exploration[key]
    return out


def _coverage_when(curve: np.ndarray, value: float, column: int) -> float:
    """Coverage when ``column`` (0: time, 1: path length) reached ``value``; the final coverage when the
    run ended before (an ended exploration explores no more)."""
    before = np.flatnonzero(curve[:, column] <= value)
    return float(curve[before[-1], 2]) if len(before) else 0.0


# ------------------------------------------------------------------------------------------------
# The evaluation


def _mean(values: Sequence[float | None]) -> float | None:
    """Mean of the values; None when any is None (a level some episode never reached)."""
    if not values or any(v is None for v in values):
        return None
    return float(np.mean([float(v) for v in values if v is not None]))


CURVE_FIGURES = (  # per-episode figures averaged over a variant's runs and shown in its table
    *(f"coverage_at_{d:g}m" for d in DISTANCES), *(f"coverage_at_{t:g}s" for t in TIMES),
    *(f"path_to_{v * 100:g}pct_m" for v in LEVELS), *(f"time_to_{v * 100:g}pct_s" for v in LEVELS),
    "goal_count", "mode_switch_count", "gaze_watching_fraction", "gaze_look_ahead_fraction",
)
POSE_FIGURES = ("pose_error_m", "heading_error_deg", "pose_error_max_m", "heading_error_max_deg",
                *(f"pose_error_at_{t:g}s_m" for t in TIMES), "pose_sigma_m")


def summarise_variant(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Per-variant figures over its episodes."""
    coverage = [r["coverage"] for r in runs]
    out: dict[str, Any] = {
        "episodes": len(runs),
        "ok": sum(bool(r["ok"]) for r in runs),
        "done": sum(bool(r["done"]) for r in runs),
        "coverage": float(np.mean(coverage)),
        "coverage_min": float(np.min(coverage)),
        "coverage_std": float(np.std(coverage, ddof=1)) if len(runs) > 1 else 0.0,
    }
    if any(r["status"] == "ERROR" for r in runs):
        out["errors"] = sum(r["status"] == "ERROR" for r in runs)
    good = [r for r in runs if r["status"] != "ERROR"]
    for key in ("coverage_map", "map_on_obstacles_m2", "path_length_m", "sim_time_s", *CURVE_FIGURES, *POSE_FIGURES):
        values = [r.get(key) for r in good]
        if good and any(key in r for r in good):
            out[key] = _mean(values)
    out.update(safety_totals(good))  # counts over the runs, not means; the smallest clearance
    if any("pose_ok" in r for r in good):
        out["pose_ok"] = sum(bool(r.get("pose_ok")) for r in good)
    return out


def _ratio(a: float | None, b: float | None) -> float | None:
    return None if a is None or b is None or b == 0 else a / b


def run(options: EvalOptions, *, resume: bool = False) -> dict[str, Any]:
    """Run the episodes through the sweep runner and compute the figures."""
    floor = options.checked[0] if options.checked else check_world(options.world)
    settings = options.checked[1] if options.checked and options.checked[1] is not None else check_options(
        options.world, options.extra)
    localisations = settings.localisations
    world = load_world(options.world)
    where, people = seed_worlds(options.world, settings.people, options.seeds, floor,
                                Path(options.results_dir).resolve())
    todo = episodes(where, options.seeds, options.max_time_s, settings.variants, localisations)
    rows = run_sweep(todo, executor=options.executor, results_dir=options.results_dir, timeout_s=options.timeout_s,
                     progress=options.progress, resume=resume)
    by_variant: dict[str, list[dict[str, Any]]] = {column(name, loc): [] for loc in localisations
                                                   for name in settings.variants}
    runs = []
    for row in rows:
        report = read_report(options.results_dir, row["id"])
        variant = variant_of({k[len("inputs."):]: v for k, v in row.items() if k.startswith("inputs.")})
        figures = episode_figures(report, floor, world.robot_radius)
        by_variant[variant].append(figures)
        runs.append({"variant": variant, "seed": row["seed"], **{k: v for k, v in figures.items() if k != "reason"}})
    out: dict[str, Any] = {
        "world": world.name,
        "seeds": len(options.seeds),
        "episodes": len(rows),
        "reachable_area_m2": floor.reachable_area,
        "criterion": f"ended by itself, coverage >= {GOAL:g}, no collision",
    }
    summary = {name: summarise_variant(v) for name, v in by_variant.items() if v}
    for name, figures in summary.items():
        out.update({f"{name}.{key}": value for key, value in figures.items()})
    for loc in localisations:
        method = summary.get(column("method", loc), {})
        for other in [n for n in settings.variants if n != "method" and column(n, loc) in summary]:
            versus, theirs = f"{column('method', loc)}_vs_{column(other, loc)}", summary[column(other, loc)]
            for key in ("coverage_at_10m", "coverage_at_20m", "coverage_at_120s", "path_to_90pct_m",
                        "path_to_95pct_m", "time_to_90pct_s", "time_to_95pct_s"):
                out[f"{versus}.{key}_ratio"] = _ratio(method.get(key), theirs.get(key))
            out[f"{versus}.path_length_ratio"] = _ratio(method.get("path_length_m"), theirs.get("path_length_m"))
    if {"visual", "ideal"} <= set(localisations):  # what the oracle was worth
        for name in [n for n in settings.variants if n in summary and column(n, "ideal") in summary]:
            visual, ideal = summary[name], summary[column(name, "ideal")]
            for key in ("map_on_obstacles_m2", "path_length_m"):
                out[f"{name}_visual_vs_ideal.{key.rsplit('_', 1)[0]}_ratio"] = _ratio(visual.get(key), ideal.get(key))
    out["runs"] = sorted(runs, key=lambda r: (r["variant"], r["seed"]))
    return {**out, **settings.people.figures(people)}


def format_table(figures: dict[str, Any]) -> str:
    """The comparison as a readable table (one column per variant)."""
    keys = ["ok", "done", "coverage", "coverage_min", "coverage_map", "map_on_obstacles_m2", "collisions",
            "safety_stops", "min_clearance_m", "path_length_m", "sim_time_s", *CURVE_FIGURES, "pose_ok", *POSE_FIGURES]
    names = [column(n, loc) for loc in LOCALISATIONS for n in VARIANTS if f"{column(n, loc)}.coverage" in figures]
    width = max(12, *(len(n) + 2 for n in names))
    lines = [f"exploration in {figures['world']}: {figures['seeds']} seed(s), reachable floor "
             f"{figures['reachable_area_m2']:.1f} m^2 ({figures['criterion']})",
             "figure".ljust(24) + "".join(n.rjust(width) for n in names)]
    for key in keys:
        cells = []
        for name in names:
            value = figures.get(f"{name}.{key}")
            text = "-" if value is None else f"{value:.3g}" if isinstance(value, float) else str(value)
            cells.append(text.rjust(width))
        lines.append(key.ljust(24) + "".join(cells))
        if key == "ok":  # what so few seeds say about the rate: its 95 % Wilson interval
            intervals = [success_interval(int(figures.get(f"{name}.ok") or 0), int(figures["seeds"])) for name in names]
            lines.append("ok rate, 95 %".ljust(24) + "".join(interval_text(i).rjust(width) for i in intervals))
    return "\n".join(lines + crowd.table_line(figures))
