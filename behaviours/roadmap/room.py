"""Room estimation on a dodecagon (docs/design.md, method 2, "Room estimation"; :mod:`maps.room`).

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
from collections.abc import Iterator
from typing import Any

import numpy as np

from behaviours.footprint import robot_radius
from behaviours.motion import ODOMETRY
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.roadmap.display import Drawn, roadmap_figures, robot_drawings, room_drawings, room_section
from behaviours.roadmap.routine import CAMERA, ROUTINE_PORTS, Failed, RoutineBehaviour, Step
from behaviours.roadmap.values import TargetView
from behaviours.roadmap.vision import describe
from behaviours.telemetry import Drawing, Figure
from maps.room import (
    CORNERS,
    RigMount,
    RoomEstimate,
    RoomEstimateError,
    RoomParams,
    StereoView,
    corner_circle,
    estimate_room,
)
from perception.frame import Frame
from perception.stereo import dense_depth, dense_points, sparse_stereo

REFERENCE_NAME = "reference"

ROOM_IN = InputPort("room", RoomEstimate, Ref("/map/room"), doc="the room estimate")


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

    SIDE = InputPort("side", float, 0.25, unit="m", minimum=0.05, maximum=2.0,
                     doc="side of the dodecagon (corners on a circle of radius 1.93 x side)")
    STEREO_CAMERA = InputPort("stereo_camera", str, "stereo", literal_only=True, camera=True,
                              doc="the stereo camera on the pan-tilt head")
    STEREO = InputPort("stereo", str, "dense", choices=("dense", "sparse"), literal_only=True,
                       doc="stereo matching: dense (SGBM) or sparse (features along epipolar lines)")
    RIG_HEIGHT = InputPort("rig_height", float, 1.08, unit="m", minimum=0.05, maximum=5.0, literal_only=True,
                           doc="height of the stereo rig's optical centre above the floor")
    PAN_AXIS = InputPort("pan_axis", list[float], [0.1, 0.0], unit="m", literal_only=True,
                         doc="the pan axis on the robot (x forward, y left)")
    RIG_OFFSET = InputPort("rig_offset", list[float], [0.05, 0.0], unit="m", literal_only=True,
                           doc="the rig's left camera on the pan head (x forward, y left)")
    MAX_OBSTACLE_HEIGHT = InputPort("max_obstacle_height", float, 2.0, unit="m", minimum=0.1, maximum=100.0,
                                    literal_only=True,
                                    doc="higher points are overhangs (or the ceiling), not obstacles")
    SUPPORT = InputPort("support", int, 30, minimum=1, maximum=10000, literal_only=True,
                        doc="a polygon vertex is the support-th nearest obstacle point of its direction")
    ROOM = OutputPort("room", RoomEstimate, "/map/room", doc="the room estimate (reference frame)")
    REFERENCE = OutputPort("reference", TargetView, "/map/reference_image", doc="the image taken at the reference pose")
    PORTS = (SIDE, STEREO_CAMERA, STEREO, RIG_HEIGHT, PAN_AXIS, RIG_OFFSET, MAX_OBSTACLE_HEIGHT, SUPPORT,
             *ROUTINE_PORTS, ROOM, REFERENCE)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.pan_axis, self.rig_offset = self.pair(self.PAN_AXIS), self.pair(self.RIG_OFFSET)
        self.drawn = Drawn()
        self._points: list[int] = []
        self._features: list[int] = []

    def mount(self) -> RigMount:
        return RigMount(self.get_input(self.RIG_HEIGHT), self.pan_axis, self.rig_offset)

    def room_needed(self) -> str:
        """What the dodecagon needs round the start, for a failure to say (a user starts the robot)."""
        side = self.get_input(self.SIDE)
        circle = corner_circle(side)
        disc = robot_radius(self, 0.0)
        return (f"the dodecagon (side {side:.2f} m) needs a free disc {2.0 * (circle + disc):.2f} m across, its "
                f"centre {circle:.2f} m to the robot's left at the start, 105 deg round from its heading "
                f"(corners on a {circle:.2f} m circle, the robot's disc {disc:.2f} m): start the robot in open "
                "floor, or give a smaller side")

    def routine(self) -> Step[None]:
        stereo, camera = self.get_input(self.STEREO_CAMERA), self.get_input(CAMERA)
        views: list[StereoView] = []
        images: list[TargetView] = []
        self._points, self._features = [], []
        for corner in range(CORNERS):
            if corner:  # paper: take the pair, turn 30 degrees, drive to the next corner
                try:
                    yield from self.rotate(2.0 * math.pi / CORNERS, f"turning at corner {corner}")
                    yield from self.drive(self.get_input(self.SIDE), f"driving to corner {corner + 1}")
                except Failed as exc:
                    raise Failed(f"{exc}; {self.room_needed()}") from None
            frames, pose = yield from self.capture_all((stereo, camera))
            points = stereo_points(frames[stereo], self.get_input(self.STEREO))
            features = describe(frames[camera].image)
            views.append(StereoView(pose, 0.0, points, features=len(features)))
            images.append(TargetView(REFERENCE_NAME, frames[camera].image, features, frames[camera].camera,
                                     f"camera:{camera}", frames[camera].stamp))
            self._points.append(len(points))
            self._features.append(len(features))
            self.feedback_message = f"corner {corner + 1}: {len(points)} stereo points, {len(features)} features"
            yield  # one corner's image work per tick
        params = RoomParams(support=self.get_input(self.SUPPORT),
                            max_obstacle_height=self.get_input(self.MAX_OBSTACLE_HEIGHT))
        try:
            room = estimate_room(views, self.mount(), params)
        except RoomEstimateError as exc:
            raise Failed(f"room estimate: {exc}") from None
        self.set_output(self.ROOM, room)
        self.set_output(self.REFERENCE, images[room.reference_index])
        self.feedback_message = f"free floor {room.free.free.sum() * room.free.cell ** 2:.1f} m2, reference corner " \
                                f"{room.reference_index + 1}"

    def figures(self) -> Iterator[Figure]:
        room, reference = self.written(self.ROOM), self.written(self.REFERENCE)
        if room is not None:
            stamp = reference.stamp if reference is not None else math.nan
            yield from roadmap_figures(room_section(room, self._points, self._features, stamp), "room")

    def drawings(self) -> Iterator[Drawing]:
        """The room when it is estimated (re-anchoring keeps the map: not again), the robot in it every time."""
        room = self.written(self.ROOM)
        if room is None:
            return
        if self.drawn.changed("room", room.polygon):
            yield from room_drawings(room)
        odometry = self.get_input(ODOMETRY, None)
        if odometry is not None:
            yield from robot_drawings(room, odometry)
