"""By-hand measurement of the roadmap missions against the simulator's ground truth (issue 13's figures).

    python -m tests.missions.measure_roadmap --world lab --targets door,window,centre,corner \\
        --seed 0 --starts 10 --out out/roadmap

1. makes one target image per named pose with ``bearings sim snapshot`` (front camera);
2. runs ``learn_targets`` from the world's start; compares every target's estimated pose
   (reference frame, from the report) with its true pose expressed in the TRUE reference frame
   (the simulator's true robot pose when the reference image was taken, recorded here every
   tick: evaluation only, the behaviours never see it);
3. runs ``goto_target`` from ``--starts`` random start poses (``random_starts``: uniform in the
   world's bounds, at least 0.45 m from any surface, any heading; a new world file per start), each to a goal
   drawn among the targets, and compares the final true pose with the goal's true pose.

Prints one JSON object of figures (and writes it to OUT/figures.json). Not a test: minutes per
run. ``bearings eval roadmap`` runs the same missions through the sweep runner (any world, many seeds).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from drivers.sim.simulation import Simulation
from drivers.sim.world import load_world
from missions.eval.roadmap_world import (
    named_poses,
    pose_error,
    random_starts,
    target_errors,
    world_with,
    write_target_images,
)
from missions.loader import load_mission
from missions.runner import Runner, RunOptions
from perception.geometry import Pose2D

POSITION_OK, HEADING_OK = 0.15, 5.0  # the thresholds (m, deg)


def run_mission(name: str, world: str | Path, seed: int, inputs: dict[str, str], report: Path
                ) -> tuple[dict[str, Any], dict[float, Pose2D], Pose2D]:
    """One run in-process; (report, true pose by simulated time, final true pose)."""
    mission = load_mission(name, overrides=inputs)
    sim = Simulation(load_world(world), seed=seed)
    truth: dict[float, Pose2D] = {0.0: sim.true_pose()}

    def record(_runner: Runner) -> None:
        truth[round(sim.time, 6)] = sim.true_pose()

    result = Runner(mission, sim.robot, clock=sim.clock(), options=RunOptions(report_path=report, seed=seed),
                    observers=[sim], on_tick=record).run()
    return result.report, truth, sim.true_pose()


def at(truth: dict[float, Pose2D], stamp: float) -> Pose2D:
    return truth[min(truth, key=lambda t: abs(t - stamp))]


def learn(world: str, targets: list[str], seed: int, out: Path) -> dict[str, Any]:
    folder = write_target_images(world, targets, out / "targets")
    started = time.monotonic()
    report, truth, _ = run_mission("learn_targets", world, seed, {"targets": str(folder),
                                                                  "roadmap": str(out / "roadmap.map")},
                                   out / "learn.json")
    section = report.get("roadmap", {})
    figures: dict[str, Any] = {"status": report["status"], "reason": report["reason"],
                               "sim_time_s": report.get("sim_time_s"),
                               "wall_time_s": round(time.monotonic() - started, 1)}
    room = section.get("room")
    if room is not None:
        reference = at(truth, room["reference_stamp"])
        errors = target_errors(report, named_poses(world), reference)
        figures["targets"] = {n: {"position_error_m": round(d, 3), "heading_error_deg": round(a, 2)}
                              for n, (d, a) in errors.items()}
        figures["found"] = f"{len(errors)} of {len(targets)}"
        figures["within_0.15m_5deg"] = sum(d <= POSITION_OK and a <= HEADING_OK for d, a in errors.values())
    figures["edges"] = [f"{e['from']}-{e['to']}" for e in section.get("edges", [])]
    figures["connected"] = section.get("connected")
    figures["dropped"] = section.get("dropped", [])
    figures["search"] = section.get("search")
    return figures


def navigate(world: str, targets: list[str], seed: int, starts: int, out: Path) -> dict[str, Any]:
    rng = np.random.default_rng(seed)
    truth = named_poses(world)
    runs = []
    for k, start in enumerate(random_starts(load_world(world), starts, seed)):
        goal = str(rng.choice(targets))
        path = world_with(world, out / f"start{k}.yaml", start=start)
        started = time.monotonic()
        report, _, final = run_mission("goto_target", path, seed + k, {"roadmap": str(out / "roadmap.map"),
                                                                        "target": goal, "seed": str(k)},
                                       out / f"goto{k}.json")
        distance, heading = pose_error(final, truth[goal])
        navigation = report.get("roadmap", {}).get("navigation", {})
        runs.append({"start": [round(start.x, 2), round(start.y, 2), round(math.degrees(start.theta), 1)],
                     "goal": goal, "status": report["status"], "error_m": round(distance, 3),
                     "error_deg": round(heading, 2), "reached": distance <= POSITION_OK and heading <= HEADING_OK,
                     "visited": navigation.get("visited"), "random_moves": navigation.get("random_moves"),
                     "sim_time_s": report.get("sim_time_s"), "wall_time_s": round(time.monotonic() - started, 1),
                     "reason": report["reason"]})
        print(json.dumps(runs[-1]), flush=True)
    return {"reached": f"{sum(r['reached'] for r in runs)} of {len(runs)}", "runs": runs}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--world", default="lab")
    parser.add_argument("--targets", default="door,window,centre,corner", help="named poses of the world")
    parser.add_argument("--pose", action="append", default=[], metavar="NAME=X,Y,DEG",
                        help="an extra named pose (a target anywhere); repeat for more")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--starts", type=int, default=10)
    parser.add_argument("--out", type=Path, default=Path("out/roadmap"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    targets = args.targets.split(",")
    world = args.world
    if args.pose:
        extra = {}
        for text in args.pose:
            name, _, numbers = text.partition("=")
            x, y, degrees = (float(v) for v in numbers.split(","))
            extra[name] = Pose2D(x, y, math.radians(degrees))
        world = str(world_with(world, args.out / "world.yaml", poses=extra))
    figures: dict[str, Any] = {"world": args.world, "seed": args.seed, "targets": targets,
                               "learn": learn(world, targets, args.seed, args.out)}
    print(json.dumps(figures["learn"]), flush=True)
    if args.starts and (args.out / "roadmap.map").is_file():  # a roadmap not connected is measured too
        figures["goto"] = navigate(world, targets, args.seed, args.starts, args.out)
    (args.out / "figures.json").write_text(json.dumps(figures, indent=1))
    summary = {k: v for k, v in figures.items() if k != "goto"}
    print(json.dumps(summary | {"goto": figures.get("goto", {}).get("reached")}))


if __name__ == "__main__":
    main()
