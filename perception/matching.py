"""Descriptor matching: k-nearest neighbours with the ratio test and a mutual check.

Brute force with ``cv2.batchDistance`` (OpenCV's brute-force matcher kernel, returning arrays
instead of one Python object per match): Hamming distance for binary descriptors (ORB, BRISK),
L2 for SIFT. The ratio test keeps a match when its distance is below ``ratio`` times the distance of the
second best candidate. Defaults: 0.65 for SIFT (the roadmap paper); 0.75 for binary descriptors,
whose integer Hamming distances are coarser, so the paper's 0.65 throws away too many good ORB
matches on 720 x 172 panoramas (the usual choice for ORB lies between 0.7 and 0.8).
The mutual check keeps a pair only when each is the other's nearest neighbour.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from perception.features import BINARY_KINDS, Features

DEFAULT_RATIO = {"sift": 0.65, "orb": 0.75, "brisk": 0.75}


@dataclass(frozen=True, slots=True)
class Matches:
    """Index pairs (``query[i]`` <-> ``train[i]``) and their descriptor distances."""

    query: np.ndarray
    train: np.ndarray
    distance: np.ndarray

    def __len__(self) -> int:
        return len(self.query)


@dataclass(frozen=True, slots=True)
class Landmarks:
    """A stored landmark set (e.g. a viewframe): descriptors with their unit bearings (N x 3).

    The bearings are compensated for the robot's rotation when the set was stored (LT-map paper),
    so they are in the frame of the place, not of whichever camera pose saw them.
    """

    descriptors: np.ndarray
    bearings: np.ndarray
    kind: str

    def __len__(self) -> int:
        return len(self.bearings)


@dataclass(frozen=True, slots=True)
class LandmarkMatches:
    """Correspondences between a frame and a landmark set, ready for :mod:`perception.zinf`.

    ``ref`` are the landmarks' stored bearings, ``cur`` the frame's bearings of the same
    landmarks; ``feature`` and ``landmark`` index the frame's features and the landmark set.
    """

    ref: np.ndarray
    cur: np.ndarray
    feature: np.ndarray
    landmark: np.ndarray
    distance: np.ndarray

    def __len__(self) -> int:
        return len(self.feature)


def _empty() -> Matches:
    none = np.zeros(0, dtype=np.int64)
    return Matches(none, none.copy(), np.zeros(0))


def match_descriptors(
    query: np.ndarray,
    train: np.ndarray,
    kind: str,
    *,
    ratio: float | None = None,
    mutual: bool = True,
) -> Matches:
    """Match two descriptor arrays of the same ``kind`` (ratio test, then optional mutual check)."""
    ratio = DEFAULT_RATIO.get(kind, 0.75) if ratio is None else ratio
    if not 0.0 < ratio <= 1.0:
        raise ValueError(f"ratio must be in (0, 1], got {ratio}")
    if len(query) == 0 or len(train) == 0:
        return _empty()
    norm, dtype = (cv2.NORM_HAMMING, cv2.CV_32S) if kind in BINARY_KINDS else (cv2.NORM_L2, cv2.CV_32F)
    # brute force in one OpenCV call per direction: arrays back, no per-match Python objects
    dist, index = cv2.batchDistance(query, train, dtype, normType=norm, K=2)
    second = dist[:, 1].astype(np.float64) if dist.shape[1] > 1 else np.full(len(dist), np.inf)
    keep = dist[:, 0] < ratio * second  # ratio test: the second best must be clearly worse
    qa = np.flatnonzero(keep).astype(np.int64)
    ta, da = index[keep, 0].astype(np.int64), dist[keep, 0].astype(np.float64)
    if mutual and len(qa):
        used = np.unique(ta)  # only the train descriptors some query chose need a backward search
        _, back = cv2.batchDistance(np.ascontiguousarray(train[used]), query, dtype, normType=norm, K=1)
        nearest_query = np.full(len(train), -1)
        nearest_query[used] = back[:, 0]
        keep = nearest_query[ta] == qa
        qa, ta, da = qa[keep], ta[keep], da[keep]
    return Matches(qa, ta, da)


def match_within(descriptors: np.ndarray, query: np.ndarray, kind: str, *, ratio: float | None = None) -> Matches:
    """Each ``query`` row of ``descriptors`` matched to the nearest OTHER row of the same array, with
    the ratio test against the second-nearest other row (no mutual check): a set searched for
    copies of its own rows (the LT-map's landmarks stored twice)."""
    ratio = DEFAULT_RATIO.get(kind, 0.75) if ratio is None else ratio
    if not 0.0 < ratio <= 1.0:
        raise ValueError(f"ratio must be in (0, 1], got {ratio}")
    query = np.asarray(query, dtype=np.int64).reshape(-1)
    if len(query) == 0 or len(descriptors) < 2:
        return _empty()
    norm, dtype = (cv2.NORM_HAMMING, cv2.CV_32S) if kind in BINARY_KINDS else (cv2.NORM_L2, cv2.CV_32F)
    k = min(3, len(descriptors))
    dist, index = cv2.batchDistance(np.ascontiguousarray(descriptors[query]), descriptors, dtype, normType=norm, K=k)
    order = np.argsort(index == query[:, None], axis=1, kind="stable")  # the row itself last
    dist = np.take_along_axis(dist, order, axis=1).astype(np.float64)
    index = np.take_along_axis(index, order, axis=1)
    second = dist[:, 1] if k == 3 else np.full(len(query), np.inf)
    keep = (dist[:, 0] < ratio * second) & (index[:, 0] != query)
    return Matches(query[keep], index[keep, 0].astype(np.int64), dist[keep, 0])


def match_features(query: Features, train: Features, *, ratio: float | None = None, mutual: bool = True) -> Matches:
    """Match two feature sets of the same kind."""
    if query.kind != train.kind:
        raise ValueError(f"cannot match {query.kind} features against {train.kind} features")
    return match_descriptors(query.descriptors, train.descriptors, query.kind, ratio=ratio, mutual=mutual)


def match_landmarks(
    features: Features,
    bearings: np.ndarray,
    landmarks: Landmarks,
    *,
    ratio: float | None = None,
    mutual: bool = True,
) -> LandmarkMatches:
    """Match a frame's features (with their bearings, N x 3) against a stored landmark set."""
    if features.kind != landmarks.kind:
        raise ValueError(f"cannot match {features.kind} features against {landmarks.kind} landmarks")
    found = match_descriptors(features.descriptors, landmarks.descriptors, features.kind, ratio=ratio, mutual=mutual)
    return LandmarkMatches(
        ref=landmarks.bearings[found.train],
        cur=np.asarray(bearings)[found.query],
        feature=found.query,
        landmark=found.train,
        distance=found.distance,
    )
