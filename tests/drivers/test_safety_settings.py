"""The profile's safety: section: defaults from the robot's footprint, polygons checked."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydantic import ValidationError

from drivers.pioneer_body import BODIES
from drivers.safety.settings import SafetySettings, monitor_config
from perception.polygons import rectangle


def test_the_defaults_grow_the_robots_own_footprint():
    config = monitor_config(None, BODIES["p3dx"].footprint)
    stop, slow = config.zones
    assert config.footprint == pytest.approx(rectangle(0.210, 0.301, 0.2125))
    assert np.sort(stop.polygon, axis=0) == pytest.approx(np.sort(rectangle(0.31, 0.401, 0.3125), axis=0))
    assert np.sort(slow.polygon, axis=0) == pytest.approx(np.sort(rectangle(0.56, 0.651, 0.5625), axis=0))
    assert (stop.action, slow.action, slow.ratio) == ("stop", "slowdown", 0.5)
    assert (config.time_before_collision, config.source_timeout, config.crawl_speed) == (1.0, 1.0, 0.1)
    assert config.crawl_turn_rate == pytest.approx(math.radians(20.0))


def test_given_polygons_replace_the_defaults():
    settings = SafetySettings(footprint=[[0.3, 0.3], [-0.3, 0.3], [-0.3, -0.3], [0.3, -0.3]],
                              stop_zone=[[0.5, 0.4], [-0.4, 0.4], [-0.4, -0.4], [0.5, -0.4]], slowdown_ratio=0.3)
    config = monitor_config(settings, BODIES["p3at"].footprint)
    assert np.sort(config.footprint, axis=0) == pytest.approx(np.sort(rectangle(0.3, 0.3, 0.3), axis=0))
    assert config.zones[0].polygon[:, 0].max() == pytest.approx(0.5)
    assert config.zones[1].ratio == 0.3


@pytest.mark.parametrize(("field", "value", "message"), [
    ("footprint", [[1.0, 1.0], [2.0, 1.0], [2.0, 2.0]], "centre"),
    ("stop_zone", [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]], "cross"),
    ("footprint", [[-1, -1], [1, -1], [0, 0.2], [1, 1], [-1, 1]], "convex"),
    ("slowdown_ratio", 1.5, "less than or equal to 1"),
])
def test_bad_settings_are_refused_with_a_reason(field, value, message):
    with pytest.raises(ValidationError, match=message):
        SafetySettings.model_validate({field: value})


def test_a_zone_that_leaves_part_of_the_footprint_out_is_refused():
    settings = SafetySettings(stop_zone=[[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.1, -0.1]])
    with pytest.raises(ValueError, match="stop_zone must contain the whole footprint"):
        monitor_config(settings, BODIES["p3dx"].footprint)
