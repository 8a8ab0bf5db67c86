"""Circular median heading filter (eqs. 7-8) and confidence-scaled velocity (eq. 9)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from perception.heading import HeadingFilter, circular_median, heading_flipped, scaled_velocity


def test_median_across_the_seam():
    angles = np.radians([170.0, -170.0, 175.0, -178.0, 179.0])
    assert np.degrees(circular_median(angles)) == pytest.approx(179.0)


def test_median_ignores_a_minority_of_wild_estimates():
    angles = np.radians([10.0, 12.0, 11.0, -150.0, 95.0])
    assert np.degrees(circular_median(angles)) == pytest.approx(11.0)


def _spread(a: np.ndarray, m: float) -> float:
    return float(np.abs(np.angle(np.exp(1j * (a - m)))).sum())


@given(st.lists(st.floats(-3.0, 3.0), min_size=1, max_size=9), st.floats(-np.pi, np.pi))
def test_median_is_the_sample_of_least_spread_and_rotates_with_the_data(angles, offset):
    a = np.array(angles)
    m = circular_median(a)
    assert np.min(np.abs(np.angle(np.exp(1j * (a - m))))) < 1e-12  # one of the samples
    assert _spread(a, m) <= min(_spread(a, x) for x in a) + 1e-9
    shifted = a + offset  # rotating every estimate rotates the median (up to ties of equal spread)
    assert _spread(shifted, circular_median(shifted)) == pytest.approx(_spread(a, m), abs=1e-9)


def test_filter_keeps_the_last_k():
    f = HeadingFilter(k=3)
    assert f.heading is None and f.confidence == 0.0
    for h in (0.0, 2.0, 0.1, 0.2):
        f = f.push(h, confidence=0.5)
    assert f.headings == (2.0, 0.1, 0.2)
    assert f.heading == pytest.approx(0.2)
    assert f.confidence == 0.5
    assert f.reset().headings == ()
    with pytest.raises(ValueError):
        HeadingFilter(k=0)
    with pytest.raises(ValueError):
        circular_median(np.array([]))


def test_velocity_scaled_by_confidence():
    assert scaled_velocity(1.0, 0.4) == pytest.approx(0.4)
    assert scaled_velocity(0.5, 0.4) == pytest.approx(0.2)
    assert scaled_velocity(0.2, 0.4, min_confidence=0.3) == 0.0
    assert scaled_velocity(0.65, 0.4, min_confidence=0.3) == pytest.approx(0.2)
    assert scaled_velocity(3.0, 0.4) == pytest.approx(0.4)


def test_heading_flip_rule():
    assert heading_flipped(np.radians(170), np.radians(-80))
    assert not heading_flipped(np.radians(170), np.radians(-100))
