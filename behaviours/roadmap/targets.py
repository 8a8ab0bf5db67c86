"""Target images in and out of a mission: load them, record where one is, check all were found.

Target images are files the user names (a folder of them for ``learn_targets``; the roadmap
file lists them for ``goto_target``), read through :func:`maps.store.read_bytes` (bounded, one
clear error) and decoded grey. A target's name is its file name without the extension.

Recording (``RecordTarget``) comes AFTER ``ReturnToReference`` in ``learn_targets``: the target's
pose relative to the reference is then the odometry of the single trip from the target (homed)
back to the reference (homed), not of everything since the reference was last seen (the paper
records the pose, then returns; recording after the return measures the same thing with the
drift of one trip instead of a whole search).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.ports import READS, InputPort, OutputPort, Ref
from behaviours.registry import register
from behaviours.roadmap.display import Drawn, roadmap_drawings, roadmap_figures, roadmap_section
from behaviours.roadmap.values import HomingResult, TargetImages, TargetView
from behaviours.roadmap.vision import FEATURES, describe
from behaviours.telemetry import Drawing, Figure
from maps.roadmap import Roadmap, Target
from maps.room import RoomEstimate
from maps.store import InputError, read_bytes

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".pgm", ".ppm", ".tif", ".tiff")
MAX_IMAGE_BYTES = 64 * 1024 * 1024
MAX_TARGETS = 100

MAX_FEATURES = InputPort("max_features", int, FEATURES, minimum=50, maximum=20000, literal_only=True,
                         doc="SIFT features per image")
TARGETS_OUT = OutputPort("targets", TargetImages, "/map/target_images", doc="the target images with their features")
TARGETS_IN = InputPort("targets", TargetImages, Ref("/map/target_images"), doc="the target images")


def read_image(path: str | os.PathLike) -> np.ndarray:
    """A grey image from a file; :class:`ValueError` with a one-line reason when it cannot be read."""
    try:
        data = read_bytes(path, limit=MAX_IMAGE_BYTES, what="an image")
    except InputError as exc:
        raise ValueError(str(exc.diagnostics[0])) from None
    image = cv2.imdecode(np.frombuffer(data, dtype=np.uint8), cv2.IMREAD_GRAYSCALE)
    if image is None or image.size == 0:
        raise ValueError(f"{path}: not an image OpenCV can read")
    return image


def target_view(name: str, path: str | os.PathLike, n_features: int = FEATURES) -> TargetView:
    """A target image file with its upright SIFT features."""
    image = read_image(path)
    return TargetView(name, image, describe(image, n_features), None, str(path))


def image_files(folder: str | os.PathLike) -> list[Path]:
    """The image files of a folder, sorted by name; ValueError when there are none or too many."""
    root = Path(folder)
    if not root.is_dir():
        raise ValueError(f"{folder}: not a folder of target images")
    files = sorted(p for p in root.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES and p.is_file())
    if not files:
        raise ValueError(f"{folder}: no image files ({', '.join(IMAGE_SUFFIXES)})")
    if len(files) > MAX_TARGETS:
        raise ValueError(f"{folder}: {len(files)} images, more than {MAX_TARGETS} targets")
    stems = [p.stem for p in files]
    twice = sorted({s for s in stems if stems.count(s) > 1})
    if twice:
        raise ValueError(f"{folder}: two images named {twice[0]!r} (names are file names without the extension)")
    return files


@register
class LoadTargetImages(BearingsBehaviour):
    """Read a folder of target images (one per target, named by file) and describe them (upright SIFT).

    FAILURE, saying why, when the folder is missing or empty or an image cannot be read.
    """

    FOLDER = InputPort("folder", str, file=READS,
                       doc="folder of target images (PNG, JPEG, ...); target name = file name")
    PORTS = (FOLDER, MAX_FEATURES, TARGETS_OUT)

    def update(self) -> Status:
        try:
            files = image_files(self.get_input(self.FOLDER))
            views = tuple(target_view(p.stem, p.resolve(), self.get_input(MAX_FEATURES)) for p in files)
        except ValueError as exc:
            self.feedback_message = str(exc)
            return Status.FAILURE
        self.set_output(TARGETS_OUT, TargetImages(views))
        self.feedback_message = f"{len(views)} targets: {', '.join(v.name for v in views)}"
        return Status.SUCCESS


@register
class LoadRoadmap(BearingsBehaviour):
    """Read a roadmap file and the target images it names (paths relative to the file's folder)."""

    FILE = InputPort("file", str, file=READS, doc="roadmap file written by learn_targets")
    ROADMAP = OutputPort("roadmap", Roadmap, "/map/roadmap", doc="targets (reference frame) and edges")
    PORTS = (FILE, MAX_FEATURES, ROADMAP, TARGETS_OUT)

    @classmethod
    def preview_outputs(cls, inputs: dict[str, Any]) -> dict[str, Any]:
        """At load time: the roadmap, when its file exists already (``missions/load_checks.py``)."""
        file = inputs.get(cls.FILE.name)
        if not isinstance(file, str) or not Path(file).is_file():
            return {}
        return {cls.ROADMAP.name: Roadmap.load(file)}

    def update(self) -> Status:
        path = Path(self.get_input(self.FILE))
        try:
            roadmap = Roadmap.load(path)
            views = tuple(target_view(t.name, resolve_image(path, t.image), self.get_input(MAX_FEATURES))
                          for t in roadmap.targets)
        except InputError as exc:
            self.feedback_message = str(exc.diagnostics[0])
            return Status.FAILURE
        except ValueError as exc:
            self.feedback_message = str(exc)
            return Status.FAILURE
        self.set_output(self.ROADMAP, roadmap)
        self.set_output(TARGETS_OUT, TargetImages(views))
        self.feedback_message = f"{len(roadmap.targets)} targets, {len(roadmap.edges)} edges"
        return Status.SUCCESS


def resolve_image(roadmap_file: Path, image: str) -> Path:
    """A target image path stored in a roadmap: relative to the roadmap file's folder."""
    if not image:
        raise ValueError(f"{roadmap_file}: a target has no image file")
    path = Path(image)
    return path if path.is_absolute() else roadmap_file.parent / path


def relative_images(roadmap: Roadmap, roadmap_file: str | os.PathLike) -> Roadmap:
    """The roadmap with image paths relative to the folder of the file it is saved to."""
    folder = Path(roadmap_file).resolve().parent
    targets = tuple(Target(t.name, t.pose, os.path.relpath(Path(t.image).resolve(), folder) if t.image else "")
                    for t in roadmap.targets)
    return Roadmap(targets, roadmap.edges)


@register
class RecordTarget(BearingsBehaviour):
    """Add the target just homed to the roadmap, with its pose relative to the reference pose.

    The pose is the homing result (odometry frame) expressed in the room's reference frame
    (``room.reference_pose``, refreshed by ``ReturnToReference``); see the module docstring for
    why this runs after the return.
    """

    HOMING = InputPort("homing", HomingResult, Ref("/map/homing"), doc="where the target is (odometry frame)")
    ROOM = InputPort("room", RoomEstimate, Ref("/map/room"), doc="room estimate: the reference pose in odometry")
    ROADMAP = InputPort("roadmap", Roadmap, Ref("/map/roadmap"), doc="the roadmap so far (none yet: empty)")
    ROADMAP_OUT = OutputPort("roadmap_out", Roadmap, "/map/roadmap", doc="the roadmap with this target")
    PORTS = (HOMING, ROOM, TARGETS_IN, ROADMAP, ROADMAP_OUT)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.drawn = Drawn()

    def update(self) -> Status:
        homing = self.get_input(self.HOMING, None)
        room = self.get_input(self.ROOM, None)
        if homing is None or room is None:
            self.feedback_message = "no homing result" if homing is None else "no room estimate"
            return Status.FAILURE
        roadmap = self.get_input(self.ROADMAP, None) or Roadmap()
        targets = self.get_input(TARGETS_IN, None)
        image = ""
        if targets is not None and homing.target in targets.names:
            image = targets.get(homing.target).source
        pose = room.to_reference(homing.pose)
        self.set_output(self.ROADMAP_OUT, roadmap.with_target(homing.target, pose, image))
        self.feedback_message = f"{homing.target} at ({pose.x:.2f}, {pose.y:.2f})"
        return Status.SUCCESS

    def figures(self) -> Iterator[Figure]:
        roadmap = self.get_input(self.ROADMAP, None)
        if roadmap is not None:
            yield from roadmap_figures(roadmap_section(roadmap))

    def drawings(self) -> Iterator[Drawing]:
        roadmap = self.get_input(self.ROADMAP, None)
        if roadmap is not None and self.drawn.changed("roadmap", roadmap):
            yield from roadmap_drawings(roadmap)


@register
class AllTargetsFound(BearingsBehaviour):
    """SUCCESS when every target image has a place in the roadmap, FAILURE otherwise."""

    KIND = "condition"
    ROADMAP = InputPort("roadmap", Roadmap, Ref("/map/roadmap"), doc="the roadmap so far")
    PORTS = (TARGETS_IN, ROADMAP)

    def update(self) -> Status:
        targets = self.get_input(TARGETS_IN, None)
        roadmap = self.get_input(self.ROADMAP, None)
        if targets is None:
            self.feedback_message = "no target images"
            return Status.FAILURE
        found = set(roadmap.names) if roadmap is not None else set()
        missing = [n for n in targets.names if n not in found]
        self.feedback_message = f"missing: {', '.join(missing)}" if missing else "all found"
        return Status.FAILURE if missing else Status.SUCCESS
