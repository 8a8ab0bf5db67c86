"""The values that cross the driver interfaces: what a pan-tilt unit reports it can do."""

from __future__ import annotations

import math

import pytest

from drivers.interfaces import PanTiltLimits, PanTiltState

STEP = math.radians(185.1428 / 3600)  # one PTU-D46 position
D46 = PanTiltLimits((-3090 * STEP, 3090 * STEP), (-907 * STEP, 604 * STEP), STEP, STEP, 2902 * STEP, 57 * STEP)


def test_targets_are_clipped_into_the_ranges_onto_whole_positions():
    pan, tilt = D46.clip(math.radians(-159.0), math.radians(40.0))
    assert (pan / STEP, tilt / STEP) == pytest.approx((-3090, 604))  # -158.91 and 31.06 deg
    pan, tilt = D46.clip(math.radians(10.0), math.radians(-10.0))
    # 10 deg = 36000 / 185.1428 = 194.44 positions -> 194; -10 deg -> -194
    assert (pan / STEP, tilt / STEP) == pytest.approx((194, -194))


def test_a_continuous_unit_is_only_clipped():
    unit = PanTiltLimits((-1.0, 1.0), (-0.5, 0.5), max_speed=2.0)
    assert unit.clip(0.123456, -0.7) == (0.123456, -0.5)
    assert unit.clip_speed(5.0) == 2.0 and unit.clip_speed(-1.0) == 0.0


def test_speeds_within_the_units_bounds():
    assert D46.clip_speed(math.radians(300.0)) == pytest.approx(math.radians(2902 * 185.1428 / 3600))  # 149.2
    assert D46.clip_speed(0.0) == pytest.approx(57 * STEP)


def test_the_state_says_nothing_of_limits_unless_the_driver_does():
    assert PanTiltState().limits is None and PanTiltState().homings == 0
