"""The target roadmap: a non-Euclidean graph between target images (docs/design.md, method 2, "Graph").

Nodes are the user's target images, each with its pose relative to the reference pose (the room
estimate's frame). An edge a -> b exists when the robot went from a to b and back: each way is
an estimate of the motion ``rotate(angle1), drive(distance), rotate(angle2)`` with a 3 x 3
covariance over ``(angle1, distance, angle2)`` (:class:`EdgeMotion`); the two estimates are
fused by covariance. Navigation takes the path of least total ``sigma_x + sigma_y``.

Choices where the paper is vague (each tested in ``tests/maps/test_roadmap.py``):

- **Fusion space**: the motion parameters themselves. The way back b -> a, ``(b1, d, b2)``, is
  the same relative placement as a -> b ``(pi - b2, d, pi - b1)``: a linear map, so reversing
  carries the covariance over exactly (``P S P^T``) with no linearisation. The two a -> b
  estimates are then fused in information form (``S = (S1^-1 + S2^-1)^-1``,
  ``m = S (S1^-1 m1 + S2^-1 m2)``), angles unwrapped around the first estimate. Covariances
  must be positive definite (no measurement is perfect).
- **Consistency gate**: two estimates whose difference has a squared Mahalanobis distance (under
  ``S1 + S2``) above the chi-square 99.9 % point for 3 degrees of freedom (16.27) describe
  different motions (a homing that converged on the wrong place, slipping wheels): fusing them
  would give a motion neither measured, so :func:`fuse` raises :class:`InconsistentEstimates`
  and the learning mission drops that edge as it drops a failed one. A fused distance below
  zero (possible when the distance is about its own standard deviation) is written as the same
  motion with ``(a1 + pi, -d, a2 - pi)``.
- **Edge cost** ``sigma_x + sigma_y``: the standard deviations of b's position in a's frame (x
  ahead, y left), by first-order propagation of the motion covariance through
  ``(d cos a1, d sin a1)``. It depends on the direction of travel, so the graph is directed:
  b -> a costs what the reversed motion's covariance says in b's frame.
- **Shortest path** and **connectivity**: ``scipy.sparse.csgraph`` (Dijkstra, connected
  components) on the cost matrix; a graph of zero or one target is connected.
- **File** (``kind = "roadmap"``, version 1, via :mod:`maps.mapfile`: checksummed, atomic):
  target names and image paths in the header's ``meta`` JSON (``targets``, ``images``: lists of
  strings, readable by ``bearings map info``), numbers in arrays: ``target_poses`` (N x 3: x, y,
  theta), ``edge_ends`` (E x 2 target indices, source first), ``edge_motions`` (E x 3),
  ``edge_covariances`` (E x 3 x 3). Loading checks shapes, indices, finiteness and covariances;
  anything wrong is one :class:`~maps.store.InputError` line.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components, dijkstra

from maps.mapfile import read_map_file, write_map_file
from maps.store import Diagnostic, InputError
from perception.geometry import Pose2D, wrap_angle

KIND = "roadmap"
VERSION = 1
_REVERSE = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # d(reversed)/d(motion)
_MIN_COST = 1e-12  # csgraph reads an explicit zero weight as "no edge"
CONSISTENCY_GATE = 16.27  # chi-square with 3 degrees of freedom at 99.9 %


def _check_covariance(covariance: np.ndarray) -> np.ndarray:
    cov = np.asarray(covariance, dtype=np.float64)
    if cov.shape != (3, 3) or not np.isfinite(cov).all():
        raise ValueError(f"a motion covariance is a finite 3 x 3 matrix, got shape {cov.shape}")
    if not np.allclose(cov, cov.T, rtol=1e-9, atol=1e-12):
        raise ValueError("a motion covariance must be symmetric")
    try:
        np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        raise ValueError("a motion covariance must be positive definite") from None
    return (cov + cov.T) / 2


@dataclass(frozen=True, eq=False)
class EdgeMotion:
    """``rotate(angle1), drive(distance), rotate(angle2)`` (rad, m, rad) with its covariance.

    Angles are counter-clockwise and wrapped to [-pi, pi); ``covariance`` is over
    ``(angle1, distance, angle2)``.
    """

    angle1: float
    distance: float
    angle2: float
    covariance: np.ndarray

    def __post_init__(self) -> None:
        if not (math.isfinite(self.distance) and self.distance >= 0):
            raise ValueError(f"distance must be finite and >= 0, got {self.distance}")
        if not (math.isfinite(self.angle1) and math.isfinite(self.angle2)):
            raise ValueError("motion angles must be finite")
        object.__setattr__(self, "angle1", wrap_angle(float(self.angle1)))
        object.__setattr__(self, "distance", float(self.distance))
        object.__setattr__(self, "angle2", wrap_angle(float(self.angle2)))
        object.__setattr__(self, "covariance", _check_covariance(self.covariance))

    @property
    def mean(self) -> np.ndarray:
        """``[angle1, distance, angle2]``."""
        return np.array([self.angle1, self.distance, self.angle2])

    @classmethod
    def from_mean(cls, mean: np.ndarray, covariance: np.ndarray) -> EdgeMotion:
        return cls(float(mean[0]), float(mean[1]), float(mean[2]), covariance)

    @classmethod
    def from_relative_pose(cls, pose: Pose2D, covariance: np.ndarray) -> EdgeMotion:
        """The motion reaching ``pose`` (b in a's frame) whose ``(x, y, theta)`` covariance is given.

        First-order propagation through ``angle1 = atan2(y, x)``, ``distance = hypot(x, y)``,
        ``angle2 = theta - angle1``; the position must not be at the origin.
        """
        x, y = pose.x, pose.y
        d2 = x * x + y * y
        if d2 <= 0:
            raise ValueError("a motion to the same position has no driving direction")
        d = math.sqrt(d2)
        jacobian = np.array([[-y / d2, x / d2, 0.0], [x / d, y / d, 0.0], [y / d2, -x / d2, 1.0]])
        angle1 = math.atan2(y, x)
        return cls(angle1, d, pose.theta - angle1, jacobian @ np.asarray(covariance, float) @ jacobian.T)

    def relative_pose(self) -> Pose2D:
        """Where the motion ends, in the frame of where it starts."""
        return Pose2D(self.distance * math.cos(self.angle1), self.distance * math.sin(self.angle1),
                      wrap_angle(self.angle1 + self.angle2))

    def pose_covariance(self) -> np.ndarray:
        """Covariance of ``(x, y, theta)`` of the end pose in the start frame (first order)."""
        c, s, d = math.cos(self.angle1), math.sin(self.angle1), self.distance
        jacobian = np.array([[-d * s, c, 0.0], [d * c, s, 0.0], [1.0, 0.0, 1.0]])
        return jacobian @ self.covariance @ jacobian.T

    @property
    def cost(self) -> float:
        """The paper's edge cost: ``sigma_x + sigma_y`` of the end position in the start frame."""
        cov = self.pose_covariance()
        return math.sqrt(max(cov[0, 0], 0.0)) + math.sqrt(max(cov[1, 1], 0.0))

    def reversed(self) -> EdgeMotion:
        """The motion back: ``(pi - angle2, distance, pi - angle1)``, covariance carried exactly."""
        return EdgeMotion(math.pi - self.angle2, self.distance, math.pi - self.angle1,
                          _REVERSE @ self.covariance @ _REVERSE.T)


class InconsistentEstimates(ValueError):
    """Two estimates of one motion disagree beyond their covariances: not fused, the edge is dropped."""


def fuse(first: EdgeMotion, second: EdgeMotion, *, gate: float | None = CONSISTENCY_GATE) -> EdgeMotion:
    """Two estimates of the same motion fused in information form (module docstring).

    Raises :class:`InconsistentEstimates` when their squared Mahalanobis distance (under the sum
    of the covariances) exceeds ``gate`` (None: never).
    """
    m1 = first.mean
    difference = second.mean - m1
    difference[[0, 2]] = [wrap_angle(difference[0]), wrap_angle(difference[2])]  # unwrap around the first
    if gate is not None:
        mahalanobis2 = float(difference @ np.linalg.solve(first.covariance + second.covariance, difference))
        if mahalanobis2 > gate:
            raise InconsistentEstimates(f"the two estimates disagree: Mahalanobis distance "
                                        f"{math.sqrt(mahalanobis2):.1f} > {math.sqrt(gate):.1f}")
    info1, info2 = np.linalg.inv(first.covariance), np.linalg.inv(second.covariance)
    covariance = np.linalg.inv(info1 + info2)  # fused by covariance (algorithm 2, "Graph")
    mean = covariance @ (info1 @ m1 + info2 @ (m1 + difference))
    if mean[1] < 0:  # the same motion driven forwards: (a1 + pi, -d, a2 - pi), an exact re-parametrisation
        mean = np.array([mean[0] + math.pi, -mean[1], mean[2] - math.pi])
        flip = np.diag([1.0, -1.0, 1.0])
        covariance = flip @ covariance @ flip
    return EdgeMotion.from_mean(mean, covariance)


def fuse_round_trip(forward: EdgeMotion, backward: EdgeMotion, *, gate: float | None = CONSISTENCY_GATE
                    ) -> EdgeMotion:
    """The a -> b motion from a measured a -> b and a measured b -> a (gated like :func:`fuse`)."""
    return fuse(forward, backward.reversed(), gate=gate)


@dataclass(frozen=True, slots=True)
class Target:
    """A target image: its name, its pose relative to the reference pose, its image file."""

    name: str
    pose: Pose2D
    image: str = ""


@dataclass(frozen=True, slots=True)
class Edge:
    """A fused edge, stored in the direction it was first measured."""

    source: str
    target: str
    motion: EdgeMotion


@dataclass(frozen=True, slots=True)
class RoadmapPath:
    """Targets from start to goal, the motion of each leg (in travel direction), total cost."""

    names: tuple[str, ...]
    motions: tuple[EdgeMotion, ...]
    cost: float


@dataclass(frozen=True)
class Roadmap:
    """Targets and fused edges; a value (``with_*`` return a new roadmap)."""

    targets: tuple[Target, ...] = ()
    edges: tuple[Edge, ...] = ()

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(t.name for t in self.targets)

    def target(self, name: str) -> Target:
        for t in self.targets:
            if t.name == name:
                return t
        raise KeyError(f"no target named {name!r}")

    def with_target(self, name: str, pose: Pose2D, image: str = "") -> Roadmap:
        """Add a target, or replace the pose of the one with that name."""
        kept = tuple(t for t in self.targets if t.name != name)
        if len(kept) == len(self.targets):
            return Roadmap((*self.targets, Target(name, pose, image)), self.edges)
        return Roadmap(tuple(Target(name, pose, image) if t.name == name else t for t in self.targets), self.edges)

    def motion(self, source: str, target: str) -> EdgeMotion | None:
        """The fused motion source -> target, whichever way it was stored; None without an edge."""
        for e in self.edges:
            if (e.source, e.target) == (source, target):
                return e.motion
            if (e.source, e.target) == (target, source):
                return e.motion.reversed()
        return None

    def with_edge(self, source: str, target: str, motion: EdgeMotion) -> Roadmap:
        """Add the edge source -> target, fused with any earlier estimate of the same pair.

        Raises :class:`InconsistentEstimates` (and changes nothing) when they disagree.
        """
        names = set(self.names)
        for name in (source, target):
            if name not in names:
                raise KeyError(f"no target named {name!r}")
        if source == target:
            raise ValueError("an edge joins two different targets")
        earlier = self.motion(source, target)
        kept = tuple(e for e in self.edges if {e.source, e.target} != {source, target})
        fused = motion if earlier is None else fuse(earlier, motion)
        return Roadmap(self.targets, (*kept, Edge(source, target, fused)))

    def with_round_trip(self, source: str, target: str, forward: EdgeMotion, backward: EdgeMotion) -> Roadmap:
        """Add the edge measured by going source -> target (``forward``) and back (``backward``)."""
        return self.with_edge(source, target, fuse_round_trip(forward, backward))

    def cost_matrix(self) -> csr_matrix:
        """Directed edge costs ``(N, N)``: entry (i, j) is the cost of going i -> j."""
        index = {n: i for i, n in enumerate(self.names)}
        rows, cols, costs = [], [], []
        for e in self.edges:
            i, j = index[e.source], index[e.target]
            rows += [i, j]
            cols += [j, i]
            costs += [max(e.motion.cost, _MIN_COST), max(e.motion.reversed().cost, _MIN_COST)]
        n = len(self.targets)
        return csr_matrix((costs, (rows, cols)), shape=(n, n))

    def components(self) -> tuple[frozenset[str], ...]:
        """Groups of targets joined by edges."""
        if not self.targets:
            return ()
        count, labels = connected_components(self.cost_matrix(), directed=False)
        names = np.array(self.names, dtype=object)
        return tuple(frozenset(names[labels == k]) for k in range(count))

    def is_connected(self) -> bool:
        """True when every target can reach every other (the learning mission's end condition)."""
        return len(self.components()) <= 1

    def shortest_path(self, start: str, goal: str) -> RoadmapPath | None:
        """The path of least total ``sigma_x + sigma_y`` (None when goal is unreachable)."""
        index = {n: i for i, n in enumerate(self.names)}
        for name in (start, goal):
            if name not in index:
                raise KeyError(f"no target named {name!r}")
        costs, previous = dijkstra(self.cost_matrix(), directed=True, indices=index[start], return_predecessors=True)
        if not np.isfinite(costs[index[goal]]):
            return None
        chain = [index[goal]]
        while chain[-1] != index[start]:
            chain.append(int(previous[chain[-1]]))
        names = tuple(self.names[i] for i in reversed(chain))
        motions = tuple(self.motion(a, b) for a, b in zip(names, names[1:], strict=False))
        return RoadmapPath(names, motions, float(costs[index[goal]]))  # type: ignore[arg-type]

    def to_arrays(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """The map-file arrays and meta of this roadmap (module docstring, "File")."""
        index = {n: i for i, n in enumerate(self.names)}
        arrays = {
            "target_poses": np.array([[t.pose.x, t.pose.y, t.pose.theta] for t in self.targets],
                                     dtype=np.float64).reshape(-1, 3),
            "edge_ends": np.array([[index[e.source], index[e.target]] for e in self.edges],
                                  dtype=np.int64).reshape(-1, 2),
            "edge_motions": np.array([e.motion.mean for e in self.edges], dtype=np.float64).reshape(-1, 3),
            "edge_covariances": np.array([e.motion.covariance for e in self.edges],
                                         dtype=np.float64).reshape(-1, 3, 3),
        }
        return arrays, {"targets": list(self.names), "images": [t.image for t in self.targets]}

    def save(self, path: str | os.PathLike) -> None:
        """Write the roadmap atomically (versioned, checksummed map file)."""
        arrays, meta = self.to_arrays()
        write_map_file(path, kind=KIND, version=VERSION, arrays=arrays, meta=meta)

    @classmethod
    def from_arrays(cls, arrays: Mapping[str, np.ndarray], meta: Mapping[str, Any]) -> Roadmap:
        """Inverse of :meth:`to_arrays`; ValueError naming what is inconsistent."""
        try:
            names = _RoadmapMeta.model_validate(dict(meta))
        except ValidationError as exc:
            first = exc.errors()[0]
            where = "".join(f".{p}" for p in first["loc"])
            raise ValueError(f"meta{where}: {first['msg'].removeprefix('Value error, ')}") from None
        poses, ends, motions, covariances = _checked_arrays(arrays, len(names.targets))
        targets = tuple(Target(n, Pose2D(*map(float, p)), img)
                        for n, p, img in zip(names.targets, poses, names.images, strict=True))
        edges = tuple(Edge(names.targets[i], names.targets[j], EdgeMotion.from_mean(m, c))
                      for (i, j), m, c in zip(ends, motions, covariances, strict=True))
        return cls(targets, edges)

    @classmethod
    def load(cls, path: str | os.PathLike) -> Roadmap:
        """Read a roadmap file; :class:`~maps.store.InputError` (one line) when it is not a valid one."""
        loaded = read_map_file(path, kind=KIND, versions=(VERSION,))
        try:
            return cls.from_arrays(loaded.arrays, loaded.meta)
        except ValueError as exc:
            raise InputError([Diagnostic(str(path), 0, 0, f"invalid roadmap: {exc}")]) from None


class _RoadmapMeta(BaseModel):
    """The roadmap's ``meta`` in the map-file header."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    targets: list[str] = Field(max_length=10_000, description="target names, in array order")
    images: list[str] = Field(max_length=10_000, description="target image paths ('' when unknown)")

    @model_validator(mode="after")
    def _consistent(self) -> _RoadmapMeta:
        if len(set(self.targets)) != len(self.targets):
            raise ValueError("target names must be unique")
        if len(self.images) != len(self.targets):
            raise ValueError("one image path per target")
        return self


def _checked_arrays(arrays: Mapping[str, np.ndarray], count: int
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    expected = {"target_poses": (count, 3), "edge_ends": (-1, 2), "edge_motions": (-1, 3),
                "edge_covariances": (-1, 3, 3)}
    for name, shape in expected.items():
        if name not in arrays:
            raise ValueError(f"array {name} is missing")
        got = arrays[name].shape
        if len(got) != len(shape) or any(s not in (-1, g) for s, g in zip(shape, got, strict=True)):
            raise ValueError(f"array {name} has shape {got}, expected {shape} (-1: any)")
    edges = {len(arrays[n]) for n in ("edge_ends", "edge_motions", "edge_covariances")}
    if len(edges) != 1:
        raise ValueError("edge arrays disagree on the number of edges")
    ends = arrays["edge_ends"]
    if ends.dtype.kind not in "iu" or (ends.size and (ends.min() < 0 or ends.max() >= count)):
        raise ValueError("edge_ends must be target indices")
    if ends.size and (ends[:, 0] == ends[:, 1]).any():
        raise ValueError("an edge joins two different targets")
    floats = [np.asarray(arrays[n], dtype=np.float64) for n in ("target_poses", "edge_motions", "edge_covariances")]
    if not all(np.isfinite(a).all() for a in floats):
        raise ValueError("poses and motions must be finite")
    return floats[0], ends.astype(np.int64), floats[1], floats[2]
