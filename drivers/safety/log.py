"""The record of the collision monitor's interventions over one run: events and episode counts.

An *event* is written when an intervention starts or changes (another action or zone), with
the time, the action and zone, the nearest range and the command before and after. Counts are
of *episodes*, not ticks: a stop that lasts 40 ticks is one safety stop; a bumper held down is
one hit. The run report's ``safety`` section is :meth:`SafetyLog.summary`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from perception.collision_monitor import SafetyState, Verdict

REPORTED_EVENTS = 20  # the first events go into the report (all of them into the recording)


@dataclass(frozen=True, slots=True)
class SafetyEvent:
    """One intervention: when, which action of which zone, why, and the command before and after."""

    t: float
    state: str
    action: str
    zone: str
    reason: str
    nearest_m: float
    before: tuple[float, float]
    after: tuple[float, float]

    def as_report(self) -> dict[str, Any]:
        return {"t": round(self.t, 3), "state": self.state, "action": self.action, "zone": self.zone,
                "reason": self.reason, "nearest_m": _metres(self.nearest_m),
                "before": {"v": _speed(self.before[0]), "w": _speed(self.before[1])},
                "after": {"v": _speed(self.after[0]), "w": _speed(self.after[1])}}

    def line(self) -> str:
        """One line for the recording's event log."""
        return (f"safety {self.state} ({self.action}{' ' + self.zone if self.zone else ''}): {self.reason}; "
                f"v {self.before[0]:+.2f} -> {self.after[0]:+.2f} m/s, w {self.before[1]:+.2f} -> "
                f"{self.after[1]:+.2f} rad/s")


@dataclass
class SafetyLog:
    """Counts and events of one run (fed every tick by the guarded base)."""

    sources: str = "none"
    safety_stops: int = 0
    slowdowns: int = 0
    bumper_hits: int = 0
    min_range_m: float = math.inf
    limited_ticks: dict[str, int] = field(default_factory=dict)
    events: list[SafetyEvent] = field(default_factory=list)
    event_count: int = 0
    _pending: list[SafetyEvent] = field(default_factory=list)
    _last: SafetyState = field(default_factory=SafetyState)

    def add(self, v: float, w: float, verdict: Verdict) -> None:
        """One tick: the command asked for and the monitor's verdict on it."""
        state, last = verdict.state, self._last
        self.min_range_m = min(self.min_range_m, state.nearest_m)
        if state.bumped and not last.bumped:
            self.bumper_hits += 1
        if state.state == "stopped" and last.state != "stopped":
            self.safety_stops += 1
        if state.state == "slowed" and last.state != "slowed":
            self.slowdowns += 1
        if state.limited:
            self.limited_ticks[state.action] = self.limited_ticks.get(state.action, 0) + 1
            if (state.state, state.action, state.zone) != (last.state, last.action, last.zone):
                event = SafetyEvent(state.stamp, state.state, state.action, state.zone, state.reason, state.nearest_m,
                                    (v, w), (verdict.v, verdict.w))
                self.event_count += 1
                self._pending.append(event)
                if len(self.events) < REPORTED_EVENTS:
                    self.events.append(event)
        self._last = state

    def take_new(self) -> list[SafetyEvent]:
        """The events since the last call (for the recording)."""
        new, self._pending = self._pending, []
        return new

    def summary(self) -> dict[str, Any]:
        """The run report's ``safety`` section."""
        return {"sources": self.sources, "safety_stops": self.safety_stops, "slowdowns": self.slowdowns,
                "bumper_hits": self.bumper_hits, "min_range_m": _metres(self.min_range_m),
                "limited_ticks": dict(sorted(self.limited_ticks.items())), "event_count": self.event_count,
                "events": [event.as_report() for event in self.events]}


def _metres(value: float) -> float | None:
    """A distance for JSON: rounded to the millimetre, None for 'nothing sensed' (inf)."""
    return round(value, 3) if math.isfinite(value) else None


def _speed(value: float) -> float:
    """A speed for JSON: rounded, and never -0.0."""
    return round(value, 4) + 0.0
