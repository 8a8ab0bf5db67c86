"""The ``bearings`` sensor: which landmarks a camera sees, as noisy unit bearing vectors.

This is the fast mode for large experiments: no pixels, no feature detection, just the ids of the
landmarks in the field of view that no wall, box or pillar hides, with their bearings in the
camera body frame (x forward, y left, z up) perturbed by Gaussian angular noise. Behaviours get
what a perfect feature tracker would give them, never a range or a position.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drivers.sim.scene import Scene
from drivers.sim.world_values import CameraSpec
from perception.frame import LandmarkBearings


@dataclass(frozen=True, slots=True)
class BearingSensorModel:
    """The field of view of a ``bearings`` sensor (its "camera model" in a Frame-free world)."""

    azimuth_fov: float
    elevation_limits: tuple[float, float]
    max_range: float
    noise: float

    @property
    def kind(self) -> str:
        return "bearings"


def observe_landmarks(
    scene: Scene,
    spec: CameraSpec,
    eye: np.ndarray,
    rotation: np.ndarray,
    *,
    rng: np.random.Generator | None,
    stamp: float,
) -> LandmarkBearings:
    """The landmarks camera ``spec`` sees from ``eye`` (world, 3,) with body ``rotation`` (world from body).

    Visible: within ``max_range``, inside the azimuth field of view and elevation limits (in the
    camera body frame) and not occluded. With ``rng`` and a non-zero ``spec.noise``, each bearing
    is perturbed by an isotropic Gaussian angular error of ``spec.noise`` rad per axis.
    """
    points = scene.landmark_xyz
    if len(points) == 0:
        return LandmarkBearings(np.zeros(0, np.int64), np.zeros((0, 3)), stamp, spec.name)
    world = points - eye
    dist = np.linalg.norm(world, axis=1)
    body = (world @ rotation) / np.maximum(dist, 1e-12)[:, None]  # R^T v as row vectors
    az = np.arctan2(body[:, 1], body[:, 0])
    el = np.arctan2(body[:, 2], np.hypot(body[:, 0], body[:, 1]))
    lo, hi = spec.elevation_limits
    visible = (dist <= spec.max_range) & (dist > 1e-6) & (el >= lo) & (el <= hi)
    visible &= np.abs(az) <= spec.azimuth_fov / 2.0 + 1e-12
    idx = np.flatnonzero(visible)
    idx = idx[~scene.occluded(eye, points[idx])]
    bearings = body[idx]
    if rng is not None and spec.noise > 0 and len(idx):
        bearings = bearings + rng.normal(0.0, spec.noise, size=bearings.shape)
        bearings /= np.linalg.norm(bearings, axis=1, keepdims=True)
    order = np.argsort(scene.landmark_ids[idx], kind="stable")
    return LandmarkBearings(scene.landmark_ids[idx][order], bearings[order], stamp, spec.name)
