"""LT-map figures for ``bearings bench ltmap --json`` (an area to list in :data:`experiments.bench.AREAS`).

A route is taught along a synthetic corridor (:mod:`perception.synthetic_route`: near landmarks
on both sides, far ones all around, noise, dropouts, one-frame clutter), once with ORB-like
descriptors and once with the ideal sensor's ids. Figures, per kind:

- ``{kind}_match_cached_ms``: matching an observation against a viewframe as route following
  does every tick (:meth:`LandmarkTree.match`, the viewframe's stack cached);
  ``{kind}_match_rebuilt_ms``: the same with the viewframe's stack built again for every call;
  ``{kind}_rebuild_cost_ratio`` = rebuilt / cached (what the cache saves on the hot path);
- ``{kind}_learn_ms``: teaching, per observation (matching, eq. 1, new viewframes);
- the taught map: viewframes, landmarks, height, bytes, and ``{kind}_bytes_per_height``: the
  bytes after each cut of the lowest level (first entry: the full tree).

Times are medians in milliseconds; the observation matched is the one taught at that viewframe.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np

from maps.ltmap.arrays import IDS
from maps.ltmap.learner import RouteLearner
from maps.ltmap.tree import LandmarkTree
from perception.observation import Observation
from perception.synthetic_route import make_route_world, observe_route, straight_route


def _median_ms(fn: Callable[[], Any], repeats: int) -> float:
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - start)
    return round(float(np.median(samples)) * 1e3, 4)


def _teach(kind: str, length: float) -> tuple[LandmarkTree, list[Observation], float]:
    """Teach the corridor; the tree, the observation at each viewframe, ms per observation."""
    world = make_route_world(0, length=length)
    rng = np.random.default_rng(1)
    learner, at_viewframe = RouteLearner(), []
    poses = straight_route(length, 0.05)
    start = time.perf_counter()
    for pose in poses:
        observation = observe_route(world, pose, rng, kind=kind, noise_deg=0.2, dropout=0.05, clutter=10)
        if learner.observe(observation, pose.theta).created:
            at_viewframe.append(observation)
    if learner.finish().created:
        at_viewframe.append(observation)
    elapsed = (time.perf_counter() - start) / len(poses)
    if learner.tree is None:
        raise RuntimeError("the benchmark route taught nothing")
    return learner.tree, at_viewframe, round(elapsed * 1e3, 4)


def _figures(kind: str, length: float, repeats: int) -> dict[str, Any]:
    tree, observations, learn_ms = _teach(kind, length)
    sample = np.linspace(0, tree.viewframe_count - 1, min(8, tree.viewframe_count)).astype(int)
    cached, rebuilt = [], []
    for i in sample:
        tree.match(int(i), observations[i])  # warm the cache, as following does after its first tick
        cached.append(_median_ms(partial(tree.match, int(i), observations[i]), repeats))
        rebuilt.append(_median_ms(partial(tree.match, int(i), observations[i], cached=False), repeats))
    summary = tree.summary()
    per_height = [tree.memory_bytes()]
    pruned = tree.copy()
    while pruned.prune_level() is not None:
        per_height.append(pruned.memory_bytes())
    cached_ms, rebuilt_ms = float(np.median(cached)), float(np.median(rebuilt))
    return {
        f"{kind}_viewframes": summary.viewframes,
        f"{kind}_landmarks": summary.landmarks,
        f"{kind}_height": summary.height,
        f"{kind}_bytes": summary.memory_bytes,
        f"{kind}_bytes_per_height": per_height,
        f"{kind}_learn_ms": learn_ms,
        f"{kind}_match_cached_ms": round(cached_ms, 4),
        f"{kind}_match_rebuilt_ms": round(rebuilt_ms, 4),
        f"{kind}_rebuild_cost_ratio": round(rebuilt_ms / cached_ms, 3),
    }


def run(quick: bool = False) -> dict[str, Any]:
    """The figures above; ``quick``: a shorter route and fewer repetitions (smoke tests)."""
    length, repeats = (4.0, 5) if quick else (15.0, 30)
    figures: dict[str, Any] = {"route_length_m": length}
    for kind in ("orb", IDS):
        figures.update(_figures(kind, length, repeats))
    return figures
