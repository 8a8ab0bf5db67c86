"""Scanning a position for target images (docs/design.md, method 2, "Coverage"; "Navigation").

At a position the robot takes ``images`` (12) images, turning 360 / images degrees between them,
and compares each with the target images not found yet (upright SIFT, ratio 0.65, planar
essential matrix: :mod:`behaviours.roadmap.vision`); it stops at the first image in which a
target matches (the one with the most inliers when several do). ``ScanForTargets`` is that
scan for the learning mission; ``NavigateToTarget`` reuses :func:`scan` to localise.

A choice where the paper is vague: when the last sighting was from (nearly) the same position
and that target is still not found, homing to it from there failed; coverage sends the robot
back to the same position (its remaining headings are still uncovered), so this scan leaves
that target out and looks for the others, and the target is sought again from elsewhere.
Without this the search can sight, fail and return to the same target from the same place
until its rounds run out.

Another: a scan that found nothing turns back to where it started (``unwind``). Odometry that
counts turns a few percent short (2 % in the simulator, typical of a differential base) has
then made no net error: the robot truly turned as far back as forwards. A full scan left
wound up would leave about 7 degrees of heading error in the map's anchor, 0.35 m at 3 m.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from behaviours.ports import InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.roadmap.routine import ROUTINE_PORTS, Failed, RoutineBehaviour, Step
from behaviours.roadmap.targets import TARGETS_IN
from behaviours.roadmap.values import ScanRecord, Sighting, TargetView
from behaviours.roadmap.vision import MIN_INLIERS, Comparison, compare, describe
from maps.roadmap import Roadmap
from maps.room import RoomEstimate
from perception.geometry import Pose2D

MIN_INLIERS_IN = InputPort("min_inliers", int, MIN_INLIERS, minimum=8, maximum=10000, literal_only=True,
                           doc="correspondences agreeing on one planar motion for a match")
"""How many inliers make a match, for scans and homing alike."""


def best_match(host: RoutineBehaviour, candidates: Sequence[TargetView], min_inliers: int
               ) -> Step[tuple[tuple[TargetView, Comparison] | None, Pose2D]]:
    """One image at rest compared with every candidate: the best match (or None) and where the
    image was taken (odometry)."""
    frame, pose = yield from host.capture()
    features = describe(frame.image)
    best: tuple[TargetView, Comparison] | None = None
    for view in candidates:
        found = compare(features, frame.camera, view.features, view.camera)
        if found.matched(min_inliers) and (best is None or found.inliers > best[1].inliers):
            best = (view, found)
    return best, pose


def scan(host: RoutineBehaviour, candidates: Sequence[TargetView], images: int, min_inliers: int, *,
         unwind: bool = False) -> Step[tuple[Sighting | None, list[Pose2D]]]:
    """Turn through ``images`` headings, stop at the first image where a candidate matches.

    Returns the sighting (None when nothing matched) and the odometry poses of the images taken.
    With ``unwind``, a scan that found nothing turns back to its first heading (module docstring).
    """
    poses: list[Pose2D] = []
    for index in range(images):
        if index:
            yield from host.rotate(2.0 * math.pi / images, f"scanning: image {index + 1} of {images}")
        host.feedback_message = f"scanning: image {index + 1} of {images}"
        found, pose = yield from best_match(host, candidates, min_inliers)
        poses.append(pose)
        if found is not None:
            view, comparison = found
            return Sighting(view.name, pose, comparison.planar.bearing, comparison.planar.theta, comparison.inliers,
                            comparison.matches), poses
        yield  # one image's work per tick
    if unwind and len(poses) > 1:
        yield from host.rotate(-2.0 * math.pi / images * (len(poses) - 1), "turning back to the first heading")
    return None, poses


AGAIN_WITHIN = 0.3  # m: a scan this close to the last sighting's skips that target if it is still not found


@register
class ScanForTargets(RoutineBehaviour):
    """Take 12 images turning on the spot; stop at the first that matches a target not found yet.

    SUCCESS with the sighting when a target matches, FAILURE after a full turn without one.
    Either way ``scan`` records the position and the headings imaged (reference frame), which
    ``CoverageScoring`` marks as covered.
    """

    IMAGES = InputPort("images", int, 12, minimum=1, maximum=72, literal_only=True,
                       doc="images per position, evenly spaced over a full turn (paper: 12)")
    UNWIND = InputPort("unwind", bool, True, literal_only=True,
                       doc="after a scan that found nothing, turn back to the first heading (no net turn)")
    ROADMAP = InputPort("roadmap", Roadmap, Ref("/map/roadmap"), doc="targets already found (skipped)")
    ROOM = InputPort("room", RoomEstimate, Ref("/map/room"), doc="the room estimate (for the scan record)")
    SIGHTING = OutputPort("sighting", Sighting, "/map/sighting", doc="the target matched and where from")
    SCAN = OutputPort("scan", ScanRecord, "/map/scan", doc="the position and headings imaged (reference frame)")
    PORTS = (IMAGES, MIN_INLIERS_IN, UNWIND, TARGETS_IN, ROADMAP, ROOM, *ROUTINE_PORTS, SIGHTING, SCAN)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.scans = 0
        self.last: tuple[str, Pose2D] | None = None  # the last sighting: target, where from (reference frame)

    def routine(self) -> Step[None]:
        targets = self.get_input(TARGETS_IN, None)
        room = self.get_input(self.ROOM, None)
        if targets is None or room is None:
            raise Failed("no target images" if targets is None else "no room estimate")
        roadmap = self.get_input(self.ROADMAP, None)
        found = set(roadmap.names) if roadmap is not None else set()
        here = room.to_reference((yield from self.pose()))
        candidates = [v for v in targets.views if v.name not in found and not self._failed_here(v.name, here)]
        if not candidates:
            raise Failed("every target is found already" if not set(targets.names) - found else
                         f"no target left to look for from ({here.x:.1f}, {here.y:.1f})")
        sighting, poses = yield from scan(self, candidates, self.get_input(self.IMAGES),
                                          self.get_input(MIN_INLIERS_IN), unwind=self.get_input(self.UNWIND))
        self.scans += 1
        headings = tuple(room.to_reference(p).theta for p in poses)
        seen = sighting.target if sighting else ""
        self.set_output(self.SCAN, ScanRecord(self.scans, here.x, here.y, headings, seen))
        if sighting is None:
            raise Failed(f"no target in sight from ({here.x:.1f}, {here.y:.1f})")
        self.last = (sighting.target, here)
        self.set_output(self.SIGHTING, sighting)
        self.feedback_message = f"{sighting.target} in sight ({sighting.inliers} inliers)"

    def _failed_here(self, name: str, here: Pose2D) -> bool:
        """The last sighting was of this target from (nearly) here, and it is still not found: homing to it
        from here failed, so look for the others (and for it from elsewhere)."""
        return self.last is not None and self.last[0] == name and self.last[1].distance_to(here) < AGAIN_WITHIN
