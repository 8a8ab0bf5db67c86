"""Comparisons of blackboard values, shared by the ``CheckBlackboard`` condition and ``Guard``."""

from __future__ import annotations

import operator
from typing import Any

OPERATORS = {
    "==": operator.eq,
    "!=": operator.ne,
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
}


def compare(left: Any, op: str, right: Any) -> bool:
    """``left op right``; False (never an exception) when the values cannot be ordered."""
    try:
        return bool(OPERATORS[op](left, right))
    except TypeError:
        return False
