"""Travel in the room estimate: to a pose (``GoToPose``) and back to the reference (``ReturnToReference``).

Both plan with OMPL in the room's free grid and drive the path with ``DriveTo``
(:mod:`behaviours.roadmap.paths`). Returning to the reference (paper: "the robot returns to the
reference pose") ends with homing to the reference image, and the homed pose becomes the room's
new reference pose in the odometry frame (``room_out``): odometry drift since the reference was
last seen is removed, so every later conversion between the reference frame and odometry
starts afresh.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.roadmap.display import Drawn, plan_drawings, roadmap_figures
from behaviours.roadmap.homing import REQUIRED_ROOM, HomingSettings, home
from behaviours.roadmap.paths import PLAN_OUT, PLAN_PORTS, reanchored, travel
from behaviours.roadmap.room import ROOM_IN
from behaviours.roadmap.routine import ROBOT_RADIUS, ROUTINE_PORTS, Failed, RoutineBehaviour, Step
from behaviours.roadmap.values import HomingResult, TargetView
from behaviours.telemetry import Drawing, Figure
from maps.room import RoomEstimate
from perception.geometry import Pose2D

REFERENCE_IN = InputPort("reference", TargetView, Ref("/map/reference_image"), doc="the image taken at the reference")


def return_to_reference(host: RoutineBehaviour, room: RoomEstimate, reference: TargetView,
                        settings: HomingSettings, *, retries: int = 0) -> Step[HomingResult]:
    """Travel to the reference pose (planned in ``room``) and home to the reference image there.

    The homed pose (odometry frame) is where the reference truly is now: the caller re-anchors the
    room there. A travel that fails (ran into something: the map is off by the drift) is tried
    ``retries`` more times before its failure is the caller's.
    """
    for attempt in range(retries + 1):
        try:
            yield from travel(host, room, Pose2D(), turn=True)
            break
        except Failed:
            if attempt == retries:
                raise
    return (yield from home(host, reference, settings))


class PlanningRoutine(RoutineBehaviour):
    """A routine that plans paths in the room estimate (``PLAN_PORTS``): draws the last one it planned."""

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.drawn = Drawn()

    def drawings(self) -> Iterator[Drawing]:
        plan = self.written(PLAN_OUT)
        if plan is not None and self.drawn.changed("plan", plan):
            yield from plan_drawings(plan)


@register
class GoToPose(PlanningRoutine):
    """Plan a path in the room estimate to a pose (reference frame) and drive it (OMPL, then DriveTo)."""

    GOAL = InputPort("goal", Pose2D, Ref("/map/coverage_goal"), doc="where to go (reference frame)")
    TURN = InputPort("turn", bool, False, literal_only=True, doc="turn to the goal's heading at the end")
    PORTS = (GOAL, TURN, ROOM_IN, ROBOT_RADIUS, *PLAN_PORTS, *ROUTINE_PORTS)

    def routine(self) -> Step[None]:
        room = self.get_input(ROOM_IN, None)
        goal = self.get_input(self.GOAL, None)
        if room is None or goal is None:
            raise Failed("no room estimate" if room is None else "no goal")
        plan = yield from travel(self, room, goal, turn=self.get_input(self.TURN))
        self.feedback_message = f"arrived after {plan.length:.1f} m"


@register
class ReturnToReference(PlanningRoutine):
    """Go back to the reference pose, home to the reference image, and re-anchor the room there.

    The homed pose becomes the room's reference pose in the odometry frame (``room_out``), which
    removes the odometry drift accumulated since the reference was last seen.
    """

    ROOM_OUT = OutputPort("room_out", RoomEstimate, "/map/room",
                          doc="the room, re-anchored at the homed reference pose")
    PORTS = (REFERENCE_IN, *REQUIRED_ROOM, *PLAN_PORTS, *ROUTINE_PORTS, ROOM_OUT)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.returns = 0
        self.corrections: list[float] = []

    def routine(self) -> Step[None]:
        room = self.get_input(ROOM_IN, None)
        reference = self.get_input(REFERENCE_IN, None)
        if room is None or reference is None:
            raise Failed("no room estimate" if room is None else "no reference image")
        result = yield from return_to_reference(self, room, reference, HomingSettings.of(self))
        correction = result.pose.relative_to(room.reference_pose)
        self.set_output(self.ROOM_OUT, reanchored(room, result.pose))
        self.returns += 1
        self.corrections.append(math.hypot(correction.x, correction.y))
        self.feedback_message = (f"at the reference; odometry had drifted {self.corrections[-1]:.2f} m, "
                                 f"{math.degrees(correction.theta):.1f} deg")

    def figures(self) -> Iterator[Figure]:
        if self.returns:  # one name per node: the mission's returns do not overwrite each other's
            yield from roadmap_figures({f"reference_drift_m ({self.name})": [round(c, 4) for c in self.corrections]})
