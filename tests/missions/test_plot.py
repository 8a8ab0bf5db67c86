"""``bearings plot``: every part of a report becomes its labelled artist, in the right place."""

from __future__ import annotations

import base64
import json
import math

import matplotlib.pyplot as plt
import numpy as np
import pytest

from missions.cli import main
from missions.plot import draw_report


def _labels(ax) -> set[str]:
    artists = [*ax.lines, *ax.collections, *ax.patches, *ax.images]
    return {a.get_label() for a in artists if a.get_label() and not a.get_label().startswith("_")}


def _report() -> dict:
    explored = np.zeros((4, 6), bool)
    explored[1, 2] = True  # one cell: x in [0.2, 0.3), y in [0.1, 0.2) of the odometry frame
    path = [[0.0, 1.5, 1.5, math.pi / 2], [1.0, 1.5, 2.5, math.pi / 2], [2.0, 2.5, 2.5, 0.0]]
    return {
        "mission": "m", "status": "FAILURE", "reason": "Drive failed: stalled",
        "ground_truth": {"world": "lab", "collisions": 1, "trajectory": path, "landmarks": [[1, 0.0, 1.0, 1.5]],
                         "odometry_trajectory": [[0.0, 1.5, 1.5], [2.0, 2.4, 2.6]],
                         "collision_points": [[2.0, 2.5, 2.5]]},
        "safety": {"safety_stops": 1, "events": [{"t": 1.0, "action": "stop", "state": "stop"},
                                                 {"t": 1.5, "action": "slow", "state": "slow"}]},
        "ltmap": {"taught": [{"viewframe": 0, "time_s": 0.0}, {"viewframe": 1, "time_s": 1.0}],
                  "reached": [{"viewframe": 1, "time_s": 2.0, "rule": "delta_t"}]},
        "exploration": {"map": {"x0": 0.0, "y0": 0.0, "resolution": 0.1, "rows": 4, "cols": 6,
                                "explored": base64.b64encode(np.packbits(explored.ravel()).tobytes()).decode()}},
        "roadmap": {"targets": {"door": {"x": 0.0, "y": 0.0, "theta": 0.0},
                                "window": {"x": 2.0, "y": 1.0, "theta": 1.0}},
                    "edges": [{"from": "door", "to": "window"}]},
        "headline": [],
    }


def test_every_part_of_the_report_is_drawn():
    fig = draw_report(_report())
    world, roadmap = fig.axes
    assert {"walls", "pillars", "landmarks", "true path", "odometry path", "start", "end", "taught viewframes",
            "reached viewframes", "explored map", "collisions", "safety stops"} <= _labels(world)
    assert _labels(roadmap) == {"roadmap targets", "roadmap edges"}
    stops = next(c for c in world.collections if c.get_label() == "safety stops")
    assert stops.get_offsets().tolist() == [[1.5, 2.5]]  # the stop at t=1 s, on the true path; the slow-down is not one
    taught = next(c for c in world.collections if c.get_label() == "taught viewframes")
    assert taught.get_offsets().tolist() == [[1.5, 1.5], [1.5, 2.5]]
    plt.close(fig)


def test_the_explored_map_is_placed_at_the_true_start_pose():
    fig = draw_report(_report())
    image = next(i for i in fig.axes[0].images if i.get_label() == "explored map")
    to_world = image.get_transform() - fig.axes[0].transData  # the image's own transform (odometry -> world)
    x, y = to_world.transform((0.25, 0.15))  # the explored cell's centre in the odometry frame
    assert (x, y) == pytest.approx((1.5 - 0.15, 1.5 + 0.25))  # turned 90 degrees left, moved to the start
    plt.close(fig)


def test_a_report_without_simulation_draws_what_it_has():
    fig = draw_report({"mission": "m", "status": "SUCCESS", "reason": "", "ltmap": {"viewframes": 3}})
    assert fig.axes[0].get_title() == "odometry frame" and _labels(fig.axes[0]) == set()
    plt.close(fig)


def test_bearings_plot_writes_a_png_with_the_path_in_it(tmp_path):
    report, image = tmp_path / "r.json", tmp_path / "r.png"
    report.write_text(json.dumps(_report()))
    assert main(["plot", str(report), "-o", str(image)]) == 0
    pixels = plt.imread(image)
    green = (np.abs(pixels[..., 0] - 0x2C / 255) < 0.05) & (np.abs(pixels[..., 1] - 0xA0 / 255) < 0.05)
    assert green.sum() > 50  # the true path's colour is there


def test_bearings_plot_refuses_what_is_not_a_report(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("[1, 2")
    assert main(["plot", str(bad), "-o", str(tmp_path / "x.png")]) == 2
    assert "bad.json:1:" in capsys.readouterr().err


def test_map_info_reads_a_roadmap_with_its_sigmas_and_draws_it(tmp_path, capsys):
    from maps.roadmap import EdgeMotion, Roadmap
    from perception.geometry import Pose2D

    roadmap = (Roadmap().with_target("door", Pose2D(0.0, 0.0, 0.0), "door.png")
               .with_target("window", Pose2D(2.0, 1.0, 0.5)))
    covariance = np.diag([0.001**2, 0.02**2, 0.001**2])  # 2 cm along the driven line, 1 mrad on each turn
    roadmap.with_edge("door", "window", EdgeMotion(0.0, 2.0, 0.0, covariance)).save(tmp_path / "r.roadmap")
    image = tmp_path / "r.png"
    assert main(["map", "info", str(tmp_path / "r.roadmap"), "--json", "--plot", str(image)]) == 0
    info = json.loads(capsys.readouterr().out)
    assert list(info["targets"]) == ["door", "window"] and info["connected"]
    (edge,) = info["edges"]
    # by hand: driving 2 m along x, sigma_x is the distance's 2 cm, sigma_y the first turn's 1 mrad x 2 m
    assert (edge["sigma_x_m"], edge["sigma_y_m"], edge["cost"]) == (0.02, 0.002, 0.022)
    assert image.stat().st_size > 1000
