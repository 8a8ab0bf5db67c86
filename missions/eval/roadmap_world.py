"""The roadmap missions in the simulator: target images from named poses, worlds with another start,
random start poses, and the ground-truth comparison (evaluation only: behaviours never see any of it).

Used by ``bearings eval roadmap`` (:mod:`missions.eval.roadmap`), the mission tests and the by-hand
measurement ``tests/missions/measure_roadmap.py``.

Target images are made with ``bearings sim snapshot`` itself (the command a user runs), one PNG
per named pose of the world, named after the pose::

    write_target_images("lab", ["door", "window"], tmp_path / "targets")

``world_with(world, out, start=..., poses=...)`` writes a copy of a world file with another start
pose and extra named poses (targets anywhere). :class:`TrueTrajectory` reads where the robot truly
was at a time from a report's ``ground_truth`` section (exact while it stood still, from the
section's ``stops``; interpolated between the decimated trajectory's rows otherwise).
"""

from __future__ import annotations

import contextlib
import io
import math
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from drivers.sim.floor import FloorGrid, reachable_floor
from drivers.sim.scene import Scene
from drivers.sim.world import World, load_world, shipped_worlds
from perception.geometry import Pose2D, wrap_angle

START_CLEARANCE = 0.45  # m: a random start is at least this far from any wall, box or pillar
MAX_DRAWS = 100_000  # random positions tried per start before giving up (a world with no room)


def world_path(world: str | Path) -> Path:
    """The file of a shipped world (by name) or a world file."""
    shipped = shipped_worlds()
    return Path(shipped[str(world)]) if str(world) in shipped else Path(world)


def world_with(world: str | Path, out: Path, *, start: Pose2D | None = None,
               poses: Mapping[str, Pose2D] | None = None) -> Path:
    """A copy of ``world`` at ``out`` with another start pose and/or more named poses."""
    data = yaml.safe_load(world_path(world).read_text())
    if start is not None:
        data["start"] = {"x": start.x, "y": start.y, "theta_deg": math.degrees(start.theta)}
    for name, pose in (poses or {}).items():
        data.setdefault("poses", {})[name] = {"x": pose.x, "y": pose.y, "theta_deg": math.degrees(pose.theta)}
    out.write_text(yaml.safe_dump(data, sort_keys=False))
    return out


def named_poses(world: str | Path | World) -> dict[str, Pose2D]:
    """The named poses of a world (world frame)."""
    loaded = world if isinstance(world, World) else load_world(str(world))
    return dict(loaded.poses)


def write_target_images(world: str | Path, names: Iterable[str], folder: Path, *, camera: str = "front",
                        seed: int = 0) -> Path:
    """One target image per named pose, rendered by ``bearings sim snapshot`` (lighting of ``seed``)
    into ``folder/NAME.png``; ``RuntimeError`` naming the pose when the command fails."""
    from missions.cli import main  # here: the command line imports the evaluations

    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()) as err:
            code = main(["sim", "snapshot", "--world", str(world), "--pose", name, "--camera", camera,
                         "--seed", str(seed), "-o", str(folder / f"{name}.png")])
        if code != 0:
            said = err.getvalue().strip().splitlines()
            raise RuntimeError(f"bearings sim snapshot failed for pose {name!r} of {world}"
                               + (f": {said[-1]}" if said else ""))
    return folder


def pose_error(estimate: Pose2D, truth: Pose2D) -> tuple[float, float]:
    """(position error m, heading error deg) of an estimate."""
    return estimate.distance_to(truth), abs(math.degrees(wrap_angle(estimate.theta - truth.theta)))


def target_errors(report: Mapping[str, Any], truth: Mapping[str, Pose2D], reference_truth: Pose2D
                  ) -> dict[str, tuple[float, float]]:
    """Errors of the targets of a learn_targets report: their estimated poses (reference frame)
    against the true poses expressed in the true reference frame. Targets without a true pose in
    ``truth`` are left out."""
    targets = report.get("roadmap", {}).get("targets", {})
    errors = {}
    for name, t in targets.items():
        if name in truth:
            estimate = Pose2D(t["x"], t["y"], math.radians(t["theta_deg"]))
            errors[name] = pose_error(estimate, truth[name].relative_to(reference_truth))
    return errors


class TrueTrajectory:
    """Where the robot truly was at any time of a run, from its report's ``ground_truth`` section.

    Within a stop (``ground_truth.stops``: the robot stood still) the pose is exact; elsewhere it is
    interpolated between the decimated ``trajectory`` rows (t, x, y, theta), the heading along the
    shorter way round. Before the first row or after the last, the first or last pose."""

    def __init__(self, ground_truth: Mapping[str, Any]) -> None:
        rows = np.asarray(ground_truth["trajectory"], dtype=np.float64).reshape(-1, 4)
        if not len(rows):
            raise ValueError("the ground truth has an empty trajectory")
        self.t, self.x, self.y = rows[:, 0], rows[:, 1], rows[:, 2]
        self.theta = np.unwrap(rows[:, 3])
        self.stops = np.asarray(ground_truth.get("stops", []), dtype=np.float64).reshape(-1, 5)

    def at(self, t: float) -> Pose2D:
        """The true pose at time ``t`` (s of simulated time)."""
        within = np.flatnonzero((self.stops[:, 0] <= t) & (t <= self.stops[:, 1]))
        if len(within):
            _, _, x, y, theta = self.stops[within[0]]
            return Pose2D(float(x), float(y), float(theta), stamp=t)
        theta = float(np.interp(t, self.t, self.theta))
        return Pose2D(float(np.interp(t, self.t, self.x)), float(np.interp(t, self.t, self.y)), wrap_angle(theta),
                      stamp=t)


def reachable_grid(world: World) -> FloorGrid:
    """Where the robot's centre can go from the world's start (``ValueError`` if the start is not free)."""
    return reachable_floor(world, resolution=0.05)


def usable_poses(world: World, grid: FloorGrid | None = None) -> dict[str, Pose2D]:
    """The named poses where the robot can stand and that it can reach from the start."""
    grid = grid or reachable_grid(world)
    names = sorted(world.poses)
    if not names:
        return {}
    rows, cols, inside = grid.cells_of(np.array([[world.poses[n].x, world.poses[n].y] for n in names]))
    return {n: world.poses[n] for n, r, c, ok in zip(names, rows, cols, inside, strict=True)
            if ok and grid.reachable[r, c]}


def random_starts(world: World, count: int, seed: int, *, clearance: float = START_CLEARANCE,
                  grid: FloorGrid | None = None) -> list[Pose2D]:
    """``count`` start poses drawn from ``seed`` alone: positions uniform in the world's bounds, at
    least ``clearance`` from any wall, box or pillar (the scene's exact distance) and reachable from
    the world's start (the floor grid), any heading. ``ValueError`` when no such place turns up."""
    grid = grid or reachable_grid(world)
    scene = Scene(world)
    xmin, ymin, xmax, ymax = world.bounds()
    rng = np.random.default_rng([seed, 0x60A1])
    starts: list[Pose2D] = []
    for _ in range(count):
        for _ in range(MAX_DRAWS):
            x, y = float(rng.uniform(xmin, xmax)), float(rng.uniform(ymin, ymax))
            row, col, inside = grid.cells_of(np.array([x, y]))
            if inside[0] and grid.reachable[row[0], col[0]] and scene.clearance(x, y) >= clearance:
                starts.append(Pose2D(x, y, float(rng.uniform(-math.pi, math.pi))))
                break
        else:
            raise ValueError(f"world {world.name!r} has no reachable place {clearance:g} m clear of every surface "
                             "to start from")
    return starts
