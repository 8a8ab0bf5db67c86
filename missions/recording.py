"""Record a run to a rerun file (``--save F.rrd``): robot pose, command, behaviour statuses,
the camera images the mission grabbed (JPEG, at a watchable rate: :mod:`missions.images`).

Uses rerun's global recording (``rr.init`` + ``rr.save``), which writes to the file with no
viewer, so it works headless; open the file later with ``rerun F.rrd``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import py_trees
from py_trees.common import Status

from behaviours.telemetry import Arrows, Drawing, Draws, Event, Lines, Picture, Plot, Points, Reports
from missions.images import DEFAULT_RATE_HZ, ImageRate, jpeg

FIGURE_PERIOD = 1.0  # s of the run's clock between two plots of the nodes' figures (some are costly to gather)
STATUS_CODE = {Status.INVALID: 0, Status.RUNNING: 1, Status.SUCCESS: 2, Status.FAILURE: 3}


class Recorder:
    """Logs one entry per tick on the ``sim_time`` (or ``wall_time``) timeline."""

    def __init__(self, path: str | Path, *, mission: str, recording_id: str, timeline: str,
                 image_rate_hz: float | None = DEFAULT_RATE_HZ) -> None:
        import rerun as rr  # imported here: the viewer wheel is large and only needed with --save

        self.rr = rr
        self.timeline = timeline
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        rr.init("bearings", recording_id=recording_id, spawn=False)
        rr.save(str(self.path))
        self._last_status: dict[str, Status] = {}
        self._last_figure: dict[str, Any] = {}
        self.images = ImageRate(image_rate_hz)
        self._figures_at = -math.inf
        rr.log("tree/status_legend", rr.TextDocument("0 invalid, 1 running, 2 success, 3 failure"), static=True)

    def log_tick(self, *, time_s: float, tick: int, root: py_trees.behaviour.Behaviour, odometry: Any,
                 command: Any, observers: Sequence[Any] = (), nodes: Sequence[Any] = (),
                 frames: Mapping[str, Any] | None = None) -> None:
        rr = self.rr
        rr.set_time(self.timeline, duration=time_s)
        rr.set_time("tick", sequence=tick)
        if odometry is not None:
            # the odometry frame is not the world frame: its own space, so views never mix the two
            rr.log("odometry_frame/robot", rr.Points2D([[odometry.x, odometry.y]], radii=0.04))
            rr.log("robot/odometry/theta", rr.Scalars([odometry.theta]))
        if command is not None:
            rr.log("robot/command/v", rr.Scalars([command.v]))
            rr.log("robot/command/w", rr.Scalars([command.w]))
        for path, node in _walk(root, "", {}):
            rr.log(f"tree/{path}", rr.Scalars([STATUS_CODE[node.status]]))
            if self._last_status.get(path) != node.status:
                self._last_status[path] = node.status
                message = f"{path}: {node.status.value}" + (f" ({node.feedback_message})"
                                                             if node.feedback_message else "")
                rr.log("tree/events", rr.TextLog(message))
        for name, frame in self.images.due(frames or {}, time_s):
            self.image(f"camera/{name}", frame.image)
            if getattr(frame, "right", None) is not None:
                self.image(f"camera/{name}_right", frame.right)
        for observer in observers:
            observer.log_rerun(rr)
        figures = time_s - self._figures_at >= FIGURE_PERIOD
        if figures:
            self._figures_at = time_s
        for node in nodes:
            self.log_node(node, figures=figures)

    def image(self, entity: str, image: Any) -> None:
        """One image, JPEG-encoded (a tenth of the raw bytes of a camera image)."""
        self.rr.log(entity, self.rr.EncodedImage(contents=jpeg(image), media_type="image/jpeg"))

    def log_node(self, node: Any, *, figures: bool = True) -> None:
        """A node's drawings, and with ``figures`` its figures (the numbers that changed since last plotted)."""
        if figures and isinstance(node, Reports):
            for figure in node.figures():
                value = figure.value
                if isinstance(value, (int, float)) and not isinstance(value, bool):
                    parts = [figure.section, *figure.name.split(".")]  # a node's name may hold spaces
                    entity = "figures/" + "/".join(self.rr.escape_entity_path_part(p) for p in parts)
                    if self._last_figure.get(entity) != value:
                        self._last_figure[entity] = value
                        self.rr.log(entity, self.rr.Scalars([float(value)]))
        if isinstance(node, Draws):
            for drawing in node.drawings():
                self.draw(drawing)

    def draw(self, drawing: Drawing) -> None:
        """One drawing as the rerun archetype that shows it."""
        rr = self.rr
        match drawing:
            case Points(entity, positions, colours, radius, labels):
                positions = np.asarray(positions)
                kind = rr.Points3D if positions.ndim == 2 and positions.shape[1] == 3 else rr.Points2D
                rr.log(entity, kind(positions, radii=radius, colors=_colours(colours),
                                    labels=list(labels) or None))
            case Lines(entity, strips, colours, radius):
                three = any(np.asarray(s).shape[-1] == 3 for s in strips)
                kind = rr.LineStrips3D if three else rr.LineStrips2D
                rr.log(entity, kind(strips, colors=_colours(colours), radii=radius))
            case Arrows(entity, vectors, colours, origins, labels):
                rr.log(entity, rr.Arrows2D(vectors=vectors, origins=origins, colors=_colours(colours),
                                           labels=list(labels) or None))
            case Picture(entity, image):
                self.image(entity, image)
            case Event(entity, text):
                rr.log(entity, rr.TextLog(text))
            case Plot(entity, value):
                rr.log(entity, rr.Scalars([float(value)]))

    def log_stop(self, *, time_s: float, tick: int) -> None:
        """The stop every run ends with: the last command in the recording is a zero velocity."""
        rr = self.rr
        rr.set_time(self.timeline, duration=time_s)
        rr.set_time("tick", sequence=tick)
        rr.log("robot/command/v", rr.Scalars([0.0]))
        rr.log("robot/command/w", rr.Scalars([0.0]))
        rr.log("tree/events", rr.TextLog("run ended: base and pan-tilt unit commanded to stop"))

    def close(self) -> None:
        self.rr.disconnect()


def _colours(colours: Any) -> list[Any]:
    """rerun takes a list of colours: one for all, or one per item."""
    return [colours] if isinstance(colours, tuple) else list(colours)


def _walk(node: py_trees.behaviour.Behaviour, prefix: str, seen: dict[str, int]):
    """(entity path, node) for a node and its subtree; paths are sanitised, de-duplicated names."""
    name = "".join(c if c.isalnum() or c in "-_" else "_" for c in node.name) or "node"
    path = f"{prefix}/{name}" if prefix else name
    count = seen.get(path, 0)
    seen[path] = count + 1
    if count:
        path = f"{path}_{count}"
    yield path, node
    for child in node.children:
        yield from _walk(child, path, seen)
