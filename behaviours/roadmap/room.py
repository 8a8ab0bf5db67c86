"""Room estimation on a dodecagon (DESIGN.md, algorithm 2, "Room estimation"; :mod:`maps.room`).

The robot drives a regular dodecagon: at each of its 12 corners it takes a stereo pair with the
pan-tilt head level at pan 0 (parallel images, known baseline), then turns 30 degrees and
drives ``side`` metres to the next corner (:func:`maps.room.dodecagon`; after the twelfth pair
it stops). Depth along horizontal epipolar lines gives 3-D points (:mod:`perception.stereo`),
:func:`maps.room.estimate_room` turns the 12 point sets into the free floor polygon, and the
corner whose image had the most features becomes the reference pose.

Choices where the paper is vague:

- **Stereo**: dense semi-global matching by default (``stereo: dense``,
  :func:`perception.stereo.dense_depth`, uniqueness 25 %, 9-pixel blocks, a point every 4
  pixels). In the simulated lab the sparse matcher found almost nothing on walls seen from
  1-2 m (smooth texture magnified 5-7 times: no corners), so five of the twelve views had under
  30 points and the polygon had a 100-degree gap; dense matching gives 6000-15000 points in
  every view. ``stereo: sparse`` keeps the feature matcher (use ``support: 3`` with it).
- **Support**: a polygon vertex is the 30th nearest obstacle point of its 2-degree sector
  (``support``), because dense matching has a few wrong near disparities in every view.
- **Obstacle heights**: points between 5 cm and ``max_obstacle_height`` (2 m) above the floor.
  The ceiling (2.6 m in the lab) is seen beyond about 3.3 m of a level camera and must not close
  the room; anything above 2 m is an overhang the robot passes under.
- **"The image with most features"**: the number of upright SIFT features of the homing
  camera's image (``camera``, taken in the same tick as the pair); that image becomes the
  reference image (``reference``) that ``ReturnToReference`` homes to. Counting homing features
  rather than stereo points picks the place the robot can best come back to.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from behaviours.ports import InputPort, OutputPort
from behaviours.registry import register
from behaviours.roadmap.display import RoadmapDisplay, room_section
from behaviours.roadmap.routine import ROUTINE_PORTS, Failed, RoutineBehaviour, Step
from behaviours.roadmap.values import TargetView
from behaviours.roadmap.vision import describe
from maps.room import CORNERS, RigMount, RoomEstimate, RoomEstimateError, RoomParams, StereoView, estimate_room
from perception.frame import Frame
from perception.stereo import dense_depth, dense_points, sparse_stereo

REFERENCE_NAME = "reference"


def stereo_points(frame: Frame, method: str) -> np.ndarray:
    """3-D points (rig frame) of a rectified stereo frame, dense (SGBM) or sparse (features)."""
    if frame.right is None:
        raise Failed(f"camera {frame.camera_name!r} gives no stereo pair")
    rig = frame.camera
    if method == "sparse":
        return sparse_stereo(frame.image, frame.right, rig).points
    depth = dense_depth(frame.image, frame.right, rig, num_disparities=96, block_size=9, uniqueness=25)
    return dense_points(depth, rig, step=4)


@register
class RoomEstimationDodecagon(RoutineBehaviour):
    """Drive a dodecagon, take a stereo pair at each of its 12 corners, estimate the room.

    Writes the room estimate (``room``: free floor polygon, distance to the scene, reference
    pose in the odometry frame) and the reference image (``reference``: the homing camera's
    image at the reference corner). FAILURE when the views do not enclose the room.
    """

    PORTS = (
        InputPort("side", float, 0.25, unit="m", minimum=0.05, maximum=2.0,
                  doc="side of the dodecagon (corners on a circle of radius 1.93 x side)"),
        InputPort("stereo_camera", str, "stereo", literal_only=True, doc="the stereo camera on the pan-tilt head"),
        InputPort("stereo", str, "dense", choices=("dense", "sparse"), literal_only=True,
                  doc="stereo matching: dense (SGBM) or sparse (features along epipolar lines)"),
        InputPort("rig_height", float, 1.08, unit="m", minimum=0.05, maximum=5.0, literal_only=True,
                  doc="height of the stereo rig's optical centre above the floor"),
        InputPort("pan_axis", list[float], [0.1, 0.0], unit="m", literal_only=True,
                  doc="the pan axis on the robot (x forward, y left)"),
        InputPort("rig_offset", list[float], [0.05, 0.0], unit="m", literal_only=True,
                  doc="the rig's left camera on the pan head (x forward, y left)"),
        InputPort("max_obstacle_height", float, 2.0, unit="m", minimum=0.1, maximum=100.0, literal_only=True,
                  doc="higher points are overhangs (or the ceiling), not obstacles"),
        InputPort("support", int, 30, minimum=1, maximum=10000, literal_only=True,
                  doc="a polygon vertex is the support-th nearest obstacle point of its direction"),
        *ROUTINE_PORTS,
        OutputPort("room", RoomEstimate, "/map/room", doc="the room estimate (reference frame)"),
        OutputPort("reference", TargetView, "/map/reference_image", doc="the image taken at the reference pose"),
    )

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        for port in ("pan_axis", "rig_offset"):
            if len(self.inputs[port]) != 2:
                raise ValueError(f"{type(self).__name__}.{port} takes [x, y], got {self.inputs[port]}")
        self.display = RoadmapDisplay()
        self._points: list[int] = []
        self._features: list[int] = []

    def mount(self) -> RigMount:
        axis, offset = self.inputs["pan_axis"], self.inputs["rig_offset"]
        return RigMount(float(self.get_input("rig_height")), (axis[0], axis[1]), (offset[0], offset[1]))

    def routine(self) -> Step[None]:
        stereo, camera = self.get_input("stereo_camera"), self.get_input("camera")
        views: list[StereoView] = []
        images: list[TargetView] = []
        self._points, self._features = [], []
        for corner in range(CORNERS):
            if corner:  # paper: take the pair, turn 30 degrees, drive to the next corner
                yield from self.rotate(2.0 * math.pi / CORNERS, f"turning at corner {corner}")
                yield from self.drive(float(self.get_input("side")), f"driving to corner {corner + 1}")
            frames, pose = yield from self.capture_all((stereo, camera))
            points = stereo_points(frames[stereo], self.get_input("stereo"))
            features = describe(frames[camera].image)
            views.append(StereoView(pose, 0.0, points, features=len(features)))
            images.append(TargetView(REFERENCE_NAME, frames[camera].image, features, frames[camera].camera,
                                     f"camera:{camera}", frames[camera].stamp))
            self._points.append(len(points))
            self._features.append(len(features))
            self.feedback_message = f"corner {corner + 1}: {len(points)} stereo points, {len(features)} features"
            yield  # one corner's image work per tick
        params = RoomParams(support=int(self.get_input("support")),
                            max_obstacle_height=float(self.get_input("max_obstacle_height")))
        try:
            room = estimate_room(views, self.mount(), params)
        except RoomEstimateError as exc:
            raise Failed(f"room estimate: {exc}") from None
        self.set_output("room", room)
        self.set_output("reference", images[room.reference_index])
        self.feedback_message = f"free floor {room.free.free.sum() * room.free.cell ** 2:.1f} m2, reference corner " \
                                f"{room.reference_index + 1}"

    def report_sections(self) -> dict[str, Any]:
        room, reference = self.written("room"), self.written("reference")
        if room is None:
            return {}
        stamp = reference.stamp if reference is not None else math.nan
        return {"roadmap": {"room": room_section(room, self._points, self._features, stamp)}}

    def log_rerun(self, rec: Any) -> None:
        room = self.written("room")
        self.display.log_room(rec, room)
        self.display.log_robot(rec, room, self.get_input("odometry", None))
