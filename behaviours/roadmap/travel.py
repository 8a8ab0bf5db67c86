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
from typing import Any

from behaviours.ports import InputPort, OutputPort, Port, Ref
from behaviours.registry import register
from behaviours.roadmap.display import RoadmapDisplay
from behaviours.roadmap.homing import REQUIRED_ROOM, HomingSettings, home
from behaviours.roadmap.paths import PLAN_TIME, reanchored, travel
from behaviours.roadmap.routine import ROBOT_RADIUS, ROUTINE_PORTS, Failed, RoutineBehaviour, Step
from behaviours.roadmap.values import TargetView
from maps.planning import PlanResult
from maps.room import RoomEstimate
from perception.geometry import Pose2D

PLAN_PORTS: tuple[Port, ...] = (
    InputPort("plan_time", float, PLAN_TIME, unit="s", minimum=0.01, maximum=10.0, literal_only=True,
              doc="time limit of one path search (wall clock, inside one tick)"),
    OutputPort("plan", PlanResult, "/map/plan", doc="the last planned path (reference frame)"),
)


@register
class GoToPose(RoutineBehaviour):
    """Plan a path in the room estimate to a pose (reference frame) and drive it (OMPL, then DriveTo)."""

    PORTS = (
        InputPort("goal", Pose2D, Ref("/map/coverage_goal"), doc="where to go (reference frame)"),
        InputPort("turn", bool, False, literal_only=True, doc="turn to the goal's heading at the end"),
        InputPort("room", RoomEstimate, Ref("/map/room"), doc="the room estimate"),
        ROBOT_RADIUS,
        *PLAN_PORTS,
        *ROUTINE_PORTS,
    )

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.display = RoadmapDisplay()

    def routine(self) -> Step[None]:
        room: RoomEstimate | None = self.get_input("room", None)
        goal: Pose2D | None = self.get_input("goal", None)
        if room is None or goal is None:
            raise Failed("no room estimate" if room is None else "no goal")
        plan = yield from travel(self, room, goal, turn=bool(self.get_input("turn")))
        self.feedback_message = f"arrived after {plan.length:.1f} m"

    def log_rerun(self, rec: Any) -> None:
        self.display.log_plan(rec, self.written("plan"))


@register
class ReturnToReference(RoutineBehaviour):
    """Go back to the reference pose, home to the reference image, and re-anchor the room there.

    The homed pose becomes the room's reference pose in the odometry frame (``room_out``), which
    removes the odometry drift accumulated since the reference was last seen.
    """

    PORTS = (
        InputPort("reference", TargetView, Ref("/map/reference_image"), doc="the image taken at the reference"),
        *REQUIRED_ROOM,
        *PLAN_PORTS,
        *ROUTINE_PORTS,
        OutputPort("room_out", RoomEstimate, "/map/room", doc="the room, re-anchored at the homed reference pose"),
    )

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.display = RoadmapDisplay()
        self.returns = 0
        self.corrections: list[float] = []

    def routine(self) -> Step[None]:
        room: RoomEstimate | None = self.get_input("room", None)
        reference: TargetView | None = self.get_input("reference", None)
        if room is None or reference is None:
            raise Failed("no room estimate" if room is None else "no reference image")
        yield from travel(self, room, Pose2D(0.0, 0.0, 0.0), turn=True)
        result = yield from home(self, reference, HomingSettings.of(self))
        correction = result.pose.relative_to(room.reference_pose)
        self.set_output("room_out", reanchored(room, result.pose))
        self.returns += 1
        self.corrections.append(math.hypot(correction.x, correction.y))
        self.feedback_message = (f"at the reference; odometry had drifted {self.corrections[-1]:.2f} m, "
                                 f"{math.degrees(correction.theta):.1f} deg")

    def report_sections(self) -> dict[str, Any]:
        if not self.returns:
            return {}
        # one key per node: the runner merges the sections of every node shallowly
        return {"roadmap": {f"reference_drift_m ({self.name})": [round(c, 4) for c in self.corrections]}}

    def log_rerun(self, rec: Any) -> None:
        self.display.log_plan(rec, self.written("plan"))
