"""Look all around with the pan-tilt cameras while the robot stands: :class:`LookAround`.

At the start of exploration (the first footprints join the robot's disc) and as a recovery (no
border reachable yet, or a goal given up), the head steps through
:func:`maps.exploration.gaze.survey`, holding each view until the map has integrated a frame from it.

The survey is planned within what the unit reports (:mod:`behaviours.exploration.head`): a PTU-D46
reports +-158.91 deg, so the mission's default +-159 deg become +-158.91 and no view is refused.
A unit can reset mid-run (a power dip): it finds its limits and stands at home, and a view it was
sent is not where it now heads. The node notices, from ``/ptu/state``, either the unit's own count
of homings going up or a view not reached within its slew time plus ``timeout``, and sends the view
again (the runner sends a command only when it changes, so it first points the unit where it
reports to be, then at the view); after ``retries`` such re-sends of one view without getting there
it fails, saying which view and where the unit stands.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.exploration.head import HEAD_PORTS, PTU_COMMAND, PTU_STATE, gaze_params, head_command, unit_params
from behaviours.ports import InputPort
from behaviours.registry import register
from behaviours.telemetry import Figure
from drivers.interfaces import PanTiltCommand, PanTiltState
from maps.exploration.gaze import survey


@register
class LookAround(BearingsBehaviour):
    """Look all around with the pan-tilt cameras while the robot stands; SUCCESS when done.

    The head steps through :func:`maps.exploration.gaze.survey` (rows of tilts from the lowest up
    to the horizon, pans from one limit to the other, fields of view overlapping by ``overlap``),
    within the limits, position step and speed the unit reports, holding each view for ``settle``
    seconds once the unit reports it there (so the map integrates a frame from it). A view not
    reached within its slew time plus ``timeout`` seconds, or a unit that reports having homed, gets
    the view sent again; FAILURE after ``retries`` re-sends of one view. The base gets no command
    (the runner stops it).
    """

    OVERLAP = InputPort("overlap", float, 0.15, minimum=0.0, maximum=0.9, literal_only=True,
                        doc="fraction by which neighbouring views overlap")
    SETTLE = InputPort("settle", float, 0.4, unit="s", minimum=0.0, maximum=10.0, literal_only=True,
                       doc="hold each pose this long once there")
    TOLERANCE = InputPort("tolerance", float, 1.0, unit="deg", minimum=0.01, maximum=10.0, literal_only=True,
                          doc="the head is at a pose within this (at least one position step of the unit)")
    PTU = PTU_STATE
    TIMEOUT = InputPort("timeout", float, 10.0, unit="s", minimum=0.1, maximum=600.0, literal_only=True,
                        doc="send a view again when the unit is not there this long after its slew time")
    RETRIES = InputPort("retries", int, 2, minimum=0, maximum=100, literal_only=True,
                        doc="re-sends of one view before failing")
    PORTS = (OVERLAP, SETTLE, TOLERANCE, *HEAD_PORTS, PTU, PTU_COMMAND, TIMEOUT, RETRIES)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.asked = gaze_params(self)
        self.params = self.asked
        self.poses = survey(self.params, self.get_input(self.OVERLAP))
        self.index = 0
        self.arrived: float | None = None
        self.sent_at: float | None = None  # when the current view was (last) commanded
        self.resends = 0  # of the current view
        self.homings_seen: int | None = None
        self.pending_nudge: PanTiltCommand | None = None
        self.surveys = 0
        self.rehomes = 0
        self.resent = 0

    def initialise(self) -> None:
        self.index, self.arrived, self.sent_at, self.resends = 0, None, None, 0
        self.pending_nudge = None

    def _plan(self, state: PanTiltState | None) -> None:
        """The survey within what the unit reports (planned again when that changes)."""
        params = unit_params(self.asked, state)
        if params != self.params:
            self.params, self.poses = params, survey(params, self.get_input(self.OVERLAP))
            self.index = min(self.index, len(self.poses) - 1)

    def update(self) -> Status:
        state = self.get_input(self.PTU, None)
        self._plan(state)
        now = self.now()
        pan, tilt = self.poses[self.index]
        target = head_command(float(pan), float(tilt), self.params, state)
        if self.sent_at is None:
            self.sent_at = now
        self._notice_homing(state, now)
        if self.pending_nudge is not None:  # a re-send: first where the unit is, then the view
            self.set_output(PTU_COMMAND, self.pending_nudge)
            self.pending_nudge = None
            self.sent_at = now
            return Status.RUNNING
        self.set_output(PTU_COMMAND, target)
        self.feedback_message = f"view {self.index + 1} of {len(self.poses)}"
        if not self._there(state, target):
            self.arrived = None
            return self._waiting(state, target, now)
        if self.arrived is None:
            self.arrived = now
        if now - self.arrived < self.get_input(self.SETTLE):
            return Status.RUNNING
        self.index, self.arrived, self.sent_at, self.resends = self.index + 1, None, None, 0
        if self.index < len(self.poses):
            return Status.RUNNING
        self.surveys += 1
        self.index = 0
        return Status.SUCCESS

    def _there(self, state: PanTiltState | None, target: PanTiltCommand) -> bool:
        if state is None or state.moving:
            return False
        tolerance = math.radians(self.get_input(self.TOLERANCE))
        if state.limits is not None:
            tolerance = max(tolerance, state.limits.pan_step, state.limits.tilt_step)
        return abs(state.pan - target.pan) <= tolerance and abs(state.tilt - target.tilt) <= tolerance

    def _notice_homing(self, state: PanTiltState | None, now: float) -> None:
        """A unit whose homing count went up has reset: send the view again, with fresh retries."""
        if state is None:
            return
        if self.homings_seen is not None and state.homings > self.homings_seen:
            self.rehomes += 1
            self.resends = 0
            self._resend(state, now)
        self.homings_seen = state.homings

    def _waiting(self, state: PanTiltState | None, target: PanTiltCommand, now: float) -> Status:
        """Not at the view yet: RUNNING, a re-send after the slew time plus ``timeout``, FAILURE after
        ``retries`` of them."""
        if self.sent_at is None or now - self.sent_at <= self._budget(state, target):
            return Status.RUNNING
        if self.resends >= self.get_input(self.RETRIES):
            where = "no report" if state is None else \
                f"({math.degrees(state.pan):.2f}, {math.degrees(state.tilt):.2f}) deg"
            self.feedback_message = (f"the pan-tilt unit did not reach view {self.index + 1} of {len(self.poses)} "
                                     f"(pan {math.degrees(target.pan):.2f}, tilt {math.degrees(target.tilt):.2f} deg) "
                                     f"after {self.resends} re-sends; it reports {where}")
            return Status.FAILURE
        self.resends += 1
        self._resend(state, now)
        return Status.RUNNING

    def _resend(self, state: PanTiltState | None, now: float) -> None:
        """Send the current view again next tick, after pointing the unit where it is this one."""
        self.resent += 1
        self.sent_at = now
        if state is not None:
            self.pending_nudge = head_command(state.pan, state.tilt, self.params, state)

    def _budget(self, state: PanTiltState | None, target: PanTiltCommand) -> float:
        """The slew time to ``target`` from where the unit is (from the farthest point of its range
        without a report), plus ``timeout``."""
        p = self.params
        if state is None:
            travel = max(p.pan_limits[1] - p.pan_limits[0], p.tilt_limits[1] - p.tilt_limits[0])
        else:
            travel = max(abs(state.pan - target.pan), abs(state.tilt - target.tilt))
        return travel / max(target.speed, 1e-6) + self.get_input(self.TIMEOUT)

    def figures(self) -> Iterator[Figure]:
        """How many look-arounds were made (the start's and the recoveries'), and how the unit did."""
        name = self.name.replace(" ", "_")
        yield Figure("exploration", f"look_arounds_{name}", self.surveys)
        if self.rehomes or self.resent:
            yield Figure("exploration", f"look_around_rehomes_{name}", self.rehomes)
            yield Figure("exploration", f"look_around_resends_{name}", self.resent)

