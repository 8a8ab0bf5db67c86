"""Following a polyline by pure pursuit: the robot's place along it, and the carrot ahead of it.

Two motion nodes follow a path this way: the route's search along its lying eights
(:mod:`behaviours.search`) and the exploration's path follower
(:mod:`behaviours.exploration.follow_path`). Both keep the robot's place along the path as the
point nearest the robot within a window on from the last place, never going back (a path that
crosses itself, as an eight does, or doubles back would otherwise let the place jump across), and
steer to the first point after the place at least a lookahead from the robot. Pure: arrays in,
index or point out.
"""

from __future__ import annotations

import numpy as np


def place_along(path: np.ndarray, start: int, stop: int, here: np.ndarray) -> int:
    """The index of the point of ``path[start:stop]`` nearest ``here`` (``start`` when the window is
    a single point; ``stop`` is clipped to the path's end)."""
    window = path[start : max(stop, start + 1)]
    return start + int(np.argmin(np.hypot(*(window - here).T)))


def carrot(path: np.ndarray, index: int, here: np.ndarray, lookahead: float) -> np.ndarray:
    """The first point of ``path`` from ``index`` on at least ``lookahead`` from ``here`` (else the end)."""
    ahead = path[index:]
    far = np.flatnonzero(np.hypot(*(ahead - here).T) >= lookahead)
    return ahead[far[0]] if len(far) else ahead[-1]
