"""The robot's place along a path and the carrot ahead of it (maps.pursuit), on paths worked by hand."""

import numpy as np

from maps.pursuit import carrot, place_along

# A path out along x and back along y = 0.1, 0.1 m apart: it doubles back on itself.
OUT = np.array([[0.0, 0.0], [0.1, 0.0], [0.2, 0.0], [0.3, 0.0]])
BACK = np.array([[0.3, 0.1], [0.2, 0.1], [0.1, 0.1], [0.0, 0.1]])
PATH = np.vstack([OUT, BACK])


def test_the_place_is_the_nearest_point_in_the_window() -> None:
    assert place_along(PATH, 0, 4, np.array([0.22, 0.03])) == 2  # (0.2, 0) is 0.036 m away, the rest farther


def test_the_place_never_goes_back_nor_across_to_the_way_back() -> None:
    here = np.array([0.1, 0.09])  # beside point 6 of the way back, 0.09 m from point 1 on the way out
    assert place_along(PATH, 1, 3, here) == 1  # the window holds points 1-2 only: the way back is not in it
    assert place_along(PATH, 2, 8, here) == 6  # once the window reaches it, the way back's point wins


def test_a_window_past_the_end_is_clipped() -> None:
    assert place_along(PATH, 6, 100, np.array([0.0, 0.12])) == 7


def test_the_carrot_is_the_first_point_a_lookahead_away() -> None:
    here = np.array([0.0, 0.0])
    assert carrot(PATH, 0, here, 0.15).tolist() == [0.2, 0.0]  # 0.1 is too near, 0.2 is the first at 0.15 or more
    assert carrot(PATH, 3, here, 0.25).tolist() == [0.3, 0.0]  # from the place on: (0.3, 0) is 0.3 m away


def test_the_carrot_is_the_end_when_nothing_is_far_enough() -> None:
    assert carrot(PATH, 5, np.array([0.1, 0.1]), 5.0).tolist() == [0.0, 0.1]
