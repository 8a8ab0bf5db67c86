"""World files: the shipped worlds load, and malformed files give every error with file:line:col."""

from __future__ import annotations

import math
import re

import pytest

from drivers.sim.simulation import Simulation
from drivers.sim.world import load_world, shipped_worlds
from maps.store import InputError


def test_four_worlds_are_shipped_and_load_by_name() -> None:
    assert {"lab", "corridor", "outdoor", "unbalanced"} <= set(shipped_worlds())
    lab = load_world("lab")
    x0, y0, x1, y1 = lab.bounds()
    assert (x1 - x0, y1 - y0) == pytest.approx((8.0, 6.0), abs=0.01)
    assert lab.ceiling == pytest.approx(2.6)
    assert len(lab.pillars) >= 2 and len(lab.walls) >= 5 and len(lab.landmarks) >= 20
    outdoor = load_world("outdoor")
    assert outdoor.ceiling is None
    assert max(math.hypot(lm.x - 30, lm.y - 20) for lm in outdoor.landmarks) > 200  # on the horizon


def test_the_office_has_people_walking_and_every_frame_shows_them_where_they_are() -> None:
    sim = Simulation.load("office", seed=0)
    assert len(sim.world.people) == 3 and all(len(p.path) >= 2 for p in sim.world.people)
    camera = sim.robot.cameras["panorama"]
    first = camera.grab()
    before = sim.people_xy()
    for _ in range(50):  # 5 s, the robot standing still: only the people move
        sim.step(0.1)
    assert (sim.people_xy() != before).any(axis=1).all()
    later = camera.grab()
    assert first is not None and later is not None and not (first.image == later.image).all()
    assert sim.robot.ranges is not None and sim.ground_truth_report()["collisions"] == 0


def test_empty_world_is_a_plane_with_the_default_cameras() -> None:
    for name in (None, "empty"):
        sim = Simulation.load(name)
        assert sim.scene.n_surfaces == 0 and len(sim.world.landmarks) == 0
        assert set(sim.robot.cameras) == {"panorama", "omni", "landmarks", "front", "stereo"}
        frame = sim.robot.cameras["panorama"].grab()
        assert frame is not None and frame.image.shape == (172, 720)


def test_a_user_file_loads_by_path(world_file) -> None:
    path = world_file(
        """
        name: box
        start: {x: 1, y: 2, theta_deg: 90}
        poses: {goal: {x: 3, y: 1}}
        walls: [{points: [[0, 0], [4, 0], [4, 4]], height: 2}]
        cameras: [{name: eye, kind: bearings}]
        """
    )
    sim = Simulation.load(path)
    assert sim.name == "box"
    assert sim.true_pose().theta == pytest.approx(math.pi / 2)
    assert sim.world.poses["goal"].x == 3
    assert list(sim.robot.cameras) == ["eye"]


def _errors(exc: pytest.ExceptionInfo[InputError]) -> list[tuple[int, str]]:
    return [(d.line, d.message) for d in exc.value.diagnostics]


def test_every_error_of_a_file_is_reported_with_its_line_and_column(world_file) -> None:
    path = world_file(
        """\
        name: broken
        walls:
          - points: [[0, 0], [1]]
            height: -2
        pillars:
          - {center: [1, 1], radius: 0.2}
        landmarks:
          - {id: 1, position: [1, 2]}
          - {id: 1, position: [1, 2, 3]}
        cameras:
          - {name: cam, kind: fisheye}
          - {name: pin, kind: pinhole, model: {fx: -1}}
        start: {x: 1, y: two}
        ceilling: 3
        """
    )
    with pytest.raises(InputError) as exc:
        load_world(path)
    found = _errors(exc)
    text = str(exc.value)
    expected = {
        3: "walls[0].points[1] must have at least 2 items, got 1",
        4: "walls[0].height must be > 0 m, got -2",
        6: "pillars[0] needs 'height'",
        8: "landmarks[0].position must have at least 3 items, got 2",
        9: "duplicate landmark id 1",
        11: "cameras[0].kind must be one of 'bearings', 'panorama', 'catadioptric', 'pinhole' or 'stereo', got "
            "'fisheye'",
        12: "cameras[1]: focal lengths must be positive",
        13: "start.y expects a finite number in m, got 'two'",
        14: "unknown key 'ceilling'",
    }
    for line, fragment in expected.items():
        assert any(ln == line and fragment in msg for ln, msg in found), (line, fragment, found)
    assert "did you mean 'ceiling'" in text
    assert all(re.match(rf"{re.escape(str(path))}:\d+:\d+: ", str(d)) for d in exc.value.diagnostics)


@pytest.mark.parametrize(
    ("text", "line", "fragment"),
    [
        ("walls: {points: [[0, 0], [1, 0]]}\n", 1, "walls: input should be a valid list"),
        ("walls:\n  - {points: [[0, 0], [0, 0]], height: 1}\n", 2, "zero-length wall"),
        ("boxes:\n  - {center: [0, 0], size: [1, 0], height: 1}\n", 2, "box size must be positive"),
        ("ptu: {tilt_limits_deg: [30, -40]}\n", 1, "the first limit must be below the second"),
        ("cameras:\n  - {name: a, kind: panorama, mount: wrist}\n", 2, "mount must be one of 'base' or 'ptu'"),
        ("cameras:\n  - {name: a, kind: panorama, noise_deg: 1}\n", 2, "only applies to a bearings sensor"),
        ("ceiling: 0.5\n", 1, "is not below the ceiling"),
        ("format: 7\n", 1, "format must be one of 1, got 7"),
        ("- just a list\n", 1, "a world file must be a mapping"),
        ("walls: [\n", 2, "malformed YAML"),
    ],
)
def test_malformed_world_files(world_file, text: str, line: int, fragment: str) -> None:
    with pytest.raises(InputError) as exc:
        load_world(world_file(text))
    assert any(ln == line and fragment in msg for ln, msg in _errors(exc)), _errors(exc)


def test_unknown_world_name_lists_the_shipped_ones() -> None:
    with pytest.raises(InputError) as exc:
        Simulation.load("nowhere")
    assert "lab" in str(exc.value) and "corridor" in str(exc.value)
