"""Small helpers the evaluation areas share to summarise episodes and print their tables."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np


def mean_present(values: Sequence[Any]) -> float | None:
    """Mean of the values that are there (None: an episode without that figure); None when none is."""
    present = [float(v) for v in values if v is not None]
    return float(np.mean(present)) if present else None


def cell(value: Any, digits: int = 3) -> str:
    """A table cell: ``-`` for a missing figure, floats to ``digits`` places."""
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)
