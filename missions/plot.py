"""A picture of a run from its report (``bearings plot REPORT.json -o run.png``), without a viewer.

Everything drawn comes from the report (and, for the floor plan, the world it names):

- the world from above, when the run was simulated: walls, pillars and landmarks of the world
  ``ground_truth.world`` (a shipped name or a world file that still exists);
- the true path (``ground_truth.trajectory``) and where odometry believed the robot was
  (``ground_truth.odometry_trajectory``), start and end marked;
- the LT-map's viewframes: where each was taught (``ltmap.taught``) and reached on the repeat
  (``ltmap.reached``), placed on the true path at the time they happened;
- the exploration map (``exploration.map``: the explored cells, in the odometry frame, put in the
  world at the true start pose);
- collisions (``ground_truth.collision_points``, when the simulator lists them; their count is in
  the title either way) and the collision monitor's stops (``safety.events`` whose action is a
  stop, placed on the true path at their time);
- the roadmap's targets and edges (``roadmap``), in a panel of their own: they live in the
  roadmap's reference frame, not the world's.

Each kind of thing drawn is one labelled artist (its ``label`` is the name above), so a test
can ask what a figure holds. matplotlib is the ``plot`` extra: ``pip install 'bearings[plot]'``.
"""

from __future__ import annotations

import base64
import math
import textwrap
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from missions.summary import summary_line

TRUE_COLOUR, ODOMETRY_COLOUR, WALL_COLOUR = "#2ca02c", "#ff7f0e", "#555555"


def require_matplotlib() -> Any:
    """pyplot on the Agg backend, or ImportError saying how to install it."""
    try:
        import matplotlib
    except ImportError:
        raise ImportError("bearings plot needs matplotlib: pip install 'bearings[plot]'") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def draw_report(report: Mapping[str, Any]) -> Any:
    """The matplotlib figure of a run report (see the module docstring for what it shows)."""
    plt = require_matplotlib()
    roadmap = _section(report, "roadmap")
    panels = 2 if roadmap.get("targets") else 1
    fig, axes = plt.subplots(1, panels, figsize=(7 * panels, 6.5), dpi=100, squeeze=False)
    ax = axes[0][0]
    truth = _section(report, "ground_truth")
    path = np.asarray(truth.get("trajectory") or np.zeros((0, 4)), dtype=float).reshape(-1, 4)
    _floor_plan(ax, truth)
    _exploration(ax, report.get("exploration"), path)
    _paths(ax, truth, path)
    _viewframes(ax, report.get("ltmap"), path)
    _incidents(ax, truth, report.get("safety"), path)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.25)
    ax.set_title("world" if truth else "odometry frame")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize=8)
    if panels == 2:
        _roadmap(axes[0][1], roadmap)
    said = summary_line(report)
    title = f"{report.get('mission', '?')}: {report.get('status', '?')} ({report.get('reason', '')})"
    fig.suptitle("\n".join([title, *textwrap.wrap(said, 50 + 60 * panels)]), fontsize=9)
    fig.tight_layout()
    return fig


def save_plot(report: Mapping[str, Any], output: str | Path) -> Path:
    """Draw ``report`` and write it as an image (PNG, or what the suffix says)."""
    plt = require_matplotlib()
    fig = draw_report(report)
    target = Path(output)
    fig.savefig(target)
    plt.close(fig)
    return target


# -- the parts -------------------------------------------------------------------------------------
def _section(report: Mapping[str, Any], name: str) -> Mapping[str, Any]:
    section = report.get(name)
    return section if isinstance(section, Mapping) else {}


def _floor_plan(ax: Any, truth: Mapping[str, Any]) -> None:
    world = _world(truth.get("world"))
    if world is not None:
        strips = [np.asarray(wall.points, dtype=float) for wall in world.walls]
        for index, strip in enumerate(strips):
            ax.plot(strip[:, 0], strip[:, 1], color=WALL_COLOUR, lw=2, label="walls" if index == 0 else None)
        for index, pillar in enumerate(world.pillars):
            ax.add_patch(_circle(pillar.x, pillar.y, pillar.radius, "pillars" if index == 0 else None))
    landmarks = np.asarray(truth.get("landmarks") or np.zeros((0, 4)), dtype=float).reshape(-1, 4)
    if len(landmarks):
        ax.scatter(landmarks[:, 1], landmarks[:, 2], s=10, marker="^", color="#1f77b4", label="landmarks")


def _world(name: Any) -> Any:
    """The world a report names, or None when it cannot be loaded any more (a moved file)."""
    if not isinstance(name, str) or not name:
        return None
    from drivers.sim.world import load_world

    try:
        return load_world(name)
    except Exception:  # noqa: BLE001 - a picture without the floor plan is still a picture
        return None


def _circle(x: float, y: float, radius: float, label: str | None) -> Any:
    from matplotlib.patches import Circle

    return Circle((x, y), radius, fill=False, color=WALL_COLOUR, lw=1.5, label=label)


def _paths(ax: Any, truth: Mapping[str, Any], path: np.ndarray) -> None:
    odometry = np.asarray(truth.get("odometry_trajectory") or np.zeros((0, 3)), dtype=float).reshape(-1, 3)
    if len(odometry):
        ax.plot(odometry[:, 1], odometry[:, 2], "--", color=ODOMETRY_COLOUR, lw=1.2, label="odometry path")
    if len(path):
        ax.plot(path[:, 1], path[:, 2], color=TRUE_COLOUR, lw=1.8, label="true path")
        ax.plot(path[0, 1], path[0, 2], "o", color=TRUE_COLOUR, ms=8, label="start")
        ax.plot(path[-1, 1], path[-1, 2], "s", color=TRUE_COLOUR, ms=8, label="end")


def _viewframes(ax: Any, ltmap: Any, path: np.ndarray) -> None:
    if not isinstance(ltmap, Mapping) or not len(path):
        return
    for key, marker, colour, label in (("taught", "D", "#e6b800", "taught viewframes"),
                                       ("reached", "x", "#009e73", "reached viewframes")):
        times = [entry.get("time_s") for entry in ltmap.get(key) or () if isinstance(entry, Mapping)]
        xy = _at_times(path, [t for t in times if isinstance(t, (int, float))])
        if len(xy):
            ax.scatter(xy[:, 0], xy[:, 1], marker=marker, s=28, color=colour, label=label, zorder=3)


def _exploration(ax: Any, exploration: Any, path: np.ndarray) -> None:
    grid = exploration.get("map") if isinstance(exploration, Mapping) else None
    if not isinstance(grid, Mapping) or "explored" not in grid:
        return
    rows, cols, resolution = int(grid["rows"]), int(grid["cols"]), float(grid["resolution"])
    bits = np.unpackbits(np.frombuffer(base64.b64decode(grid["explored"]), dtype=np.uint8))
    explored = bits[: rows * cols].reshape(rows, cols).astype(float)
    image = np.ma.masked_equal(explored, 0.0)
    extent = (grid["x0"], grid["x0"] + cols * resolution, grid["y0"], grid["y0"] + rows * resolution)
    shown = ax.imshow(image, origin="lower", extent=extent, cmap="Blues", vmin=0.0, vmax=2.5, alpha=0.6,
                      interpolation="nearest", label="explored map")
    if len(path):  # the map is in the odometry frame, whose origin is the true start pose
        from matplotlib.transforms import Affine2D

        x, y, theta = path[0, 1], path[0, 2], path[0, 3]
        shown.set_transform(Affine2D().rotate(theta).translate(x, y) + ax.transData)


def _incidents(ax: Any, truth: Mapping[str, Any], safety: Any, path: np.ndarray) -> None:
    points = np.asarray(truth.get("collision_points") or np.zeros((0, 3)), dtype=float).reshape(-1, 3)
    if len(points):
        ax.scatter(points[:, 1], points[:, 2], marker="X", s=90, color="#d62728", label="collisions", zorder=4)
    events = safety.get("events") if isinstance(safety, Mapping) else None
    stops = [event.get("t") for event in events or () if isinstance(event, Mapping)
             and "stop" in f"{event.get('action', '')} {event.get('state', '')}"]
    xy = _at_times(path, [t for t in stops if isinstance(t, (int, float))])
    if len(xy):
        ax.scatter(xy[:, 0], xy[:, 1], marker="o", s=70, facecolors="none", edgecolors="#d62728", lw=2,
                   label="safety stops", zorder=4)


def _roadmap(ax: Any, roadmap: Mapping[str, Any]) -> None:
    targets = {name: pose for name, pose in (roadmap.get("targets") or {}).items() if isinstance(pose, Mapping)}
    for index, edge in enumerate(roadmap.get("edges") or ()):
        a, b = targets.get(edge.get("from")), targets.get(edge.get("to"))
        if a is not None and b is not None:
            ax.annotate("", xy=(b["x"], b["y"]), xytext=(a["x"], a["y"]),
                        arrowprops={"arrowstyle": "->", "color": "#7f7f7f", "lw": 1.2})
            ax.plot([a["x"], b["x"]], [a["y"], b["y"]], color="#7f7f7f", lw=0.8,
                    label="roadmap edges" if index == 0 else None)
    if targets:
        xs = [pose["x"] for pose in targets.values()]
        ys = [pose["y"] for pose in targets.values()]
        ax.scatter(xs, ys, s=60, color="#9467bd", label="roadmap targets", zorder=3)
        for name, pose in targets.items():
            ax.annotate(name, (pose["x"], pose["y"]), textcoords="offset points", xytext=(5, 5), fontsize=8)
            theta = pose.get("theta")
            if isinstance(theta, (int, float)):
                ax.arrow(pose["x"], pose["y"], 0.3 * math.cos(theta), 0.3 * math.sin(theta), width=0.01,
                         color="#9467bd")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.25)
    ax.set_title("roadmap (reference frame)")
    ax.legend(loc="best", fontsize=8)


def _at_times(path: np.ndarray, times: Sequence[float]) -> np.ndarray:
    """Positions on the true path (t, x, y, theta rows) at the given times."""
    if not len(path) or not times:
        return np.zeros((0, 2))
    t = np.asarray(times, dtype=float)
    return np.column_stack([np.interp(t, path[:, 0], path[:, 1]), np.interp(t, path[:, 0], path[:, 2])])


def draw_roadmap_figure(roadmap: Mapping[str, Any], output: str | Path) -> Path:
    """A roadmap's targets and edges alone (``bearings map info FILE --plot F.png``)."""
    plt = require_matplotlib()
    fig, ax = plt.subplots(figsize=(7, 6.5), dpi=100)
    _roadmap(ax, roadmap)
    fig.tight_layout()
    target = Path(output)
    fig.savefig(target)
    plt.close(fig)
    return target
