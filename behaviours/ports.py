"""Typed ports: what a node type reads and writes, declared once, checked before anything ticks.

As in BehaviorTree.CPP, every node type declares its ports, here with Python types:

- an :class:`InputPort` takes a literal (checked against the port's type, unit and range at load
  time) or a reference ``{/ns/key}`` to a blackboard entry read when the node ticks; its default
  may itself be a reference (``Drive`` reads ``{/robot/odometry}`` unless a mission says
  otherwise); a port whose text names a file declares it (``file=READS`` or ``file=WRITES``), so
  the loader resolves every such path the same way and keeps the files a mission writes inside
  its output folders (:class:`maps.store.OutputFolders`), plugins' ports included;
- an :class:`OutputPort` names the blackboard key the node writes; a mission may remap it per
  node (two ``Perceive`` nodes on two cameras write two observation keys).

The mission loader checks the whole data flow with these declarations (see
:mod:`missions.dataflow`); the BehaviorTree.CPP export writes them as ``input_port`` and
``output_port`` in its ``TreeNodesModel``.
"""

from __future__ import annotations

import math
import re
import types
import typing
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Generic, NewType, TypeVar, Union

from maps.located import describe_value

Key = NewType("Key", str)
"""A blackboard key given as a literal (``CheckBlackboard.key``): the node reads that key."""

REF_PATTERN = re.compile(r"^\{(/[A-Za-z_][\w/]*(?:\.[A-Za-z_]\w*)*)\}$")
KEY_PATTERN = re.compile(r"^/[A-Za-z_][\w/]*(?:\.[A-Za-z_]\w*)*$")
NAMESPACES = ("/robot", "/ptu", "/perception", "/map", "/mission")
COMPARISONS = ("==", "!=", "<", "<=", ">", ">=")
READS, WRITES = "reads", "writes"
"""``InputPort.file``: the port's text names a file (or folder) the node reads, or a file it writes."""

# The types a mission can name (input declarations, ``bearings schema``), by their YAML names.
TYPE_NAMES: dict[str, Any] = {
    "float": float, "int": int, "bool": bool, "str": str, "key": Key, "list[float]": list[float], "any": Any,
}  # fmt: skip


class _Missing:
    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Missing()

T = TypeVar("T")


@dataclass(frozen=True, slots=True)
class Ref:
    """A reference to a blackboard key, optionally to an attribute of its value (``/robot/odometry.x``)."""

    key: str

    @property
    def base(self) -> str:
        """The blackboard entry itself, without the attribute path."""
        return self.key.split(".", 1)[0]

    @property
    def attributes(self) -> tuple[str, ...]:
        return tuple(self.key.split(".")[1:])

    def __str__(self) -> str:
        return "{" + self.key + "}"


@dataclass(frozen=True, slots=True)
class InputPort(Generic[T]):
    """An input of a node type: a literal or a ``{/ns/key}`` reference of type ``type``.

    ``unit`` is the unit a mission writes the value in; ``choices`` restrict a ``str``;
    ``minimum``/``maximum`` bound numbers; ``literal_only`` ports configure the node and cannot
    change while it runs (they take no reference). ``file`` is :data:`READS` or :data:`WRITES`
    when the text names a file: relative paths are resolved against the mission's output folder
    before the node is built, and a written file must lie inside the output folders (checked at
    load; such a port is ``str`` and ``literal_only``, see :func:`file_port_problem`). ``camera``
    marks a text port that names the camera whose frames the node reads: a mission without
    ``cameras:`` grabs the cameras its nodes name this way and no other (:mod:`missions.camera_use`).

    The port is generic in its value type, so ``node.get_input(SPEED)`` is a ``float`` to mypy
    (``InputPort("speed", float, ...)`` infers ``InputPort[float]``). A union type cannot be
    inferred from its value: annotate the port (``GOAL: InputPort[Goal | None] = InputPort(...)``).
    """

    name: str
    type: type[T] | types.UnionType
    default: Any = REQUIRED
    unit: str = ""
    doc: str = ""
    choices: tuple[str, ...] = ()
    minimum: float | None = None
    maximum: float | None = None
    literal_only: bool = False
    file: str = ""
    camera: bool = False

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def describe(self) -> str:
        unit = f" [{self.unit}]" if self.unit else ""
        default = "required" if self.required else f"default {format_literal(self.default)}"
        return f"{self.name}: {type_name(self.type)}{unit}, {default}. {self.doc}".strip()


@dataclass(frozen=True, slots=True)
class OutputPort(Generic[T]):
    """An output of a node type: it writes values of ``type`` to blackboard key ``key`` (remappable).

    Generic in its value type like :class:`InputPort`: ``node.set_output(COMMAND, value)`` checks
    ``value`` against the port's type under mypy, and at run time against the declaration.
    """

    name: str
    type: type[T] | types.UnionType
    key: str
    doc: str = ""
    unit: str = ""

    def describe(self) -> str:
        return f"{self.name} -> {{{self.key}}}: {type_name(self.type)}. {self.doc}".strip()


Port = InputPort[Any] | OutputPort[Any]


def file_port_problem(port: InputPort) -> str | None:
    """Why a port declared to name a file is malformed, or None: a written file must be known at
    load time (a literal), so that where it goes is checked before anything runs."""
    if port.file not in ("", READS, WRITES):
        return f"port {port.name!r}: file is {READS!r}, {WRITES!r} or empty, not {port.file!r}"
    if port.file and port.type is not str:
        return f"port {port.name!r} names a file: its type is str"
    if port.file == WRITES and not port.literal_only:
        return f"port {port.name!r} names a file it writes: it must be literal_only (checked at load)"
    return None


# -- type names and compatibility ------------------------------------------------------------------
def type_name(tp: Any) -> str:
    """The name a type is written with in missions, schemas and the BT.CPP export."""
    for name, known in TYPE_NAMES.items():
        if tp is known or tp == known:
            return name
    if _is_union(tp):
        return " | ".join(type_name(t) for t in typing.get_args(tp))
    if tp is object:
        return "any"
    return getattr(tp, "__name__", str(tp))


def _is_union(tp: Any) -> bool:
    return typing.get_origin(tp) in (Union, types.UnionType)


def _plain(tp: Any) -> Any:
    """``Key`` is text at run time; ``object`` means any."""
    if tp is Key:
        return str
    return Any if tp is object else tp


def assignable(source: Any, target: Any) -> bool:
    """Can a value declared as ``source`` feed a port declared as ``target``?

    ``Any`` on either side is accepted (checked when the value arrives); ``int`` feeds ``float``;
    classes follow subclassing; unions must fit member by member; generic aliases must be equal.
    """
    source, target = _plain(source), _plain(target)
    if source is Any or target is Any or source == target:
        return True
    if _is_union(source):
        return all(assignable(member, target) for member in typing.get_args(source))
    if _is_union(target):
        return any(assignable(source, member) for member in typing.get_args(target))
    if target is float and source is int:
        return True
    if isinstance(source, type) and isinstance(target, type):
        return issubclass(source, target) and not (source is bool and target is not bool)
    return False


def attribute_type(owner: Any, attribute: str) -> Any:
    """The declared type of ``owner.attribute`` (a dataclass field or a typed property).

    ``Any`` when ``owner`` is not a class with type hints (nothing to check); raises
    ``AttributeError`` when the class declares no such attribute.
    """
    owner = _plain(owner)
    if not isinstance(owner, type):
        return Any
    try:
        hints = typing.get_type_hints(owner)
    except Exception:  # noqa: BLE001 - unresolvable annotations: do not check
        return Any
    if attribute in hints:
        return hints[attribute]
    member = getattr(owner, attribute, None)
    if isinstance(member, property) and member.fget is not None:
        return typing.get_type_hints(member.fget).get("return", Any)
    if member is None:
        raise AttributeError(f"{owner.__name__} has no attribute {attribute!r}")
    return Any


def matches_type(value: Any, tp: Any) -> bool:
    """Does a run-time value fit a declared type (as far as ``isinstance`` can tell)?"""
    tp = _plain(tp)
    if tp is Any or value is None:
        return True
    if _is_union(tp):
        return any(matches_type(value, member) for member in typing.get_args(tp))
    origin = typing.get_origin(tp)
    if origin is not None:
        return isinstance(value, origin)
    if tp is float:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    return isinstance(value, tp) if isinstance(tp, type) else True


# -- references ------------------------------------------------------------------------------------
def parse_ref(value: Any) -> Ref | None:
    """The reference a YAML value spells, or None for a literal.

    ``"{/map/goal}"`` (a string) and ``{/map/goal}`` (YAML flow mapping with one null entry) both
    mean the key ``/map/goal``.
    """
    if isinstance(value, Ref):
        return value
    if isinstance(value, str):
        match = REF_PATTERN.match(value.strip())
        return Ref(match.group(1)) if match else None
    if isinstance(value, dict) and len(value) == 1:
        ((key, val),) = value.items()
        if val is None and isinstance(key, str):
            return parse_ref("{" + key + "}")
    return None


def key_problem(key: str, *, attributes: bool = True) -> str | None:
    """Why ``key`` is not a usable blackboard key, or None."""
    if not KEY_PATTERN.match(key) or (not attributes and "." in key):
        return f"{key!r} is not a blackboard key like /map/goal" + ("" if attributes else " (no attribute path)")
    namespace = "/" + key.split("/")[1]
    if namespace not in NAMESPACES or key.count("/") < 2:
        return f"{key!r} is outside the blackboard namespaces {', '.join(NAMESPACES)}"
    return None


# -- literals --------------------------------------------------------------------------------------
Checker = Callable[[InputPort, Any], tuple[Any, str | None]]


def _number(port: InputPort, value: Any) -> tuple[Any, str | None]:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return value, f"expects a number{_in_unit(port)}, got {describe_value(value)}"
    if not math.isfinite(value):
        return value, f"expects a finite number, got {value}"
    return _bounded(port, float(value))


def _integer(port: InputPort, value: Any) -> tuple[Any, str | None]:
    if isinstance(value, bool) or not isinstance(value, int):
        return value, f"expects a whole number, got {describe_value(value)}"
    return _bounded(port, value)


def _boolean(port: InputPort, value: Any) -> tuple[Any, str | None]:
    return value, None if isinstance(value, bool) else f"expects true or false, got {describe_value(value)}"


def _text(port: InputPort, value: Any) -> tuple[Any, str | None]:
    if not isinstance(value, str):
        return value, f"expects text, got {describe_value(value)}"
    if port.choices and value not in port.choices:
        return value, f"expects one of {', '.join(port.choices)}, got {value!r}"
    return value, None


def _key(port: InputPort, value: Any) -> tuple[Any, str | None]:
    if not isinstance(value, str):
        return value, f"expects a blackboard key, got {describe_value(value)}"
    return value, key_problem(value)


def _numbers(port: InputPort, value: Any) -> tuple[Any, str | None]:
    if not isinstance(value, Sequence) or isinstance(value, str):
        return value, f"expects a list of numbers, got {describe_value(value)}"
    bad = [item for item in value if isinstance(item, bool) or not isinstance(item, (int, float))
           or not math.isfinite(item)]
    if bad:
        return value, f"expects a list of finite numbers, found {describe_value(bad[0])}"
    return [float(item) for item in value], None


_CHECKERS: dict[Any, Checker] = {float: _number, int: _integer, bool: _boolean, str: _text, Key: _key,
                                 list[float]: _numbers}


def check_literal(port: InputPort, value: Any) -> tuple[Any, str | None]:
    """Coerce a literal to the port's type; returns (value, error message or None)."""
    if port.type is Any or port.type is object:
        return value, None
    checker = _CHECKERS.get(port.type)
    if checker is None:
        return value, (f"takes a {type_name(port.type)} from the blackboard: write a reference like "
                       "{/ns/key}, not a literal")
    return checker(port, value)


def _bounded(port: InputPort, value: float) -> tuple[Any, str | None]:
    if port.minimum is not None and value < port.minimum:
        return value, f"must be >= {port.minimum:g}{_in_unit(port)}, got {value:g}"
    if port.maximum is not None and value > port.maximum:
        return value, f"must be <= {port.maximum:g}{_in_unit(port)}, got {value:g}"
    return value, None


def _in_unit(port: InputPort) -> str:
    return f" in {port.unit}" if port.unit else ""


def format_literal(value: Any) -> str:
    """A literal or reference as missions and the BT.CPP export write it."""
    if isinstance(value, Ref):
        return str(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, list):
        return "[" + ", ".join(format_literal(v) for v in value) + "]"
    return str(value)
