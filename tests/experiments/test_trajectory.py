"""The true-trajectory reader every evaluation uses, against values worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from experiments.eval.trajectory import TrueTrajectory


def test_the_true_pose_at_a_time_is_exact_in_a_stop_and_interpolated_elsewhere():
    # still at (1, 2, 170 deg) from t = 4.0 to 4.3, then turning fast; decimated rows 0.5 s apart
    truth = {"trajectory": [[3.5, 0.9, 2.0, math.radians(170)], [4.0, 1.0, 2.0, math.radians(170)],
                            [4.5, 1.0, 2.0, math.radians(-170)], [5.0, 1.2, 2.0, math.radians(-150)]],
             "stops": [[4.0, 4.3, 1.0, 2.0, math.radians(170)]]}
    trajectory = TrueTrajectory(truth)
    at = trajectory.at(4.3)
    assert (at.x, at.y, at.theta) == pytest.approx((1.0, 2.0, math.radians(170)))
    moving = trajectory.at(4.75)  # interpolated, the heading the short way round through 180 deg
    assert (moving.x, math.degrees(moving.theta)) == pytest.approx((1.1, -160.0))
    without = TrueTrajectory({"trajectory": truth["trajectory"]}).at(4.25)  # an old report: no stops
    assert abs(math.degrees(without.theta)) == pytest.approx(180.0)
    assert TrueTrajectory(truth).at(99.0).x == pytest.approx(1.2)  # after the last row: the last pose


def test_positions_path_lengths_and_the_heading_between_rows():
    # (0, 0) -> (3, 4) in 5 s, then back to (3, 0) by 10 s; turning from 170 deg to -170 deg on the way
    truth = {"trajectory": [[0.0, 0.0, 0.0, math.radians(170)], [5.0, 3.0, 4.0, math.radians(-170)],
                            [10.0, 3.0, 0.0, math.radians(-170)]]}
    trajectory = TrueTrajectory(truth)
    assert trajectory.position(2.5).tolist() == pytest.approx([1.5, 2.0])
    assert trajectory.length.tolist() == pytest.approx([0.0, 5.0, 9.0])
    assert trajectory.path_length(7.5) == pytest.approx(7.0)
    assert trajectory.path_length(99.0) == pytest.approx(9.0)  # after the last row: all of it
    halfway = trajectory.interpolated(2.5)  # the shorter way round: through 180 deg, not through 0
    assert (halfway.x, halfway.y, math.degrees(halfway.theta)) == pytest.approx((1.5, 2.0, 180.0))
    assert math.degrees(trajectory.interpolated(5.0).theta) == pytest.approx(190.0)  # continuous, not wrapped
    assert math.degrees(trajectory.at(5.0).theta) == pytest.approx(-170.0)  # wrapped
    np.testing.assert_array_equal(trajectory.xy[-1], [3.0, 0.0])


def test_an_empty_trajectory_is_refused():
    with pytest.raises(ValueError, match="empty trajectory"):
        TrueTrajectory({"trajectory": []})
