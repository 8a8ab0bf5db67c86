"""``bearings map info`` of a roadmap file: its targets, its edges with their sigmas, a drawing.

A roadmap (written by ``learn_targets``) holds the targets' poses relative to the reference pose
and the fused edges between them: rotate ``angle1``, drive ``distance``, rotate ``angle2``, with
the standard deviations ``sigma_x``, ``sigma_y`` of the end position in the start frame, whose sum
is the edge's cost in navigation (docs/roadmap.md).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from maps.roadmap import Roadmap


def roadmap_info(roadmap: Roadmap) -> dict[str, Any]:
    """The roadmap as ``bearings map info --json`` prints it (and as ``bearings plot`` draws it)."""
    edges = []
    for edge in roadmap.edges:
        covariance = edge.motion.pose_covariance()
        edges.append({"from": edge.source, "to": edge.target, "angle1_deg": round(math.degrees(edge.motion.angle1), 3),
                      "distance_m": round(edge.motion.distance, 4),
                      "angle2_deg": round(math.degrees(edge.motion.angle2), 3),
                      "sigma_x_m": round(math.sqrt(max(covariance[0, 0], 0.0)), 5),
                      "sigma_y_m": round(math.sqrt(max(covariance[1, 1], 0.0)), 5),
                      "cost": round(edge.motion.cost, 5)})
    return {
        "kind": "roadmap",
        "targets": {t.name: {"x": t.pose.x, "y": t.pose.y, "theta": t.pose.theta, "image": t.image}
                    for t in roadmap.targets},
        "edges": edges,
        "connected": roadmap.is_connected(),
        "components": len(roadmap.components()),
    }


def print_roadmap(file: str, info: dict[str, Any], as_json: bool) -> None:
    if as_json:
        print(json.dumps({"file": file, **info}, indent=2))
        return
    print(file)
    joined = "connected" if info["connected"] else f"{info['components']} components"
    print(f"  {len(info['targets'])} targets, {len(info['edges'])} edges, {joined}")
    for name, pose in info["targets"].items():
        image = f" ({pose['image']})" if pose["image"] else ""
        print(f"  target {name}: x {pose['x']:.3f} m, y {pose['y']:.3f} m, "
              f"theta {math.degrees(pose['theta']):.1f} deg{image}")
    for edge in info["edges"]:
        print(f"  edge {edge['from']} -> {edge['to']}: rotate {edge['angle1_deg']:.1f} deg, drive "
              f"{edge['distance_m']:.3f} m, rotate {edge['angle2_deg']:.1f} deg; sigma_x {edge['sigma_x_m']:.4f} m, "
              f"sigma_y {edge['sigma_y_m']:.4f} m (cost {edge['cost']:.4f})")


def draw_roadmap(info: dict[str, Any], output: Path) -> None:
    """The targets and edges as an image (the roadmap panel of ``bearings plot``)."""
    from missions.plot import draw_roadmap_figure

    draw_roadmap_figure(info, output)
