"""Passing a viewframe that cannot be reached: something stands where it was taught.

A person standing on a taught route stands on the places of a few viewframes (in the lab they
are 0.2 m apart): route following homes to one of them, ``AvoidObstacles`` drives round the
person and, since homing keeps pulling the robot back to a place it cannot reach, gives up (or
the target is lost from view while the robot is off the route, behind the person).
:class:`SkipViewframes` moves the target on to the farthest of the next ``window`` viewframes in
view (enough landmarks match, with a valid Z-infinity rotation: the rule ``FollowRoute`` follows
by), so that following resumes beyond the obstacle. When none of them is in view the trail is
lost, which is the search pattern's job (``SearchPattern``): FAILURE, and nothing changes.

In ``follow_route`` it is the recovery of the avoidance, inside the search's recovery::

    RecoveryNode: [RecoveryNode: [AvoidObstacles: {child: ...follow...}, SkipViewframes], SearchPattern]
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.landmark_tree import LTMAP_IN
from behaviours.ports import InputPort, OutputPort
from behaviours.registry import register
from behaviours.route import MIN_MATCHES, OBSERVATION_IN, PROGRESS_IN, PROGRESS_KEY, RouteProgress, sees
from behaviours.telemetry import Event, Figure


@register
class SkipViewframes(BearingsBehaviour):
    """Move the route's target on to the farthest of the next ``window`` viewframes in view.

    SUCCESS with the new target (``skipped``); FAILURE when none of them is in view (the trail is
    lost).
    """

    WINDOW = InputPort("window", int, 5, minimum=1, maximum=100, literal_only=True,
                       doc="viewframes past the target the route may skip to")
    SKIPPED = OutputPort("skipped", RouteProgress, PROGRESS_KEY, doc="the progress with the new target")
    PORTS = (WINDOW, MIN_MATCHES, LTMAP_IN, PROGRESS_IN, OBSERVATION_IN, SKIPPED)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.skips: list[dict[str, Any]] = []
        self._rng = np.random.default_rng(0)
        self._drawn = 0

    def update(self) -> Status:
        tree = self.get_input(LTMAP_IN, None)
        progress = self.get_input(PROGRESS_IN, None)
        observation = self.get_input(OBSERVATION_IN, None)
        if tree is None or progress is None or observation is None or progress.finished:
            self.feedback_message = "no route to skip along"
            return Status.FAILURE
        minimum, target = self.get_input(MIN_MATCHES), progress.target
        last = tree.viewframe_count - 1
        ahead = [target + progress.direction * k for k in range(self.get_input(self.WINDOW), 0, -1)]
        for index in (i for i in ahead if 0 <= i <= last):
            if sees(tree, index, observation, minimum, self._rng):
                self.set_output(self.SKIPPED, progress.retargeted(index, self.now()))
                self.skips.append({"from": target, "to": index, "time_s": round(self.now(), 3)})
                self.feedback_message = f"viewframe {target} cannot be reached: on to viewframe {index}"
                return Status.SUCCESS
        self.feedback_message = f"none of the {len(ahead)} viewframes past {target} is in view: the trail is lost"
        return Status.FAILURE

    def figures(self) -> Iterator[Figure]:
        yield Figure("ltmap", "skips", list(self.skips))

    def drawings(self) -> Iterator[Event]:
        for skip in self.skips[self._drawn:]:
            yield Event("route/events", f"viewframe {skip['from']} cannot be reached: skipped to {skip['to']}")
        self._drawn = len(self.skips)
