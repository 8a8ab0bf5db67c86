"""Perception steps of the data-gathering branch: frame -> features -> bearings."""

from __future__ import annotations

from typing import Any

from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from perception.features import available_kinds
from perception.frame import LandmarkBearings
from perception.observation import Observation, from_landmark_bearings, observe


@register
class Perceive(BearingsBehaviour):
    """Detect landmarks in the newest frame of a camera and publish their bearings.

    Writes its ``observation`` output (an :class:`~perception.observation.Observation`,
    ``/perception/observation`` unless remapped: two cameras, two keys). From an image: features
    and their bearings; from an ideal bearings sensor (the simulator's fast
    mode): the identified bearings as they are. A frame already processed is not processed again
    (its stamp is remembered), so a slow camera costs nothing on ticks between frames. Belongs
    under the mission's ``sense:``.
    """

    CAMERA = InputPort("camera", str, "", doc="camera name; empty: the first camera", literal_only=True, camera=True)
    FEATURES = InputPort("features", str, "orb", doc="detector", choices=available_kinds(), literal_only=True)
    MAX_FEATURES = InputPort("max_features", int, 500, doc="most features per frame", minimum=10, maximum=10000,
                             literal_only=True)
    FRAMES = InputPort("frames", dict, Ref("/perception/frames"), doc="the latest frame of each camera, by name")
    OBSERVATION = OutputPort("observation", Observation, "/perception/observation",
                             doc="bearings and features or ids")
    PORTS = (CAMERA, FEATURES, MAX_FEATURES, FRAMES, OBSERVATION)

    def __init__(self, name: str | None = None, **params: Any) -> None:
        super().__init__(name=name, **params)
        self._last_stamp: tuple[str, float] | None = None

    def update(self) -> Status:
        name = self.get_input(self.CAMERA)
        frames = self.get_input(self.FRAMES, None) or {}
        frame = frames.get(name) if name else next(iter(frames.values()), None)
        if frame is None:
            self.feedback_message = f"no frame from {name or 'the camera'} yet"
            return Status.SUCCESS  # nothing to perceive is not a failure of perception
        stamp = (frame.camera_name, frame.stamp)
        if stamp != self._last_stamp:
            self._last_stamp = stamp
            if isinstance(frame, LandmarkBearings):
                observation = from_landmark_bearings(frame)
            else:
                observation = observe(frame, kind=self.get_input(self.FEATURES),
                                      n_features=self.get_input(self.MAX_FEATURES))
            self.set_output(self.OBSERVATION, observation)
            self.feedback_message = f"{observation.count} landmarks"
        return Status.SUCCESS
