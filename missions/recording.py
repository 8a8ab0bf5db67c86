"""Record a run to a rerun file (``--save F.rrd``): robot pose, command, behaviour statuses.

Uses rerun's global recording (``rr.init`` + ``rr.save``), which writes to the file with no
viewer, so it works headless; open the file later with ``rerun F.rrd``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import py_trees
from py_trees.common import Status

STATUS_CODE = {Status.INVALID: 0, Status.RUNNING: 1, Status.SUCCESS: 2, Status.FAILURE: 3}


class Recorder:
    """Logs one entry per tick on the ``sim_time`` (or ``wall_time``) timeline."""

    def __init__(self, path: str | Path, *, mission: str, recording_id: str, timeline: str) -> None:
        import rerun as rr  # imported here: the viewer wheel is large and only needed with --save

        self.rr = rr
        self.timeline = timeline
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        rr.init("bearings", recording_id=recording_id, spawn=False)
        rr.save(str(self.path))
        self._last_status: dict[str, Status] = {}
        rr.log("tree/status_legend", rr.TextDocument("0 invalid, 1 running, 2 success, 3 failure"), static=True)

    def log_tick(self, *, time_s: float, tick: int, root: py_trees.behaviour.Behaviour, odometry: Any,
                 command: Any, observers: Sequence[Any] = ()) -> None:
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
        for observer in observers:
            observer.log_rerun(rr)

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
