"""Route-following heading filter and speed (LT-map paper, eqs. 7-9).

Z-infinity gives a homing direction every frame; single estimates jump when matches change. The
heading actually steered is the circular median of the last K estimates (eqs. 7-8), and the
forward speed is scaled by the confidence of the estimate (eq. 9). The circular median is the
sample that minimises the sum of wrapped angular distances to all samples, which is robust to
up to half of the samples being wild, and correct across the +-pi seam.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from perception.geometry import wrap_angle, wrap_angles


def circular_median(angles: np.ndarray, weights: np.ndarray | None = None) -> float:
    """Eqs. 7-8: the sample angle with the least (weighted) sum of wrapped distances to all others."""
    a = np.asarray(angles, dtype=np.float64).ravel()
    if len(a) == 0:
        raise ValueError("the circular median of no angles is undefined")
    w = np.ones(len(a)) if weights is None else np.asarray(weights, dtype=np.float64).ravel()
    distances = np.abs(wrap_angles(a[:, None] - a[None, :]))  # K x K wrapped differences
    return float(wrap_angles(a[int(np.argmin(distances @ w))]))


@dataclass(frozen=True, slots=True)
class HeadingFilter:
    """The last ``k`` heading estimates (rad) and their confidences; immutable, ``push`` returns a new one."""

    k: int = 5
    headings: tuple[float, ...] = ()
    confidences: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if self.k < 1:
            raise ValueError(f"k must be at least 1, got {self.k}")

    def push(self, heading: float, confidence: float = 1.0) -> HeadingFilter:
        """This filter with one more estimate (the oldest beyond ``k`` is dropped)."""
        return HeadingFilter(
            self.k, (*self.headings, float(heading))[-self.k :], (*self.confidences, float(confidence))[-self.k :]
        )

    def reset(self) -> HeadingFilter:
        """An empty filter of the same length (after a switch to the next viewframe)."""
        return HeadingFilter(self.k)

    @property
    def heading(self) -> float | None:
        """Eqs. 7-8: circular median of the stored headings, or None before the first estimate."""
        return circular_median(np.array(self.headings)) if self.headings else None

    @property
    def confidence(self) -> float:
        """Median confidence of the stored estimates (0 when empty)."""
        return float(np.median(self.confidences)) if self.confidences else 0.0


def scaled_velocity(confidence: float, v_max: float, *, min_confidence: float = 0.0) -> float:
    """Eq. 9: forward speed ``v_max`` scaled by the confidence of the homing estimate.

    The confidence is mapped linearly from ``[min_confidence, 1]`` to ``[0, 1]``: below
    ``min_confidence`` the robot stops rather than drive on a guess.
    """
    if not 0.0 <= min_confidence < 1.0:
        raise ValueError(f"min_confidence must be in [0, 1), got {min_confidence}")
    scale = (float(confidence) - min_confidence) / (1.0 - min_confidence)
    return float(v_max * np.clip(scale, 0.0, 1.0))


def heading_flipped(previous: float, current: float, *, limit: float = np.pi / 2) -> bool:
    """True when the heading turned by more than ``limit`` (90 deg): the viewframe was passed."""
    return bool(abs(wrap_angle(current - previous)) > limit)
