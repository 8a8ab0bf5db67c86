"""The landmark map of the stereo SLAM: 3-D points with covariances, descriptors and bookkeeping.

A landmark is a point of the scene (a corner of a wall's texture, of a table, of the floor's)
triangulated by the stereo pair. It keeps its world position (odometry frame) with a 3 x 3
covariance, the descriptor of its last sighting (so tracking follows its slowly changing look while
the robot approaches), the keyframe it was created at (its *anchor*: when a loop closure moves a
keyframe, its landmarks move with it), a persistent id, and two counts: how often it was predicted
in view, and how often it was found there.

Choices:

- **Fusion** (:meth:`LandmarkMap.fuse`): a new sighting's triangulation (world frame, covariance
  of the triangulation and of the pose it was placed from) is fused in information form. The pose
  was itself estimated from landmarks, so the two are not independent; the covariance is kept
  above ``floor`` (m^2 on each axis) so that a landmark never becomes surer than a few
  centimetres and later sightings still move it.
- **Culling** (:meth:`LandmarkMap.cull`): a landmark predicted in view ``min_visible`` times and
  found in fewer than ``min_found_ratio`` of them is dropped: a wrong stereo match, a corner
  formed by two surfaces at different depths (it slides with the viewpoint), a point that another
  object hides.
- **Duplicates** (:meth:`LandmarkMap.merge_duplicates`): after a loop closure, the landmarks mapped
  while the pose had drifted lie where the old ones of the same place are; pairs close in space and
  in descriptor become one (the older, with the two fused).

A map that is being built: this class is mutable (arrays replaced as landmarks join and leave).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

_POPCOUNT = np.array([bin(i).count("1") for i in range(256)], dtype=np.uint8)


def hamming(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Bitwise distances between the rows of two binary descriptor arrays of the same shape (N, D)."""
    return _POPCOUNT[np.bitwise_xor(a, b)].sum(axis=-1, dtype=np.int32)


def descriptor_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise distances: Hamming for binary (uint8) descriptors, L2 for float ones (SIFT)."""
    if a.dtype == np.uint8:
        return hamming(a, b)
    return np.linalg.norm(a.astype(np.float64) - b.astype(np.float64), axis=-1)


@dataclass
class LandmarkMap:
    """The landmarks, one row each (see the module docstring); ``next_id`` is the next id to give."""

    positions: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    covariances: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3)))
    descriptors: np.ndarray = field(default_factory=lambda: np.zeros((0, 32), dtype=np.uint8))
    anchors: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    ids: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    visible: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    found: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    next_id: int = 0

    def __len__(self) -> int:
        return len(self.ids)

    def add(self, positions: np.ndarray, covariances: np.ndarray, descriptors: np.ndarray, anchor: int) -> np.ndarray:
        """New landmarks (seen once, found once) anchored to keyframe ``anchor``; returns their ids."""
        n = len(positions)
        new_ids = np.arange(self.next_id, self.next_id + n, dtype=np.int64)
        self.next_id += n
        if len(self) == 0:
            self.descriptors = descriptors[:0].copy()
        self.positions = np.concatenate((self.positions, positions))
        self.covariances = np.concatenate((self.covariances, covariances))
        self.descriptors = np.concatenate((self.descriptors, descriptors))
        self.anchors = np.concatenate((self.anchors, np.full(n, anchor, dtype=np.int64)))
        self.ids = np.concatenate((self.ids, new_ids))
        self.visible = np.concatenate((self.visible, np.ones(n, dtype=np.int64)))
        self.found = np.concatenate((self.found, np.ones(n, dtype=np.int64)))
        return new_ids

    def rows_of(self, ids: np.ndarray) -> np.ndarray:
        """Rows of the landmarks with these ids (-1 for an id no longer in the map)."""
        ids = np.asarray(ids, dtype=np.int64)
        if len(self) == 0:
            return np.full(len(ids), -1, dtype=np.int64)
        rows = np.minimum(np.searchsorted(self.ids, ids), len(self) - 1)  # ids are kept in increasing order
        return np.where(self.ids[rows] == ids, rows, -1)

    def fuse(self, rows: np.ndarray, positions: np.ndarray, covariances: np.ndarray, floor: float) -> None:
        """Fuse new triangulations (world, with covariances) into landmarks ``rows`` (information form),
        each axis' variance kept above ``floor``."""
        if len(rows) == 0:
            return
        info_old = np.linalg.inv(self.covariances[rows])
        info_new = np.linalg.inv(covariances)
        fused = np.linalg.inv(info_old + info_new)
        mean = np.einsum("nij,nj->ni", fused, np.einsum("nij,nj->ni", info_old, self.positions[rows])
                         + np.einsum("nij,nj->ni", info_new, positions))
        self.positions[rows] = mean
        self.covariances[rows] = fused + np.eye(3) * np.maximum(floor - np.einsum("nii->ni", fused), 0.0)[:, :, None]

    def cull(self, min_visible: int, min_found_ratio: float) -> int:
        """Drop the landmarks seen in view often but rarely found (see the module docstring); how many."""
        bad = (self.visible >= min_visible) & (self.found < min_found_ratio * self.visible)
        self.keep(~bad)
        return int(np.count_nonzero(bad))

    def keep(self, mask: np.ndarray) -> None:
        """Keep only the landmarks of ``mask`` (order and ids unchanged)."""
        for name in ("positions", "covariances", "descriptors", "anchors", "ids", "visible", "found"):
            setattr(self, name, getattr(self, name)[mask])

    def move(self, corrections: dict[int, tuple[np.ndarray, np.ndarray]]) -> None:
        """Move each landmark with its anchor: ``corrections[k] = (R, t)`` maps keyframe k's old world
        frame to its new one (``P' = R P + t``, covariances turned by ``R``)."""
        for anchor, (rotation, translation) in corrections.items():
            rows = np.flatnonzero(self.anchors == anchor)
            if len(rows):
                self.positions[rows] = self.positions[rows] @ rotation.T + translation
                self.covariances[rows] = rotation @ self.covariances[rows] @ rotation.T

    def merge_duplicates(self, radius: float, max_distance: float, floor: float) -> int:
        """Make one landmark of each pair within ``radius`` (m) whose descriptors differ by at most
        ``max_distance``: the older keeps its id, the two fused; returns how many were merged away."""
        if len(self) < 2:
            return 0
        pairs = cKDTree(self.positions).query_pairs(radius, output_type="ndarray")
        if len(pairs) == 0:
            return 0
        pairs = np.sort(pairs, axis=1)  # rows follow the ids: the first of a pair is the older
        close = descriptor_distance(self.descriptors[pairs[:, 0]], self.descriptors[pairs[:, 1]]) <= max_distance
        gone = np.zeros(len(self), dtype=bool)
        for older, newer in pairs[close]:
            if gone[older] or gone[newer]:
                continue
            self.fuse(np.array([older]), self.positions[[newer]], self.covariances[[newer]], floor)
            self.visible[older] += self.visible[newer]
            self.found[older] += self.found[newer]
            gone[newer] = True
        self.keep(~gone)
        return int(np.count_nonzero(gone))
