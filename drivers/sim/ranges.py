"""The simulated sonar ring and bumpers: a :class:`~drivers.interfaces.RangeSource` of the base.

The ring is the robot model's (:mod:`drivers.pioneer_body`: a Pioneer 3-DX's or 3-AT's 16
transducers from ARIA's parameter files). Like the real one it fires in turn: in each ring (front
0-7, rear 8-15) one transducer every :data:`FIRING_PERIOD_S` of simulated time, the two rings
together, so each transducer is refreshed every 0.32 s and a reading can be that old; a transducer
that has not fired yet reads ``nan``. A firing casts :data:`RAYS_PER_CONE` rays across the
transducer's cone and hears the nearest wall, box face, pillar or person they meet (at any height:
everything in a world stands on the floor and is taller than a sonar), or the open end of a wall
anywhere in the cone, whichever is nearer: a wall is drawn as a line, but a real one is about
:data:`WALL_THICKNESS` thick, and its end (a door jamb) is an edge a sonar hears wherever it is in
the beam, where rays 7.5 degrees apart pass either side of it, or along a wall seen end-on
(:func:`wall_ends_in_cones`). Gaussian noise of
``noise`` metres is added, an echo beyond ``max_range`` is ``inf``, nearer than the transducer's
``min_range`` reads ``min_range``, and with probability ``miss_probability`` the firing hears
nothing (``inf``: a specular reflection, a soft surface). Firings are computed when the ring is
read, at the pose of the read (at most one tick late), with every firing since the last read
done in its order and stamped with the read's time (``RangeScan.fired``: what they measured is the world
then); noise and misses draw from the run's own seeded stream, so the same seed gives
the same readings.

Not modelled: specular reflections at grazing angles, cross-talk, the cone's lobes, and a wall end
hidden in the cone behind something its rays do not meet (the nearer thing is heard when they do).

Bumpers: a segment is pressed while the robot's disc touches something (within
:data:`CONTACT_M`: the simulator stops a robot at contact) and the point touched is nearer, in
bearing, to that segment than to any other on the same side (front: within 90 degrees of
straight ahead).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from drivers.pioneer_body import BODIES, RING_SIZE
from drivers.sim.scene import Scene
from drivers.sim.world_values import RangeSpec
from perception.geometry import Pose2D, frame_to_parent, wrap_angle, wrap_angles
from perception.ranges import Bumper, RangeScan, RangeSensor

FIRING_PERIOD_S = 0.04  # s: one transducer per ring every 40 ms (25 Hz, the Pioneer 3's rate)
RAYS_PER_CONE = 5
WALL_THICKNESS = 0.1  # m: a wall drawn as a line, where a sonar meets its open end
CONTACT_M = 0.01  # m: a bumper closes this near (the simulator stops the robot within 1 mm of contact)


def wall_ends_in_cones(origins: np.ndarray, headings: np.ndarray, fov: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Range from each transducer (``origins`` N x 2, world ``headings`` and whole cone ``fov``, rad) to
    the nearest wall end's face (a disc :data:`WALL_THICKNESS` across at each of ``ends``, E x 2) any
    part of which is in its cone; inf: none."""
    if len(ends) == 0 or len(origins) == 0:
        return np.full(len(origins), np.inf)
    radius = WALL_THICKNESS / 2.0
    offset = ends[None, :, :] - origins[:, None, :]  # (N, E, 2)
    distance = np.hypot(offset[..., 0], offset[..., 1])
    off_axis = np.abs(wrap_angles(np.arctan2(offset[..., 1], offset[..., 0]) - headings[:, None]))
    half = np.arcsin(np.clip(radius / np.maximum(distance, radius), 0.0, 1.0))  # half the disc's width seen
    inside = off_axis <= fov[:, None] / 2.0 + half
    return np.where(inside, np.maximum(distance - radius, 0.0), np.inf).min(axis=1)


class SimRanges:
    """The range sensors of a simulated base; ``state()`` gives the true pose and the time now."""

    def __init__(self, sensors: tuple[RangeSensor, ...], bumpers: tuple[Bumper, ...], spec: RangeSpec, scene: Scene,
                 state: Callable[[], tuple[Pose2D, float]], *, radius: float, rng: np.random.Generator) -> None:
        self.sensors, self.bumpers, self.spec = sensors, bumpers, spec
        self.scene, self.radius, self.rng = scene, radius, rng
        self._state = state
        self._ranges = np.full(len(sensors), np.nan)
        self._fired = np.full(len(sensors), np.nan)  # when each reading was taken (the read that fired it)
        self._last_slot = -1  # the last firing slot done (slot k fires at k * FIRING_PERIOD_S)
        offsets = np.linspace(-0.5, 0.5, RAYS_PER_CONE)
        self._ray_angles = np.array([s.heading + s.fov * offsets for s in sensors]).reshape(-1, RAYS_PER_CONE)
        self._bumper_bearings = np.array([math.atan2(b.y, b.x) for b in bumpers])

    @classmethod
    def of(cls, spec: RangeSpec, scene: Scene, state: Callable[[], tuple[Pose2D, float]], *, radius: float,
           rng: np.random.Generator) -> SimRanges | None:
        """The ring and bumpers ``spec`` asks for on a robot of ``radius``, or None when it has neither."""
        body = BODIES[spec.sonar if spec.sonar != "none" else "p3dx"]  # bumpers: the Pioneer's five and five
        sensors = body.sensors(max_range=spec.max_range) if spec.sonar != "none" else ()
        bumpers = body.bumpers(radius) if spec.bumpers else ()
        if not sensors and not bumpers:
            return None
        return cls(sensors, bumpers, spec, scene, state, radius=radius, rng=rng)

    def read(self) -> RangeScan:
        """Every transducer's newest range (firing those due since the last read) and the bumpers."""
        pose, now = self._state()
        slot = math.floor(now / FIRING_PERIOD_S + 1e-9)
        if self.sensors and slot > self._last_slot:
            due = range(max(self._last_slot + 1, slot - RING_SIZE + 1), slot + 1)
            firing = [k % RING_SIZE + ring for k in due for ring in range(0, len(self.sensors), RING_SIZE)]
            self._fire(np.array(firing, dtype=int), pose)
            self._fired[firing] = now
        self._last_slot = max(self._last_slot, slot)
        return RangeScan(self.sensors, self._ranges.copy(), now, self.bumpers, self._pressed(pose),
                         fired=self._fired.copy())

    def _fire(self, which: np.ndarray, pose: Pose2D) -> None:
        """Range of each transducer in ``which`` (in that order) from ``pose``, with noise and misses."""
        origins = frame_to_parent(pose, np.array([(self.sensors[i].x, self.sensors[i].y) for i in which]))
        angles = self._ray_angles[which] + pose.theta  # (n, rays)
        dirs = np.stack([np.cos(angles), np.sin(angles)], axis=-1).reshape(-1, 2)
        true = self.scene.cast_rays(np.repeat(origins, RAYS_PER_CONE, axis=0), dirs)
        true = true.reshape(-1, RAYS_PER_CONE).min(axis=1)
        headings = np.array([self.sensors[i].heading for i in which]) + pose.theta
        fov = np.array([self.sensors[i].fov for i in which])
        true = np.minimum(true, wall_ends_in_cones(origins, headings, fov, self.scene.wall_ends))
        noise = self.rng.normal(0.0, 1.0, size=len(which)) * self.spec.noise
        missed = self.rng.random(len(which)) < self.spec.miss_probability
        for k, i in enumerate(which):
            sensor = self.sensors[i]
            heard = true[k] + noise[k]
            if missed[k] or not heard <= sensor.max_range:  # no echo, or too far (inf, nan)
                self._ranges[i] = math.inf
            else:
                self._ranges[i] = max(heard, sensor.min_range)

    def _pressed(self, pose: Pose2D) -> np.ndarray:
        """Which bumper segments touch something now (module docstring)."""
        pressed = np.zeros(len(self.bumpers), dtype=bool)
        if not self.bumpers:
            return pressed
        distance, direction = self.scene.nearest(pose.x, pose.y)
        if distance - self.radius >= CONTACT_M:
            return pressed
        bearing = wrap_angle(direction - pose.theta)
        front = abs(bearing) < math.pi / 2
        side = np.array([(b.facing > 0) == front for b in self.bumpers])
        gap = np.abs(np.angle(np.exp(1j * (self._bumper_bearings - bearing))))
        pressed[int(np.argmin(np.where(side, gap, np.inf)))] = True
        return pressed

    def close(self) -> None:
        pass
