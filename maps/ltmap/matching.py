"""Matching an observation against one viewframe of an LT-map, and the cache that makes it cheap.

Route following matches every new observation against the target viewframe (the hot path), so
each viewframe's landmarks are stacked once for matching (:class:`Viewframe`: map indices,
bearings, descriptors or ids) and the stack is kept until the map changes.

- **Matching cache** (:class:`ViewframeCache`). Each viewframe's landmark stack is built once and
  kept until the map changes; a change (a new viewframe, pruning) clears every entry.
- **One row per id.** With ids, a branch holding one id twice (a landmark stored again after its
  bearing moved) keeps the deepest, most local copy. With descriptors both copies stay, and the
  ratio test discards the pair: an ambiguous landmark is better unused than matched to a stale
  bearing.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from maps.ltmap.arrays import IDS, readonly
from perception.matching import LandmarkMatches, Landmarks, match_landmarks
from perception.observation import Observation


@dataclass(frozen=True, slots=True, eq=False)
class Viewframe:
    """The landmarks of one viewframe stacked for matching (built once, kept until the map changes).

    ``landmarks`` are map indices; ``bearings`` unit (K x 3, route frame, float64); ``descriptors``
    (K x W) or ``ids`` (K,, sorted); ``matchable``: the descriptor set :func:`match_landmarks` takes.
    """

    index: int
    landmarks: np.ndarray
    bearings: np.ndarray
    descriptors: np.ndarray | None
    ids: np.ndarray | None
    matchable: Landmarks | None

    def __len__(self) -> int:
        return len(self.landmarks)


def stack_viewframe(index: int, kind: str, landmarks: np.ndarray, bearings: np.ndarray, data: np.ndarray,
                    depth: np.ndarray | None = None) -> Viewframe:
    """Viewframe ``index`` of a ``kind`` map, stacked for matching.

    ``landmarks``: the map indices on its branch (ascending); ``bearings`` and ``data`` (ids or
    descriptor rows): every landmark of the map; ``depth``: per landmark of ``landmarks`` the
    depth of its node, needed for ids (of two rows with one id the deepest is kept).
    """
    if kind == IDS:  # one row per id: the deepest (most local) copy, sorted by id
        if depth is None:
            raise ValueError("stacking a viewframe of landmark ids needs the depth of each landmark's node")
        order = np.lexsort((-depth, data[landmarks]))
        _, first = np.unique(data[landmarks[order]], return_index=True)
        landmarks = landmarks[order[first]]
    stacked_bearings = readonly(bearings[landmarks].astype(np.float64))
    stacked = readonly(np.ascontiguousarray(data[landmarks]))
    if kind == IDS:
        return Viewframe(index, readonly(landmarks), stacked_bearings, None, stacked, None)
    return Viewframe(index, readonly(landmarks), stacked_bearings, stacked, None,
                     Landmarks(stacked, stacked_bearings, kind))


class ViewframeCache:
    """Each viewframe's stack, built on first use and kept until :meth:`clear` (the map changed)."""

    def __init__(self) -> None:
        self._stacks: dict[int, Viewframe] = {}

    def get(self, index: int, build: Callable[[int], Viewframe]) -> Viewframe:
        """The stack of viewframe ``index`` (``build`` makes it when it is not kept yet)."""
        found = self._stacks.get(index)
        if found is None:
            found = self._stacks[index] = build(index)
        return found

    def clear(self) -> None:
        self._stacks.clear()


def match_viewframe(viewframe: Viewframe, observation: Observation, cur: np.ndarray, *, kind: str,
                    ratio: float | None = None) -> LandmarkMatches:
    """Match an observation, seen at bearings ``cur`` (one row per observed landmark), against a
    viewframe of a ``kind`` map: ``ref`` the viewframe's bearings, ``landmark`` indexes the
    viewframe. ``ValueError`` when the observation has the other kind of landmarks."""
    if viewframe.ids is not None:
        if observation.ids is None:
            raise ValueError("this map holds landmark ids; the observation has descriptors")
        return _match_ids(np.asarray(observation.ids), viewframe.ids, cur, viewframe.bearings)
    if observation.features is None or viewframe.matchable is None:
        raise ValueError(f"this map holds {kind} descriptors; the observation has landmark ids")
    return match_landmarks(observation.features, cur, viewframe.matchable, ratio=ratio)


def _match_ids(ids: np.ndarray, stored: np.ndarray, cur: np.ndarray, ref: np.ndarray) -> LandmarkMatches:
    """Correspondences by equal ids (the ideal sensor): observed ``ids`` with bearings ``cur``
    against ``stored`` ids with bearings ``ref``."""
    _, feature, landmark = np.intersect1d(ids, stored, return_indices=True)
    feature, landmark = feature.astype(np.int64), landmark.astype(np.int64)
    return LandmarkMatches(ref=ref[landmark], cur=cur[feature], feature=feature, landmark=landmark,
                           distance=np.zeros(len(feature)))
