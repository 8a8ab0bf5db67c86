"""A world's cameras are budgeted at load (issue 22, item 2): their pixels times the renderer's
measured memory per pixel must stay within the budget, or the world is refused with the figure
(exit 2) before anything renders: one camera can no longer take the machine's memory."""

from __future__ import annotations

import pytest

from drivers.sim.world import load_world
from drivers.sim.world_file import MAX_RENDER_BYTES, RENDER_BYTES_PER_PIXEL
from maps.store import InputError
from missions.cli import main


def _cameras(*entries: str) -> str:
    return "cameras:\n" + "".join(f"  - {entry}\n" for entry in entries)


def pinhole(name: str, side: int, kind: str = "pinhole") -> str:
    c = side / 2 - 0.5
    return f"{{name: {name}, kind: {kind}, model: {{width: {side}, height: {side}, fx: {side}, fy: {side}, " \
           f"cx: {c}, cy: {c}}}}}"


def test_four_huge_cameras_are_refused_with_the_figure(world_file, capsys):
    path = world_file(_cameras(*(pinhole(f"c{i}", 8192) for i in range(4))))
    assert main(["run", "square", "--sim", str(path), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"{path}:2:3: cameras: rendering them would take about 193.3 GB (at most 4 GB: 720 bytes per pixel" in err
    assert "Traceback" not in err


def test_a_stereo_pair_counts_both_images_and_a_level_panorama_little(world_file):
    side = int((MAX_RENDER_BYTES / RENDER_BYTES_PER_PIXEL / 2) ** 0.5) + 1  # one pair just past the budget
    with pytest.raises(InputError, match="rendering them would take"):
        load_world(world_file(_cameras(pinhole("pair", side, "stereo"))))
    assert load_world(world_file(_cameras(pinhole("one", side)))).cameras  # half of it: within
    wide = "{name: p, kind: panorama, model: {width: 8192, height: 2048, deg_per_px: 0.0439453125, horizon_row: 900}}"
    assert load_world(world_file(_cameras(wide))).cameras  # 16.8 Mpx, ray-cast directly: about 0.5 GB


@pytest.mark.parametrize("world", ["lab", "corridor", "rooms", "outdoor", "unbalanced"])
def test_the_shipped_worlds_are_well_within_the_budget(world):
    load_world(world)
