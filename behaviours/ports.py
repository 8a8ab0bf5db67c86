"""Typed ports: the parameters a node type declares, and references to blackboard keys.

A parameter value in a mission is either a literal (checked against the declared type at load
time) or a reference ``{/ns/key}`` read from the blackboard when the node ticks.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from behaviours.keys import key_spec

REF_PATTERN = re.compile(r"^\{(/[A-Za-z_][\w/]*(?:\.[A-Za-z_]\w*)*)\}$")
COMPARISONS = ("==", "!=", "<", "<=", ">", ">=")
TYPES = ("float", "int", "bool", "str", "key", "list[float]", "any")


class _Missing:
    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Missing()


@dataclass(frozen=True, slots=True)
class Ref:
    """A reference to a blackboard key (optionally an attribute of its value, ``/robot/odometry.x``)."""

    key: str

    def __str__(self) -> str:
        return "{" + self.key + "}"


@dataclass(frozen=True, slots=True)
class Param:
    """One declared parameter of a node type.

    ``type`` is one of :data:`TYPES`; ``unit`` is the unit the mission writes the value in;
    ``choices`` restricts a ``str`` parameter; ``minimum``/``maximum`` bound numbers.
    """

    name: str
    type: str
    default: Any = REQUIRED
    unit: str = ""
    doc: str = ""
    choices: tuple[str, ...] = ()
    minimum: float | None = None
    maximum: float | None = None
    refs: bool = True  # may the value be a blackboard reference?
    extra: dict = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if self.type not in TYPES:
            raise ValueError(f"parameter {self.name!r}: unknown type {self.type!r}")

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def describe(self) -> str:
        unit = f" [{self.unit}]" if self.unit else ""
        default = "required" if self.required else f"default {self.default!r}"
        return f"{self.name}: {self.type}{unit}, {default}. {self.doc}".strip()


def parse_ref(value: Any) -> Ref | None:
    """The reference a YAML value spells, or None for a literal.

    ``"{/map/goal}"`` (a string) and ``{/map/goal}`` (YAML flow mapping with one null entry) both
    mean the key ``/map/goal``.
    """
    if isinstance(value, str):
        match = REF_PATTERN.match(value.strip())
        return Ref(match.group(1)) if match else None
    if isinstance(value, dict) and len(value) == 1:
        (key, val), = value.items()
        if val is None and isinstance(key, str):
            return parse_ref("{" + key + "}")
    return None


def check_value(param: Param, value: Any) -> tuple[Any, str | None]:
    """Coerce a literal to the parameter's type; returns (value, error message or None)."""
    kind = param.type
    if kind == "any":
        return value, None
    if kind == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return value, f"expects a number{_unit(param)}, got {describe_value(value)}"
        value = float(value)
        if not math.isfinite(value):
            return value, f"expects a finite number, got {value}"
    elif kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            return value, f"expects a whole number, got {describe_value(value)}"
    elif kind == "bool":
        if not isinstance(value, bool):
            return value, f"expects true or false, got {describe_value(value)}"
    elif kind in ("str", "key"):
        if not isinstance(value, str):
            return value, f"expects text, got {describe_value(value)}"
        if kind == "key":
            if key_spec(value) is None:
                return value, f"unknown blackboard key {value!r}"
        elif param.choices and value not in param.choices:
            return value, f"expects one of {', '.join(param.choices)}, got {value!r}"
    elif kind == "list[float]":
        if not isinstance(value, Sequence) or isinstance(value, str):
            return value, f"expects a list of numbers, got {describe_value(value)}"
        items = []
        for item in value:
            if isinstance(item, bool) or not isinstance(item, (int, float)):
                return value, f"expects a list of numbers, found {describe_value(item)}"
            items.append(float(item))
        value = items
    if kind in ("float", "int"):
        if param.minimum is not None and value < param.minimum:
            return value, f"must be >= {param.minimum:g}{_unit(param)}, got {value:g}"
        if param.maximum is not None and value > param.maximum:
            return value, f"must be <= {param.maximum:g}{_unit(param)}, got {value:g}"
    return value, None


def check_ref(param: Param, ref: Ref) -> str | None:
    """Why a reference cannot feed this parameter, or None if it can."""
    if not param.refs:
        return "takes a literal value, not a blackboard reference"
    spec = key_spec(ref.key)
    if spec is None:
        return f"refers to unknown blackboard key {ref.key!r}"
    if "." in ref.key or spec.type is object or param.type == "any":
        return None
    wanted = {"float": (float, int), "int": (int,), "bool": (bool,), "str": (str,), "key": (str,),
              "list[float]": (list, tuple)}[param.type]
    if not (isinstance(spec.type, type) and issubclass(spec.type, wanted)):
        return f"refers to {ref.key} which holds {getattr(spec.type, '__name__', spec.type)}, not {param.type}"
    return None


def _unit(param: Param) -> str:
    return f" in {param.unit}" if param.unit else ""


def describe_value(value: Any) -> str:
    """A value as error messages name it: 'a mapping', 'a list', 'nothing (null)' or its repr."""
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    if value is None:
        return "nothing (null)"
    return repr(value)
