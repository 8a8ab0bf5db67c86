"""The record of interventions: episodes (not ticks), bumper hits, the nearest range, the first events."""

from __future__ import annotations

import math

from drivers.safety.log import REPORTED_EVENTS, SafetyLog
from perception.collision_monitor import SafetyState, Verdict


def verdict(v, w, state="clear", action="", ratio=1.0, nearest=math.inf, bumped=False, t=0.0, zone=""):
    return Verdict(v * ratio, w * ratio, SafetyState(state, action, zone, f"{action} because", ratio, nearest,
                                                    bumped, t))


def test_a_long_stop_is_one_episode_and_one_event():
    log = SafetyLog(sources="sonar")
    log.add(0.3, 0.0, verdict(0.3, 0.0, nearest=1.0))
    for tick in range(40):
        log.add(0.3, 0.0, verdict(0.3, 0.0, "stopped", "stop", 0.0, 0.08, t=1.0 + tick / 10, zone="stop"))
    log.add(-0.2, 0.0, verdict(-0.2, 0.0, nearest=0.08))  # backing away
    log.add(0.3, 0.0, verdict(0.3, 0.0, "stopped", "stop", 0.0, 0.09, t=6.0, zone="stop"))
    summary = log.summary()
    assert summary["safety_stops"] == 2 and summary["limited_ticks"] == {"stop": 41}
    assert summary["event_count"] == 2 and summary["min_range_m"] == 0.08
    first = summary["events"][0]
    assert first == {"t": 1.0, "state": "stopped", "action": "stop", "zone": "stop", "reason": "stop because",
                     "nearest_m": 0.08, "before": {"v": 0.3, "w": 0.0}, "after": {"v": 0.0, "w": 0.0}}
    assert [event.t for event in log.take_new()] == [1.0, 6.0] and log.take_new() == []


def test_slowing_by_one_shape_then_another_is_one_slowdown_but_two_events():
    log = SafetyLog()
    log.add(0.3, 0.0, verdict(0.3, 0.0, "slowed", "slowdown", 0.5, zone="slowdown"))
    log.add(0.3, 0.0, verdict(0.3, 0.0, "slowed", "approach", 0.4))
    assert (log.slowdowns, log.event_count) == (1, 2)


def test_a_bumper_held_down_is_one_hit():
    log = SafetyLog()
    for pressed in (False, True, True, True, False, True):
        log.add(0.0, 0.0, verdict(0.0, 0.0, bumped=pressed))
    assert log.bumper_hits == 2


def test_only_the_first_events_go_into_the_report_and_nothing_sensed_is_null():
    log = SafetyLog()
    for i in range(2 * REPORTED_EVENTS):
        action = "stop" if i % 2 else "approach"
        log.add(0.3, 0.0, verdict(0.3, 0.0, "stopped" if i % 2 else "slowed", action, 0.0 if i % 2 else 0.5, t=i))
    summary = log.summary()
    assert summary["event_count"] == 2 * REPORTED_EVENTS and len(summary["events"]) == REPORTED_EVENTS
    assert summary["min_range_m"] is None
