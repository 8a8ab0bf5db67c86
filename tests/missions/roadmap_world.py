"""Helpers for the roadmap missions in the simulator: target images from named poses, worlds with
another start, and the ground-truth comparison (evaluation only: behaviours never see any of it).

Target images are made with ``bearings sim snapshot`` itself (the command a user runs), one PNG
per named pose of the world, named after the pose::

    write_target_images("lab", ["door", "window"], tmp_path / "targets")

``world_with(world, start=..., poses=...)`` writes a copy of a world file with another start pose
(random unknown starts for ``goto_target``) and extra named poses (targets anywhere).
"""

from __future__ import annotations

import contextlib
import io
import math
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import yaml

from drivers.sim.world import shipped_worlds
from missions.cli import main
from perception.geometry import Pose2D, wrap_angle


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


def named_poses(world: str | Path) -> dict[str, Pose2D]:
    """The named poses of a world file (world frame)."""
    data = yaml.safe_load(world_path(world).read_text())
    return {name: Pose2D(p["x"], p["y"], math.radians(p.get("theta_deg", 0.0)))
            for name, p in (data.get("poses") or {}).items()}


def write_target_images(world: str | Path, names: Iterable[str], folder: Path, *, camera: str = "front") -> Path:
    """One target image per named pose, rendered by ``bearings sim snapshot`` into ``folder/NAME.png``."""
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        with contextlib.redirect_stdout(io.StringIO()):
            code = main(["sim", "snapshot", "--world", str(world), "--pose", name, "--camera", camera,
                         "-o", str(folder / f"{name}.png")])
        if code != 0:
            raise RuntimeError(f"bearings sim snapshot failed for pose {name!r} of {world}")
    return folder


def pose_error(estimate: Pose2D, truth: Pose2D) -> tuple[float, float]:
    """(position error m, heading error deg) of an estimate."""
    return estimate.distance_to(truth), abs(math.degrees(wrap_angle(estimate.theta - truth.theta)))


def target_errors(report: Mapping[str, Any], truth: Mapping[str, Pose2D], reference_truth: Pose2D
                  ) -> dict[str, tuple[float, float]]:
    """Errors of the targets of a learn_targets report: their estimated poses (reference frame)
    against the true poses expressed in the true reference frame."""
    targets = report.get("roadmap", {}).get("targets", {})
    errors = {}
    for name, t in targets.items():
        estimate = Pose2D(t["x"], t["y"], math.radians(t["theta_deg"]))
        errors[name] = pose_error(estimate, truth[name].relative_to(reference_truth))
    return errors
