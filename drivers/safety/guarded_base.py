"""A :class:`~drivers.interfaces.Base` that passes every command through the collision monitor.

The runner wraps the robot's base in it before the tree is set up (``missions/runner.py``), on
the robot and in the simulator alike, whatever the mission: every ``drive(v, w)`` reads the
newest scan of the robot's :class:`~drivers.interfaces.RangeSource`, asks
:class:`~perception.collision_monitor.CollisionMonitor` for the limited command against it and
the echoes of the last ``memory`` seconds (kept where the base's odometry put them,
:class:`~perception.obstacle_memory.ObstacleMemory`), records the
verdict (:class:`~drivers.safety.log.SafetyLog`) and sends the limited command to the base. Each
transducer's successive readings say how fast what it hears closes on the robot by itself
(:class:`~perception.closing.ClosingEchoes`): a walker's echo is judged where it is now, not where
the transducer last heard it.
``stop()`` goes straight through (stopping is always allowed), as do ``odometry()``,
``stalled()``, ``close()`` and anything else the wrapped driver offers (``status()``,
``report_sections()``...).

A robot without a range source has nothing to monitor: commands pass unchanged and the log says
``sources: none``. A source that gives no scan, or an old one, is a blind robot: it crawls.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from drivers.interfaces import Base, RangeSource
from drivers.safety.log import SafetyLog
from perception.closing import ClosingEchoes
from perception.collision_monitor import CollisionMonitor, SafetyState, Verdict
from perception.geometry import Pose2D
from perception.obstacle_memory import ObstacleMemory
from perception.ranges import RangeScan


class GuardedBase:
    """``base`` behind ``monitor``, fed by ``ranges`` and stamped by ``clock`` (the run's clock)."""

    def __init__(self, base: Base, monitor: CollisionMonitor, ranges: RangeSource | None,
                 clock: Callable[[], float]) -> None:
        self.base = base
        self.monitor = monitor
        self.ranges = ranges
        self.clock = clock
        self.state = SafetyState(reason="no command yet")
        self.scan: RangeScan | None = None
        self.memory = ObstacleMemory(keep=monitor.config.memory)
        self.closing = ClosingEchoes()
        self.log = SafetyLog(sources=_describe(ranges))

    def drive(self, v: float, w: float) -> None:
        """Send ``(v, w)`` limited by the monitor against the newest scan."""
        now = self.clock()
        if self.ranges is None:
            verdict = Verdict(v, w, SafetyState(reason="no range sensors", stamp=now))
        else:
            self.scan = self.ranges.read()
            pose = self._pose(self.scan)  # one odometry read for both: they judge the same scan
            judged, speeds = self._closing(self.scan, pose, now)
            verdict = self.monitor.check(v, w, judged, now, self._remembered(self.scan, pose, now), speeds)
        self.state = verdict.state
        self.log.add(v, w, verdict)
        self.base.drive(verdict.v, verdict.w)

    def _pose(self, scan: RangeScan | None) -> Pose2D | None:
        """The base's odometry, when the closing speeds or the memory need it for ``scan``."""
        if scan is None or not (self.monitor.config.closing or self.memory.keep > 0.0):
            return None
        return self.base.odometry()

    def _closing(self, scan: RangeScan | None, pose: Pose2D | None,
                 now: float) -> tuple[RangeScan | None, np.ndarray | None]:
        """``scan`` with its closing echoes where they are now, and each point's closing speed."""
        if scan is None or pose is None or not self.monitor.config.closing:
            return scan, None
        self.closing = self.closing.added(scan, pose)
        return self.closing.judged(scan, now)

    def _remembered(self, scan: RangeScan | None, pose: Pose2D | None, now: float) -> np.ndarray | None:
        """The echoes of earlier scans (within ``memory`` seconds) in the base frame now; the new
        scan joins them for the next command. Only those in the ring's blind gaps count: where a
        transducer looks now, its own reading says what is there (``RangeScan.covers``)."""
        if scan is None or pose is None or self.memory.keep <= 0.0:
            return None
        earlier = self.memory.around(pose, now)
        self.memory = self.memory.added(scan.points(), pose, scan.stamp)
        return earlier[~scan.covers(earlier)]

    def stop(self) -> None:
        self.base.stop()

    def odometry(self) -> Pose2D:
        return self.base.odometry()

    def stalled(self) -> bool:
        return self.base.stalled()

    def close(self) -> None:
        self.base.close()

    def __getattr__(self, name: str) -> Any:
        return getattr(self.base, name)  # the wrapped driver's own extras (status(), report_sections()...)


def _describe(ranges: RangeSource | None) -> str:
    """What the monitor sees with, for the report (``none``: it sees nothing)."""
    if ranges is None:
        return "none"
    describe = getattr(ranges, "describe", None)
    return str(describe()) if callable(describe) else type(ranges).__name__
