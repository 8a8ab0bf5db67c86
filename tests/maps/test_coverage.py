"""Coverage grid and score: hand-computed cases, the vectorised score against covering, a figure."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maps.coverage import (
    CoverageGrid,
    SensorRange,
    choose_next,
    count_fragments,
    coverage_grid,
    image_headings,
    newly_covered,
    reachable_positions,
    sensor_range,
)
from maps.room import FreeGrid, RoomEstimate

RECT = np.array([[0.0, 0.0], [8.0, 0.0], [8.0, 6.0], [0.0, 6.0]])


def test_each_image_serves_six_bins_and_a_position_serves_all_once():
    grid = CoverageGrid.empty(np.ones((1, 1), bool), 0)
    assert list(np.flatnonzero(grid.sector_bins(0.0))) == [0, 1, 2, 69, 70, 71]  # centres +-2.5, 7.5, 12.5 deg
    served = sum(grid.sector_bins(h).astype(int) for h in image_headings())
    assert (served == 1).all()


def test_new_coverage_by_hand_3x3():
    """Reach 1 cell (a plus shape): centre 5 cells, edge 4, corner 3, each at 72 headings."""
    grid = CoverageGrid.empty(np.ones((3, 3), bool), 1)
    expected = 72 * np.array([[3, 4, 3], [4, 5, 4], [3, 4, 3]])
    np.testing.assert_array_equal(newly_covered(grid), expected)
    # one image at the centre, heading 0: bins 69-71 and 0-2 of the 5 plus cells are covered
    after = grid.cover(0.1, 0.1, headings=[0.0])
    assert after.covered.sum() == 5 * 6
    np.testing.assert_array_equal(newly_covered(after), [[216 - 12, 288 - 12, 216 - 12],
                                                         [288 - 12, 360 - 30, 288 - 12],
                                                         [216 - 12, 288 - 12, 216 - 12]])


def test_cell_positions_one_by_one_or_as_arrays():
    grid = CoverageGrid.empty(np.ones((3, 2), bool), 1, cell=0.1, origin=(-0.5, 2.0))
    assert grid.position(2, 1) == pytest.approx((-0.3, 2.1))
    x, y = grid.position(*np.indices(grid.valid.shape))  # every cell at once, as the same sums
    assert x.shape == y.shape == (3, 2)
    assert all((x[i, j], y[i, j]) == grid.position(i, j) for i in range(3) for j in range(2))


def test_invalid_positions_are_neither_covered_nor_candidates():
    valid = np.ones((3, 3), bool)
    valid[1, 1] = False
    grid = CoverageGrid.empty(valid, 1)
    new = newly_covered(grid)
    assert new[1, 1] == 0 and new[0, 1] == 72 * 3  # (0,1) reaches (0,0), (0,2) and itself
    assert not grid.cover(0.1, 0.1).covered[1, 1].any()


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_vectorised_score_equals_covering_each_candidate(seed):
    rng = np.random.default_rng(seed)
    valid = rng.random((7, 5)) > 0.2
    grid = CoverageGrid(valid, rng.integers(0, 4, (7, 5, 72)), rng.random((7, 5, 72)) > 0.7)
    new = newly_covered(grid)
    before = grid.covered.sum()
    for ix, iy in np.argwhere(valid):
        assert new[ix, iy] == grid.cover(*grid.position(ix, iy)).covered.sum() - before


def test_sensor_range_is_where_covering_reaches_the_target():
    """For images taken at bin-centre headings the two views of matching agree exactly."""
    rng = np.random.default_rng(3)
    grid = CoverageGrid(np.ones((6, 6), bool), rng.integers(0, 3, (6, 6, 72)), np.zeros((6, 6, 72), bool))
    target = (0.2, 0.3, math.radians(102.5))  # cell (2, 3), centre of heading bin 20
    ranged = sensor_range(grid, *target)
    assert list(np.flatnonzero(ranged[2, 3])) == [18, 19, 20, 21, 22]  # centres within 15 deg
    for ix, iy in np.ndindex(6, 6):
        for heading in np.radians([82.5, 87.5, 92.5, 107.5, 117.5, 132.5]):
            covered = grid.cover(*grid.position(ix, iy), headings=[heading]).covered[2, 3, 20]
            in_range = ranged[ix, iy, int(heading // math.radians(5))]
            assert covered == in_range


def test_fragments_by_hand_and_across_the_heading_seam():
    mask = np.zeros((4, 1, 72), bool)
    mask[0, 0, :] = True
    mask[2:, 0, 10:20] = True
    assert count_fragments(mask) == 2
    seam = np.zeros((1, 1, 72), bool)
    seam[0, 0, [0, 1, 70, 71]] = True  # bins 71 and 0 are neighbours
    assert count_fragments(seam) == 1
    assert count_fragments(np.zeros((2, 2, 72), bool)) == 0


def _corridor() -> CoverageGrid:
    """1 x 8 corridor, reach 1 cell, except 0 at both ends (hand-computed in the test below)."""
    reach = np.ones((8, 1, 72), int)
    reach[[0, 7]] = 0
    return CoverageGrid(np.ones((8, 1), bool), reach, np.zeros((8, 1, 72), bool))


def test_fragmentation_penalty_changes_the_choice_by_hand():
    grid = _corridor()
    np.testing.assert_array_equal(newly_covered(grid)[:, 0], 72 * np.array([2, 2, 3, 3, 3, 3, 2, 2]))
    greedy = choose_next(grid, fragment_cost=0.0)
    assert greedy.index == (2, 0) and greedy.new == 216 and greedy.evaluated == 1
    # from cells 2-5 what stays uncovered splits in two (+1 fragment: 216 - 100 = 116); from
    # cell 0 it stays whole (144); cell 1 (144) cannot beat that and is not evaluated
    careful = choose_next(grid, fragment_cost=100.0)
    assert careful.index == (0, 0) and careful.score == 144 and careful.fragments_added == 0
    assert careful.evaluated == 5


def test_nothing_left_to_cover_gives_no_choice():
    grid = CoverageGrid.empty(np.ones((2, 2), bool), 1)
    assert choose_next(grid.cover(0.0, 0.0).cover(0.1, 0.1)) is None
    assert choose_next(grid, candidates=np.zeros((2, 2), bool)) is None


def test_room_grid_reach_from_the_distance_to_the_scene():
    room = RoomEstimate.from_polygon(RECT)
    grid = coverage_grid(room, room.free_grid(0.05), robot_radius=0.25, sensor=SensorRange(0.35, 0.2, 1.5))
    at = grid.index(1.0, 3.0)
    assert grid.valid[at]
    assert grid.reach[at][36] == 3  # facing the wall 1.0 m away (bin centre 182.5 deg): 0.35 m
    assert grid.reach[at][0] == 15  # 7 m of room ahead: capped at 1.5 m
    assert not grid.valid[grid.index(0.2, 3.0)]  # a 0.25 m robot cannot stand 0.2 m from a wall


def test_candidates_beyond_a_dividing_wall_are_unreachable():
    room = RoomEstimate.from_polygon(np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]]))
    whole = room.free_grid(0.05)
    wall = np.abs(whole.centres()[..., 0] - 2.0) < 0.1
    free = FreeGrid(whole.free & ~wall, whole.cell, whole.origin)
    grid = coverage_grid(room, free, robot_radius=0.25)
    here = reachable_positions(grid, free, 0.25, 0.6, 0.6)
    xs = grid.origin[0] + np.argwhere(here)[:, 0] * grid.cell
    assert here.any() and xs.max() < 2.0 and (grid.valid & ~here).any()
    choice = choose_next(grid, candidates=here)
    assert choice.x < 2.0
    assert not reachable_positions(grid, free, 0.25, 2.0, 1.5).any()  # standing in the wall


def test_choice_sequence_covers_the_lab_sized_room(record_property):
    """8 x 6 m room: the figure is the time to score every candidate (printed, not asserted)."""
    room = RoomEstimate.from_polygon(RECT)
    grid = coverage_grid(room, room.free_grid(0.05), robot_radius=0.25)
    assert grid.valid.shape == (81, 61) and grid.heading_bins == 72
    start = time.perf_counter()
    new = newly_covered(grid)
    score_all = time.perf_counter() - start
    start = time.perf_counter()
    choice = choose_next(grid)
    choose = time.perf_counter() - start
    assert (choice.x, choice.y) == pytest.approx((4.0, 3.0))  # the centre sees the most
    assert choice.new == new.max()
    fractions = []
    for _ in range(8):
        grid = grid.cover(choice.x, choice.y)
        fractions.append(grid.fraction_covered)
        choice = choose_next(grid)
    assert all(b > a for a, b in zip(fractions, fractions[1:], strict=False))
    record_property("score_all_candidates_ms", round(score_all * 1e3, 2))
    record_property("choose_next_ms", round(choose * 1e3, 2))
    print(f"\n8 x 6 m room, {int(grid.valid.sum())} candidates x 72 headings: newly_covered "
          f"{score_all * 1e3:.1f} ms, choose_next {choose * 1e3:.1f} ms")
