"""Replay a log as a robot (``bearings run MISSION --replay run.mcap``).

:class:`Replay` plays a log (:func:`~drivers.logs.reader.open_log`) back through the driver
interfaces: a :class:`~drivers.interfaces.Robot` whose base answers the logged odometry and stall
flag, whose pan-tilt unit the logged joint state, whose cameras the logged frames, whose range
source the logged ranges and bumpers, and a keyboard of the logged keys. Its clock
(:meth:`Replay.clock`, timeline ``replay_time``: rerun has a ``log_time`` of its own) plays the
log as the simulator's clock steps the world: each tick moves time on by the period and delivers
every message logged up to then, so the first tick sees what was logged at the log's start and
frames arrive as they were logged (their rate, their drops: a camera whose frame did not come in
since the last grab returns None). Messages are read one at a time as time reaches them; nothing
is loaded ahead. Times count from the log's first message.

Open loop: the mission's commands go nowhere. They are counted, and compared with the commands
the log holds at the same time (the report's ``replay`` section; the rerun recording plots the
logged command beside the mission's). When the log has no message left, the next tick raises
:class:`EndOfLog`: the run ends there (FAILURE, unless the mission ended first).

A log recorded with ``--record`` replays through the same mission to the same result: the same
readings at the same ticks (odometry headings through a quaternion and ranges through float32
are within rounding; lossless ``png`` images are the very pixels).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from drivers.interfaces import KeySource, PanTiltState, Robot, VelocityCommand
from drivers.logs import codec
from drivers.logs.replay_devices import ReplayCamera, ReplayRanges, describe_problem
from drivers.logs.source import LogError, LogMessage, LogReader
from drivers.logs.topics import Topics
from perception.geometry import Pose2D


class EndOfLog(Exception):  # noqa: N818 - not an error: the log has been played to its end
    """The log has no message left: the run ends here."""


class Replay:
    """A log played back as a robot, on the clock of :meth:`clock`."""

    def __init__(self, reader: LogReader, topics: Topics) -> None:
        self.reader = reader
        self.topics = topics
        self.contents = reader.contents()
        available = self.contents.types()
        self.path = Path(reader.path)
        self.now = 0.0
        self.origin_ns: int | None = None
        self.exhausted = False
        self.consumed = 0
        self._stream: Iterator[LogMessage] = reader.messages([t for t in topics.wanted() if t in available])
        self._next: LogMessage | None = None
        self.odometry: Pose2D | None = None
        self._origin_pose: Pose2D | None = None
        self._first_odometry = True
        self.stalled = False
        self.ptu_state: PanTiltState | None = None
        self._keys: list[str] = []
        self._logged_now: list[VelocityCommand] = []  # logged commands at the current time, in order
        self._logged_at = -1
        self._drives_now = 0
        self.commands = {"mission": 0, "compared": 0, "max_dv": 0.0, "max_dw": 0.0, "ptu": 0}
        self.cameras = {name: ReplayCamera(self, source, available) for name, source in topics.cameras.items()
                        if source.image in available}
        has_ranges = any(t in available for t in (*topics.ranges, *topics.bumpers))
        self.ranges = ReplayRanges(self) if has_ranges else None
        self._handlers = self._dispatch_table(available)
        self.robot = Robot(base=ReplayBase(self), ptu=ReplayPanTilt(self) if topics.ptu in available else None,
                           cameras=dict(self.cameras), ranges=self.ranges, name=f"replay:{self.path.name}")
        self.has_keys = topics.keys in available

    def _dispatch_table(self, available: dict[str, str]) -> dict[str, Callable[[LogMessage], None]]:
        topics = self.topics
        table: dict[str, Callable[[LogMessage], None]] = {
            topics.odometry: self._on_odometry, topics.stalled: self._on_stalled, topics.ptu: self._on_ptu,
            topics.keys: self._on_keys, topics.commands: self._on_command}
        if self.ranges is not None:
            ranges = self.ranges
            table[topics.tf_static] = ranges.on_mounting
            table.update({t: ranges.on_range for t in topics.ranges})
            table.update({t: ranges.on_bumper for t in topics.bumpers})
        for camera in self.cameras.values():
            table.update(camera.handlers())
        return {topic: handler for topic, handler in table.items() if topic in available}

    # -- time ----------------------------------------------------------------------------------------
    def clock(self) -> ReplayClock:
        """A fresh clock at the log's start (hand it to the runner)."""
        return ReplayClock(self)

    def advance_to(self, seconds: float) -> None:
        """Deliver every message logged up to ``seconds`` after the log's start."""
        self.now = seconds
        limit = codec.nanoseconds(seconds)
        while True:
            message = self._peek()
            if message is None:
                self.exhausted = True
                return
            if self.origin_ns is None:
                self.origin_ns = message.log_ns
            if message.log_ns - self.origin_ns > limit:
                return
            self._next = None
            self.consumed += 1
            handler = self._handlers.get(message.topic)
            if handler is not None:
                try:
                    handler(message)
                except (ValueError, KeyError, TypeError, IndexError) as exc:
                    raise LogError(f"{self.path}: {message.topic} at {self.log_seconds(message.log_ns):.3f} s: "
                                   f"{describe_problem(exc)}") from None

    def _peek(self) -> LogMessage | None:
        if self._next is None and not self.exhausted:
            self._next = next(self._stream, None)
        return self._next

    def log_seconds(self, log_ns: int) -> float:
        """A log time as seconds after the log's start."""
        return (log_ns - (self.origin_ns or 0)) / 1e9

    def stamp_seconds(self, message: LogMessage) -> float:
        """A message's header stamp as seconds after the log's start (its log time when unstamped)."""
        stamp = message.message.get("header", {}).get("stamp")
        ns = codec.time_ns(stamp) if stamp else 0
        return self.log_seconds(ns if ns else message.log_ns)

    # -- what the log says ---------------------------------------------------------------------------
    def _on_odometry(self, message: LogMessage) -> None:
        pose = codec.pose_from_odometry(message.message, self.stamp_seconds(message))
        if self._first_odometry:
            self._first_odometry = False
            if self.topics.rebase_odometry and (pose.x, pose.y, pose.theta) != (0.0, 0.0, 0.0):
                self._origin_pose = pose  # a run's odometry starts at the origin
        if self._origin_pose is not None:
            pose = pose.relative_to(self._origin_pose)
        self.odometry = pose

    def _on_stalled(self, message: LogMessage) -> None:
        self.stalled = bool(message.message["data"])

    def _on_ptu(self, message: LogMessage) -> None:
        self.ptu_state = codec.ptu_state_from(message.message, self.stamp_seconds(message), self.topics.ptu_joints)

    def _on_keys(self, message: LogMessage) -> None:
        self._keys += codec.keys_from(message.message)

    def _on_command(self, message: LogMessage) -> None:
        if message.log_ns != self._logged_at:
            self._logged_at, self._logged_now, self._drives_now = message.log_ns, [], 0
        self._logged_now.append(codec.command_from_twist(message.message))

    # -- what the mission does -----------------------------------------------------------------------
    def mission_command(self, v: float, w: float) -> None:
        """A command of the mission (sent nowhere): compared with the logged one at this time."""
        self.commands["mission"] += 1
        if self._drives_now < len(self._logged_now):
            logged = self._logged_now[self._drives_now]
            self.commands["compared"] += 1
            self.commands["max_dv"] = max(self.commands["max_dv"], abs(v - logged.v))
            self.commands["max_dw"] = max(self.commands["max_dw"], abs(w - logged.w))
        self._drives_now += 1

    def keyboard(self) -> KeySource:
        """The operator's keys as logged (the runner's keyboard opener); OSError when the log has none."""
        if not self.has_keys:
            raise OSError(f"the log {self.path.name} has no operator keys ({self.topics.keys})")
        return ReplayKeys(self)

    def take_keys(self) -> list[str]:
        keys, self._keys = self._keys, []
        return keys

    # -- the run's observer --------------------------------------------------------------------------
    def report_sections(self, evaluation: Any) -> dict[str, Any]:
        """The report's ``replay`` section: what was played and how the mission's commands compare."""
        contents = self.contents
        section: dict[str, Any] = {
            "log": str(self.path), "format": contents.format, "log_duration_s": round(contents.duration_s, 3),
            "played_s": round(self.now, 3), "messages": self.consumed, "ended": self.exhausted,
            "frames": {name: camera.delivered for name, camera in self.cameras.items()},
            "commands": {"mission": self.commands["mission"], "ptu": self.commands["ptu"]}}
        if self.commands["compared"]:
            section["commands"].update(compared=self.commands["compared"],
                                       max_dv=round(float(self.commands["max_dv"]), 6),
                                       max_dw=round(float(self.commands["max_dw"]), 6))
        if self.reader.cut:
            section["cut"] = self.reader.cut
        return {"replay": section}

    def log_rerun(self, rec: Any) -> None:
        """The logged command beside the mission's (``robot/command``) in the recording."""
        if self._logged_now:
            logged = self._logged_now[-1]
            rec.log("replay/logged_command/v", rec.Scalars([logged.v]))
            rec.log("replay/logged_command/w", rec.Scalars([logged.w]))

    def close(self) -> None:
        self.reader.close()


class ReplayClock:
    """The replay's clock: time is ``ticks * period`` after the log's start (no drift), and each
    tick delivers the messages logged up to it; :class:`EndOfLog` when none is left."""

    timeline = "replay_time"

    def __init__(self, replay: Replay) -> None:
        self._replay = replay
        self._ticks = 0
        self._now = 0.0
        replay.advance_to(0.0)

    def now(self) -> float:
        return self._now

    def next_tick(self, period: float) -> None:
        replay = self._replay
        if replay.exhausted:
            raise EndOfLog(f"the log {replay.path.name} ended at {self._now:.3f} s, before the mission did")
        self._ticks += 1
        self._now = self._ticks * period
        replay.advance_to(self._now)


class ReplayBase:
    """The logged odometry and stall flag; commands are counted and compared, never sent."""

    def __init__(self, replay: Replay) -> None:
        self._replay = replay

    def drive(self, v: float, w: float) -> None:
        self._replay.mission_command(float(v), float(w))

    def stop(self) -> None:
        pass

    def odometry(self) -> Pose2D:
        pose = self._replay.odometry
        return pose if pose is not None else Pose2D(stamp=self._replay.now)

    def stalled(self) -> bool:
        return self._replay.stalled

    def close(self) -> None:
        pass


class ReplayPanTilt:
    """The logged pan-tilt state; moves and halts are counted, never sent."""

    def __init__(self, replay: Replay) -> None:
        self._replay = replay

    def move(self, pan: float, tilt: float, speed: float) -> None:
        self._replay.commands["ptu"] += 1

    def halt(self) -> None:
        pass

    def state(self) -> PanTiltState:
        state = self._replay.ptu_state
        return state if state is not None else PanTiltState(stamp=self._replay.now)

    def close(self) -> None:
        pass


class ReplayKeys:
    """The operator's keys, as logged."""

    def __init__(self, replay: Replay) -> None:
        self._replay = replay

    def read(self) -> list[str]:
        return self._replay.take_keys()

    def close(self) -> None:
        pass

