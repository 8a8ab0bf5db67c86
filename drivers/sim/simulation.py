"""The simulated robot: world, base, pan-tilt and cameras stepped by the runner's clock.

The runner only uses this API: :meth:`Simulation.load`, :attr:`Simulation.robot`,
:meth:`Simulation.clock` (which steps the world), :meth:`Simulation.report_sections` and
:meth:`Simulation.log_rerun`;
perception benchmarks and ``bearings sim snapshot`` use :meth:`Simulation.snapshot`.
Ground truth stays in here; behaviours only see the :class:`~drivers.interfaces.Robot`
interfaces, exactly as on hardware.

People (:mod:`drivers.sim.people`) walk on the simulated clock and stop for the robot; the robot
stops at contact with a wall, box, pillar or person. The base has the world's sonar ring and
bumpers (:mod:`drivers.sim.ranges`) as ``robot.ranges``.

Determinism: every source of randomness is a numpy Generator derived from the seed (wheel slip
from ``seed`` itself, each camera and the run's lighting from their own spawned streams, the sonar
from a stream of its own, so adding a camera does not change the robot's motion). Same world and
seed: same trajectory, bit-identical images, ranges and reports.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from drivers.interfaces import Camera, Robot
from drivers.sim.cameras import SimCamera, run_lighting
from drivers.sim.kinematics import DiffDrive, DiffDriveLimits, SlipModel
from drivers.sim.people import Crowd
from drivers.sim.ptu import SimPanTilt
from drivers.sim.ranges import SimRanges
from drivers.sim.scene import Scene
from drivers.sim.visualise import RerunLogger
from drivers.sim.world import load_world
from drivers.sim.world_values import World, empty_world
from perception.frame import Frame, LandmarkBearings
from perception.geometry import Pose2D, frame_to_parent, parent_to_frame, wrap_angle

CONTACT_PRECISION_M = 0.0005  # m: a blocked step ends this close to where the robot would touch


class SimClock:
    """Simulated time for the runner: :meth:`next_tick` steps the world by the tick period.

    Time is ``ticks * period`` exactly (no drift from summing the period), so a 5 s timeout in a
    mission lasts 50 ticks at 10 Hz whatever the floating-point history.
    """

    timeline = "sim_time"

    def __init__(self, sim: Simulation) -> None:
        self._sim = sim
        self._ticks = 0
        self._now = 0.0

    def now(self) -> float:
        return self._now

    def next_tick(self, period: float) -> None:
        self._sim.step(period)
        self._ticks += 1
        self._now = self._ticks * period


WATCHDOG_S = 2.0
"""The simulated base stops when no command arrives for this long, as a Pioneer's firmware does
(its config packet's Watchdog, 2000 ms; docs/protocols.md): a mission that leaves the base to run
on without commands stops in the simulator as it would on the robot."""
REPORTED_CONTACTS = 20  # collisions listed with their time and place in the report (all are counted)


class SimBase:
    """The :class:`~drivers.interfaces.Base` of the simulated robot."""

    def __init__(self, sim: Simulation) -> None:
        self._sim = sim
        self.commands: list[tuple[float, float, float]] = []  # (time, v, w) as received

    def drive(self, v: float, w: float) -> None:
        self.commands.append((self._sim.time, float(v), float(w)))
        self._sim.last_command = self._sim.time
        self._sim.drive.command(v, w)

    def stop(self) -> None:
        self.drive(0.0, 0.0)

    def odometry(self) -> Pose2D:
        return self._sim.drive.odometry(self._sim.time)

    def stalled(self) -> bool:
        return self._sim.stalled

    def close(self) -> None:
        pass


@dataclass
class GroundTruth:
    """True and odometry trajectories as (t, x, y, theta) rows, for evaluation only."""

    true: list[tuple[float, float, float, float]] = field(default_factory=list)
    odometry: list[tuple[float, float, float, float]] = field(default_factory=list)

    def record(self, t: float, true: Pose2D, odom: Pose2D) -> None:
        self.true.append((t, true.x, true.y, true.theta))
        self.odometry.append((t, odom.x, odom.y, odom.theta))


class Simulation:
    """A deterministic simulated world for one mission run."""

    def __init__(
        self,
        world: World | None = None,
        *,
        seed: int = 0,
        start: Pose2D | None = None,
        limits: DiffDriveLimits | None = None,
        slip: SlipModel | None = None,
        name: str | None = None,
        noise: bool = True,
    ) -> None:
        self.world = world or empty_world()
        self.name = name or self.world.name
        self.seed = seed
        self.rng = np.random.default_rng(seed)  # wheel slip
        streams = np.random.SeedSequence([seed, 0xBEA], pool_size=4).spawn(1 + len(self.world.cameras))
        self.scene = Scene(self.world)
        self.crowd = Crowd(self.world.people, room=self.scene.clearance)
        self.time = 0.0
        self.last_command = 0.0  # when the base last heard a drive command (the watchdog's clock)
        self.stalled = False
        self.collisions = 0
        self.collisions_with_people = 0
        self._in_contact = False
        self._stalled_time = 0.0
        self.drive = DiffDrive(start=start or self.world.start, limits=limits, slip=slip, rng=self.rng)
        self.min_clearance = self._clearance(*self.drive.true_pose[:2]) - self.world.robot_radius
        self._nearest_at: dict[str, Any] | None = None  # when and where the clearance was least, and to what
        self._contacts: list[dict[str, Any]] = []  # when and where each collision began, and with what
        self.ptu = SimPanTilt(self.world.ptu, clock=lambda: self.time)
        self.lighting = run_lighting(self.world.lighting, np.random.default_rng(streams[0]))
        self.cameras: dict[str, SimCamera] = {}
        for spec, stream in zip(self.world.cameras, streams[1:], strict=True):
            camera = SimCamera(
                spec, self.scene, self.world.ptu, self._camera_state, rng=np.random.default_rng(stream),
                lighting=self.lighting,
            )  # fmt: skip
            camera.enabled_noise = noise
            self.cameras[spec.name] = camera
        cameras: dict[str, Camera] = dict(self.cameras)
        sonar_rng = np.random.default_rng(np.random.SeedSequence([seed, 0x50AA]))
        self.ranges = SimRanges.of(self.world.ranges, self.scene, self._ranges_state, radius=self.world.robot_radius,
                                   rng=sonar_rng)
        self.robot = Robot(base=SimBase(self), ptu=self.ptu, cameras=cameras, ranges=self.ranges,
                           name=f"sim:{self.name}")
        self.truth = GroundTruth()
        self.truth.record(0.0, self.drive.true(0.0), self.drive.odometry(0.0))
        self._rerun = RerunLogger()

    @classmethod
    def load(cls, world: str | Path | World | None = None, *, seed: int = 0, **options: Any) -> Simulation:
        """The simulation of a shipped world (by name), a world file (by path) or a :class:`World`.

        None, "" or "empty": an empty plane. Invalid files raise :class:`~maps.store.InputError`
        with every problem located. ``options`` go to the constructor (``start``, ``limits``,
        ``slip``, ``noise``).
        """
        loaded = world if isinstance(world, World) else load_world(world)
        return cls(loaded, seed=seed, **options)

    # ----------------------------------------------------------------------------------------
    # Time

    def step(self, dt: float) -> None:
        """Advance the world by ``dt`` seconds of simulated time.

        A step that would bring the robot's disc into a wall, box, pillar or person (closer than
        it was) ends where the disc touches (within :data:`CONTACT_PRECISION_M`): the base stops
        there, its wheels and odometry included, the contact is counted (once per episode), and
        :meth:`SimBase.stalled` is True until a command moves it away. Then the people walk
        (:class:`~drivers.sim.people.Crowd`: they wait for the robot rather than walk into it). A base
        that has heard no command for :data:`WATCHDOG_S` stops, as the robot's firmware stops it.
        """
        drive = self.drive
        if self.time - self.last_command >= WATCHDOG_S - 1e-9 and drive.target != (0.0, 0.0):
            drive.command(0.0, 0.0)  # the firmware's watchdog: no command for WATCHDOG_S, the base stops
        before_true, before_odom = drive.true_pose.copy(), drive.odom_pose.copy()
        drive.step(dt, blocked=False)
        after_true, after_odom = drive.true_pose.copy(), drive.odom_pose.copy()
        radius = self.world.robot_radius
        swept = self._swept_clearance(before_true[:2], after_true[:2], radius)
        clearance, at_end, by_person, fixed_at_end = swept
        # blocked: touching, and closer than before (a robot in contact may still back away)
        if clearance < radius and clearance < self._clearance(before_true[0], before_true[1]) - 1e-12:
            f = self._contact_fraction(before_true[:2], after_true[:2], radius)
            drive.true_pose = _between(before_true, after_true, f)
            drive.odom_pose = _between(before_odom, after_odom, f)
            fixed_at_end = self.scene.clearance(*drive.true_pose[:2])
            drive.velocity = (0.0, 0.0)
            if not self._in_contact:  # a new contact episode (not the same push, step after step)
                self.collisions += 1
                self.collisions_with_people += int(by_person)
                if len(self._contacts) < REPORTED_CONTACTS:  # the rest are counted, not placed
                    self._contacts.append(self._where(self.time + dt, "person" if by_person else "surface"))
            self.stalled = self._in_contact = True
        else:
            self.stalled = False
            self._in_contact = self._in_contact and at_end < radius + 0.01
        if self.stalled:
            self._stalled_time += dt
        self.crowd.step(dt, drive.true_pose[:2], radius)
        self.scene.move_people(self.crowd.xy)
        self.ptu.step(dt)
        self.time += dt
        person = self.crowd.clearance(*drive.true_pose[:2])  # the people have moved
        here = min(fixed_at_end, person)
        if here - radius < self.min_clearance:
            self.min_clearance = here - radius
            self._nearest_at = self._where(self.time, "person" if person < fixed_at_end else "surface")
        self.truth.record(self.time, drive.true(self.time), drive.odometry(self.time))

    def _where(self, t: float, what: str) -> dict[str, Any]:
        """The time, the robot's true place and what it met, for the report."""
        x, y, theta = (float(v) for v in self.drive.true_pose[:3])
        return {"t": round(t, 2), "x": round(x, 3), "y": round(y, 3), "theta_deg": round(math.degrees(theta), 1),
                "with": what}

    def _clearance(self, x: float, y: float) -> float:
        """Distance (m) from (x, y) to the nearest wall, box face, pillar or person."""
        return min(self.scene.clearance(x, y), self.crowd.clearance(x, y))

    def _swept_clearance(self, start: np.ndarray, end: np.ndarray,
                         radius: float) -> tuple[float, float, bool, float]:
        """The smallest clearance along a step's straight path, sampled every radius / 2 (so a long
        step cannot jump over a thin wall), the clearance at its end, whether a person is the
        nearest thing where the clearance is smallest, and the walls', boxes' and pillars' alone at
        its end."""
        samples = max(1, math.ceil(math.hypot(end[0] - start[0], end[1] - start[1]) / (radius / 2.0)))
        points = [start + (end - start) * (i / samples) for i in range(1, samples + 1)]
        fixed = [self.scene.clearance(*p) for p in points]
        people = [self.crowd.clearance(*p) for p in points] if len(self.crowd) else [math.inf] * samples
        values = [min(a, b) for a, b in zip(fixed, people, strict=True)]
        nearest = min(range(samples), key=values.__getitem__)
        return values[nearest], values[-1], people[nearest] < fixed[nearest], fixed[-1]

    def _contact_fraction(self, start: np.ndarray, end: np.ndarray, radius: float) -> float:
        """The largest fraction of a blocked step (start -> end) the robot can drive before its disc
        touches (bisection to :data:`CONTACT_PRECISION_M`; 0 when that is less than it: pushing)."""
        length = math.hypot(end[0] - start[0], end[1] - start[1])
        lo, hi = 0.0, 1.0
        while (hi - lo) * length > CONTACT_PRECISION_M:
            mid = 0.5 * (lo + hi)
            if self._swept_clearance(start, start + (end - start) * mid, radius)[0] >= radius:
                lo = mid
            else:
                hi = mid
        return lo if lo * length >= 2 * CONTACT_PRECISION_M else 0.0

    def clock(self) -> SimClock:
        """A fresh clock that steps this world once per tick (hand it to the runner)."""
        return SimClock(self)

    # ----------------------------------------------------------------------------------------
    # Ground truth (evaluation only)

    HEADLINE = ("ground_truth.goal_error_m", "ground_truth.path_error_m", "ground_truth.trajectory_length_m")
    """The ground-truth figures the end-of-run line shows (besides collisions: ``missions/summary.py``)."""

    def report_sections(self, evaluation: Mapping[str, Any]) -> dict[str, Any]:
        """What a run report gets from the simulator: ``ground_truth`` against the mission's
        ``evaluation`` references (``goal``, ``reference_path``, ``frame``)."""
        return {"ground_truth": self.ground_truth_report(
            goal=evaluation.get("goal"), reference_path=evaluation.get("reference_path"),
            frame=evaluation.get("frame", "world"))}

    def true_pose(self) -> Pose2D:
        """The robot's true pose (evaluation only: never hand this to a behaviour)."""
        return self.drive.true(self.time)

    def odometry_in_world(self) -> np.ndarray:
        """Where odometry believes the robot is, as world (x, y): odometry starts at the true start."""
        return frame_to_parent(_pose_of(self.truth.true[0]), np.asarray(self.truth.odometry[-1:])[:, 1:3])[0]

    def true_trajectory(self) -> np.ndarray:
        """The whole true trajectory as world (x, y) rows."""
        return np.asarray(self.truth.true)[:, 1:3]

    def people_xy(self) -> np.ndarray:
        """Where every person is now, world (x, y) rows in the world's order (evaluation only)."""
        return self.crowd.xy.copy()

    def odometry_trajectory_in_world(self) -> np.ndarray:
        """The whole odometry trajectory as world (x, y) rows."""
        return frame_to_parent(_pose_of(self.truth.true[0]), np.asarray(self.truth.odometry)[:, 1:3])

    def ground_truth_report(
        self,
        *,
        goal: Sequence[float] | None = None,
        reference_path: Sequence[Sequence[float]] | None = None,
        frame: str = "world",
    ) -> dict:
        """The ``ground_truth`` section of a run report (docs/design.md, contracts).

        Always: ``trajectory_length_m``, ``final_pose``, ``odometry_drift_m``, ``collisions`` (every
        contact episode: the robot ran into something), ``collisions_with_people`` (those of them
        with a person; people stop for the robot, so a contact is always the robot's doing),
        ``min_clearance_m`` (the smallest distance from the robot's disc to any wall, box, pillar
        or person over the run; None in a world with nothing in it), ``min_clearance_at`` (when,
        where the robot was, and whether a ``person`` or a ``surface``; None when the start was the
        nearest), ``collisions_at`` (the same for the first :data:`REPORTED_CONTACTS` collisions),
        ``stalled_time_s``,
        ``trajectory`` (decimated), ``stops`` (every stretch the robot stood still, exactly: see
        :func:`_stops`) and the true ``landmarks``; with ``goal``
        (x, y): ``goal_error_m``; with a ``reference_path`` of (x, y) points: ``path_error_m``
        (mean distance of the trajectory to it) and ``path_error_max_m``. ``goal`` and
        ``reference_path`` are world coordinates, or with ``frame="start"`` coordinates relative
        to the robot's true start pose (for missions written for any world, like odometry).
        """
        if frame not in ("world", "start"):
            raise ValueError(f"frame must be 'world' or 'start', got {frame!r}")
        true = np.asarray(self.truth.true, dtype=float)
        xy = true[:, 1:3]
        if frame == "start":  # express the trajectory in the start frame instead
            xy = parent_to_frame(_pose_of(true[0]), xy)
        report: dict = {
            "world": self.name,
            "seed": self.seed,
            "sim_time_s": float(self.time),
            "evaluation_frame": frame,
            "trajectory_length_m": float(np.sum(np.linalg.norm(np.diff(xy, axis=0), axis=1))),
            "final_pose": {"x": float(true[-1, 1]), "y": float(true[-1, 2]), "theta": float(true[-1, 3])},
            "odometry_drift_m": float(np.linalg.norm(true[-1, 1:3] - self.odometry_in_world())),
            "collisions": int(self.collisions),
            "collisions_with_people": int(self.collisions_with_people),
            "min_clearance_m": float(self.min_clearance) if math.isfinite(self.min_clearance) else None,
            "min_clearance_at": self._nearest_at,
            "collisions_at": list(self._contacts),
            "stalled_time_s": float(self._stalled_time),
            "trajectory": _decimate(true, max_points=2000),
            "stops": _stops(true),
            "landmarks": [[int(lm.id), lm.x, lm.y, lm.z] for lm in self.world.landmarks],
            # where odometry believed the robot was, (t, x, y) in the world (odometry starts at the true start)
            "odometry_trajectory": _decimate(np.column_stack([np.asarray(self.truth.odometry)[:, 0],
                                                              self.odometry_trajectory_in_world()]), max_points=2000),
        }
        if goal is not None:
            report["goal_error_m"] = float(math.hypot(xy[-1, 0] - goal[0], xy[-1, 1] - goal[1]))
        if reference_path is not None and len(reference_path) >= 2:
            distances = path_distances(xy, np.asarray(reference_path, dtype=float)[:, :2])
            report["path_error_m"] = float(distances.mean())
            report["path_error_max_m"] = float(distances.max())
        return report

    # ----------------------------------------------------------------------------------------
    # Cameras

    def snapshot(
        self, pose: Pose2D, camera: str = "panorama", *, pan: float | None = None, tilt: float | None = None
    ) -> Frame:
        """What image camera ``camera`` would see with the robot at the TRUE ``pose``.

        A pan-tilt mounted camera uses the unit's current angles unless ``pan``/``tilt`` are given.
        Clean: the run's lighting, no exposure noise, never dropped. Stamped with the current time.
        """
        cam = self._camera(camera)
        state = self.ptu.state()
        return cam.snapshot(
            pose, state.pan if pan is None else pan, state.tilt if tilt is None else tilt, stamp=self.time
        )

    def observe(self, pose: Pose2D, camera: str = "landmarks") -> LandmarkBearings:
        """Noise-free landmark bearings of a ``bearings`` sensor at the TRUE ``pose``."""
        state = self.ptu.state()
        return self._camera(camera).observe(pose, state.pan, state.tilt, stamp=self.time)

    def _camera(self, name: str) -> SimCamera:
        if name not in self.cameras:
            raise KeyError(f"no camera {name!r} in world {self.name!r} (cameras: {', '.join(self.cameras)})")
        return self.cameras[name]

    def _camera_state(self) -> tuple[Pose2D, float, float, float]:
        return self.true_pose(), self.ptu.pan, self.ptu.tilt, self.time

    def _ranges_state(self) -> tuple[Pose2D, float]:
        return self.true_pose(), self.time

    # ----------------------------------------------------------------------------------------
    # Visualisation

    def log_rerun(self, rec: Any) -> None:
        """Log this tick to rerun (``rec``: the rerun module or a RecordingStream).

        Once: the world from above (walls, pillars, landmarks, named poses, static). Every call:
        the true and odometry poses, heading and pan-tilt view direction. Every 20th call: the
        trajectories. Camera images are the recorder's (the frames the mission grabbed).
        """
        self._rerun.log(self, rec)


def _between(a: np.ndarray, b: np.ndarray, f: float) -> np.ndarray:
    """The (x, y, theta) pose a fraction ``f`` of the way from ``a`` to ``b`` (the shorter turn)."""
    theta = wrap_angle(a[2] + f * wrap_angle(b[2] - a[2]))
    return np.array([a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), theta])


def path_distances(trajectory_xy: np.ndarray, reference_xy: np.ndarray) -> np.ndarray:
    """Distance (m) from each trajectory point to the reference polyline."""
    a, b = reference_xy[:-1], reference_xy[1:]
    ab = b - a
    seg_len2 = np.maximum(np.sum(ab * ab, axis=1), 1e-12)
    p = trajectory_xy[:, None, :]
    t = np.clip(np.sum((p - a) * ab, axis=2) / seg_len2, 0.0, 1.0)
    closest = a + t[..., None] * ab
    return np.linalg.norm(p - closest, axis=2).min(axis=1)


def _pose_of(row: Sequence[float]) -> Pose2D:
    """The pose of a trajectory row (t, x, y, theta)."""
    _, x, y, theta = row
    return Pose2D(float(x), float(y), float(theta))


def _stops(rows: np.ndarray, *, tolerance: float = 1e-6) -> list[list[float]]:
    """Every stretch of (t, x, y, theta) rows over which the robot stood still (no step moved it
    more than ``tolerance`` m or rad: a still robot does not move at all in the simulator):
    ``[t_first, t_last, x, y, theta]``, rounded as the trajectory.

    The decimated trajectory cannot say where the robot was at a given time to better than its
    spacing (up to half a second in a long run, with a turn starting right after a still image);
    an evaluation that needs the true pose when an image was taken finds the stop holding that
    time here instead (images are taken standing still)."""
    if len(rows) < 2:
        return []
    still = np.all(np.abs(np.diff(rows[:, 1:4], axis=0)) <= tolerance, axis=1).astype(np.int8)
    edges = np.diff(np.concatenate([[0], still, [0]]))
    first, end = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)  # step runs [first, end)
    out = np.column_stack([rows[first, 0], rows[end, 0], rows[first, 1:4]])
    return np.round(out, 4).tolist()


def _decimate(rows: np.ndarray, *, max_points: int) -> list[list[float]]:
    """At most ``max_points`` rows of (t, x, y, theta), first and last kept, rounded to 0.1 mm."""
    if len(rows) > max_points:
        idx = np.unique(np.linspace(0, len(rows) - 1, max_points).round().astype(int))
        rows = rows[idx]
    return np.round(rows, 4).tolist()
