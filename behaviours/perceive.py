"""Perception steps of the data-gathering branch: frame -> features -> bearings."""

from __future__ import annotations

from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.ports import Param
from behaviours.registry import register
from perception.features import available_kinds
from perception.frame import LandmarkBearings
from perception.observation import from_landmark_bearings, observe


@register
class Perceive(BearingsBehaviour):
    """Detect landmarks in the newest frame of a camera and publish their bearings.

    Writes ``/perception/observation`` (an :class:`~perception.observation.Observation`). From an
    image: features and their bearings; from an ideal bearings sensor (the simulator's fast
    mode): the identified bearings as they are. A frame already processed is not processed again
    (its stamp is remembered), so a slow camera costs nothing on ticks between frames. Belongs
    under the mission's ``sense:``.
    """

    PARAMS = (
        Param("camera", "str", "", doc="camera name; empty: the first camera", refs=False),
        Param("features", "str", "orb", doc="detector", choices=available_kinds(), refs=False),
        Param("max_features", "int", 500, doc="most features per frame", minimum=10, maximum=10000,
              refs=False),
    )
    READS = ("/perception/frames", "/perception/frame")
    WRITES = ("/perception/observation",)

    def __init__(self, name: str | None = None, **params) -> None:
        super().__init__(name=name, **params)
        self._last_stamp: tuple[str, float] | None = None

    def update(self) -> Status:
        name = self.param("camera")
        frame = (self.read("/perception/frames") or {}).get(name) if name else self.read("/perception/frame")
        if frame is None:
            self.feedback_message = f"no frame from {name or 'the camera'} yet"
            return Status.SUCCESS  # nothing to perceive is not a failure of perception
        stamp = (frame.camera_name, frame.stamp)
        if stamp != self._last_stamp:
            self._last_stamp = stamp
            if isinstance(frame, LandmarkBearings):
                observation = from_landmark_bearings(frame)
            else:
                observation = observe(frame, kind=self.param("features"), n_features=self.param("max_features"))
            self.write("/perception/observation", observation)
            self.feedback_message = f"{observation.count} landmarks"
        return Status.SUCCESS
