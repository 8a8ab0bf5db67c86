"""compare (behaviours/comparison.py): the six comparisons of CheckBlackboard and Guard, never raising."""

from __future__ import annotations

import pytest

from behaviours.comparison import OPERATORS, compare
from behaviours.ports import COMPARISONS


@pytest.mark.parametrize(("left", "op", "right", "holds"), [
    (1, "==", 1.0, True), (1, "!=", 2, True), (1.5, "<", 2, True), (2, "<=", 2, True), (3, ">", 2, True),
    (2, ">=", 3, False), ("a", "==", "a", True), (None, "==", None, True), (True, "!=", False, True),
])
def test_compare_applies_the_operator(left, op, right, holds):
    assert compare(left, op, right) is holds


@pytest.mark.parametrize(("left", "op", "right"), [("lab", "<", 1), (None, ">=", 0.0), ([1], ">", 2)])
def test_values_that_cannot_be_ordered_compare_false(left, op, right):
    assert compare(left, op, right) is False


def test_every_declared_comparison_has_an_operator():
    assert set(OPERATORS) == set(COMPARISONS)
