"""A synthetic taught route: landmarks around a planar path, and what a robot sees along it.

For the LT-map tests and its benchmark, where the truth must be known: which landmark is which,
from where it can be seen, how far it is. Near landmarks stand on both sides of a corridor along
the x axis, each detectable up to its own range; far landmarks (10 km) are seen from everywhere.
An observation holds either the landmarks' ids (the simulator's ideal bearings sensor) or ORB-like
descriptors: one random 256-bit row per landmark with a few bits flipped per sighting, so that
Hamming matching behaves as it does on real ORB (a true match is far closer than any other row).
Optional extras per frame: dropouts (a landmark missed now and then) and flickering clutter seen
in one frame only (what the learner must reject as volatile). Pure numpy; no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from perception.features import Features
from perception.geometry import Pose2D
from perception.observation import Observation
from perception.synthetic import unit

DESCRIPTOR_BYTES = 32  # ORB: 256 bits
CLUTTER_ID_BASE = 1 << 40  # ids of one-frame clutter, far above any landmark's


@dataclass(frozen=True)
class RouteWorld:
    """Landmarks: ``positions`` (L x 3, m), detection ``ranges`` (L, m; inf for far ones),
    ``descriptors`` (L x 32 uint8) and which are ``far``. Landmark ``i`` has id ``i``."""

    positions: np.ndarray
    ranges: np.ndarray
    descriptors: np.ndarray
    far: np.ndarray

    def __len__(self) -> int:
        return len(self.positions)


def make_route_world(
    seed: int = 0,
    *,
    length: float = 8.0,
    n_far: int = 80,
    n_near: int = 800,
    half_width: tuple[float, float] = (0.6, 3.0),
    detect_range: tuple[float, float] = (1.5, 4.0),
) -> RouteWorld:
    """``n_near`` landmarks within ``half_width`` metres of the x axis along ``[-2, length + 2]`` m,
    each detectable up to a range drawn from ``detect_range``, and ``n_far`` landmarks at 10 km."""
    rng = np.random.default_rng(seed)
    side = rng.choice([-1.0, 1.0], size=n_near)
    near = np.column_stack((
        rng.uniform(-2.0, length + 2.0, n_near),
        side * rng.uniform(*half_width, n_near),
        rng.uniform(-0.5, 1.5, n_near),
    ))
    az, el = rng.uniform(-np.pi, np.pi, n_far), np.radians(rng.uniform(0.0, 20.0, n_far))
    far = 1e4 * np.column_stack((np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)))
    ranges = np.concatenate((np.full(n_far, np.inf), rng.uniform(*detect_range, n_near)))
    descriptors = rng.integers(0, 256, size=(n_far + n_near, DESCRIPTOR_BYTES), dtype=np.uint8)
    return RouteWorld(np.vstack((far, near)), ranges, descriptors, np.arange(n_far + n_near) < n_far)


def straight_route(length: float = 8.0, step: float = 0.05, *, heading: float = 0.0) -> list[Pose2D]:
    """Poses every ``step`` metres from the origin along x, the robot facing ``heading`` (rad)."""
    count = int(round(length / step)) + 1
    return [Pose2D(i * step, 0.0, heading, stamp=0.1 * i) for i in range(count)]


def visible(world: RouteWorld, pose: Pose2D) -> np.ndarray:
    """Indices of the landmarks detectable from ``pose`` (within their range)."""
    distance = np.hypot(world.positions[:, 0] - pose.x, world.positions[:, 1] - pose.y)
    return np.flatnonzero(distance < world.ranges)


def observe_route(
    world: RouteWorld,
    pose: Pose2D,
    rng: np.random.Generator,
    *,
    kind: str = "ids",
    noise_deg: float = 0.0,
    dropout: float = 0.0,
    clutter: int = 0,
    bit_flips: int = 6,
) -> Observation:
    """What the robot sees at ``pose``: camera body-frame bearings (x forward, y left, z up) with
    ids (``kind="ids"``, sorted) or ORB-like descriptors (``kind="orb"``, shuffled). ``dropout``:
    chance to miss a visible landmark; ``clutter``: one-frame landmarks at random bearings."""
    seen = visible(world, pose)
    seen = seen[rng.random(len(seen)) >= dropout]
    c, s = np.cos(pose.theta), np.sin(pose.theta)
    world_to_body = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    bearings = unit((world.positions[seen] - [pose.x, pose.y, 0.0]) @ world_to_body.T)
    bearings = np.vstack((bearings, unit(rng.normal(size=(clutter, 3)))))
    if noise_deg > 0:
        bearings = unit(bearings + rng.normal(0.0, np.radians(noise_deg), bearings.shape))
    if kind == "ids":
        ids = np.concatenate((seen, CLUTTER_ID_BASE + rng.choice(1 << 30, clutter, replace=False))).astype(np.int64)
        order = np.argsort(ids)
        return Observation(bearings[order], pose.stamp, "bearings", ids=ids[order])
    descriptors = np.vstack((world.descriptors[seen],
                             rng.integers(0, 256, size=(clutter, DESCRIPTOR_BYTES), dtype=np.uint8)))
    descriptors = _flip_bits(descriptors, bit_flips, rng)
    order = rng.permutation(len(bearings))
    features = Features(np.zeros((len(order), 2)), descriptors[order], "orb")
    return Observation(bearings[order], pose.stamp, "panorama", features=features)


def _flip_bits(descriptors: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """Each row with ``count`` random bits flipped (appearance noise between sightings)."""
    bits = np.unpackbits(descriptors, axis=1)
    if count and len(bits):
        rows = np.repeat(np.arange(len(bits)), count)
        columns = rng.integers(0, bits.shape[1], size=len(rows))
        bits[rows, columns] ^= 1
    return np.packbits(bits, axis=1)
