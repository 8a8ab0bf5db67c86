"""The BehaviorTree.CPP v4 vocabulary shared by the XML export and ``bearings import``.

Blackboard keys. bearings keys are absolute paths with an optional attribute path
(``/perception/observation.count``); BT.CPP scripts (``Precondition if=``, ``ScriptCondition
code=``) name entries as identifiers, ``@name`` for the root blackboard, and know no ``/`` or
``.``. One reversible mapping is used everywhere a key is written, in scripts and in port
remappings ``{...}`` alike, so a script and a port name the same BT.CPP entry:

- ``@`` first: bearings keys are absolute, BT.CPP's root blackboard is the one every subtree
  reaches;
- each path segment and attribute made of ASCII letters and digits with single inner
  underscores (``min_landmarks``) is written as it is, ``/`` as ``__`` and ``.`` as ``___``:
  ``/perception/observation.count`` is ``@perception__observation___count``, ``/robot/odometry``
  is ``@robot__odometry``;
- any other key (a segment with a leading, trailing or double underscore, an empty segment,
  non-ASCII letters) is ``@_`` followed by the hexadecimal UTF-8 bytes of the whole key:
  ``/map/goal_`` is ``@_2f6d61702f676f616c5f``.

Both forms are valid BT.CPP script identifiers and remapping keys, distinct from each other (a
readable form never starts with ``_``), and decoding re-encodes to check that an identifier is
the canonical name of a key, so the mapping is one-to-one. BT.CPP has no attribute access:
``@robot__odometry___x`` is an entry of its own in a BT.CPP host.

Literals. Port values are written as BT.CPP's ``convertFromString`` reads them: ``true`` /
``false``, integers, floats in their shortest exact form (``0.1``, ``1e-07``), lists of numbers
separated by ``;``. Script literals are BT.CPP's: numbers, ``true``/``false`` and quoted ASCII
text.
"""

from __future__ import annotations

import math
import re
import sys
from dataclasses import dataclass
from typing import Any

from behaviours.ports import Key, Ref, key_problem, type_name

_SIMPLE_PART = re.compile(r"[A-Za-z0-9]+(?:_[A-Za-z0-9]+)*")
_HEX_PREFIX = "_"
INT64 = (-(2**63) + 1, 2**63 - 1)  # script integers: a sign and an int64 magnitude
INT32 = (-(2**31), 2**31 - 1)
UINT32 = (0, 2**32 - 1)


# -- keys --------------------------------------------------------------------------------------
def key_to_identifier(key: str) -> str:
    """The BT.CPP identifier (with its ``@``) of a bearings key, attribute path included."""
    path, *attributes = key[1:].split(".")
    segments = path.split("/")
    if all(_SIMPLE_PART.fullmatch(part) for part in (*segments, *attributes)):
        return "@" + "__".join(segments) + "".join("___" + attribute for attribute in attributes)
    return "@" + _HEX_PREFIX + key.encode("utf-8").hex()


def identifier_to_key(identifier: str) -> str | None:
    """The bearings key a BT.CPP identifier names (``@`` optional), or None when it names none."""
    body = identifier.removeprefix("@")
    if body.startswith(_HEX_PREFIX):
        try:
            key = bytes.fromhex(body[len(_HEX_PREFIX):]).decode("utf-8")
        except ValueError:
            return None
    else:
        path, *attributes = body.split("___")
        key = "/" + path.replace("__", "/") + "".join("." + attribute for attribute in attributes)
    if key_problem(key) or key_to_identifier(key) != "@" + body:
        return None
    return key


def remap(key: str) -> str:
    """A port value that reads or writes ``key``: ``{@robot__odometry}``."""
    return "{" + key_to_identifier(key) + "}"


def blackboard_pointer(text: str) -> str | None:
    """What is inside ``{...}`` when BT.CPP reads ``text`` as a blackboard pointer, else None."""
    stripped = text.strip(" ")
    if len(stripped) >= 3 and stripped[0] == "{" and stripped[-1] == "}":
        return stripped[1:-1]
    return None


# -- port literals -----------------------------------------------------------------------------
def format_value(value: Any) -> str:
    """A literal or reference as a BT.CPP port value (exact: floats keep every digit)."""
    if isinstance(value, Ref):
        return remap(value.key)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return ";".join(format_value(item) for item in value)
    return str(value)


def literal_problem(value: Any, bounds: tuple[int, int] = INT32) -> str | None:
    """Why BT.CPP cannot read a literal port value (``std::stod`` for doubles, a bounds-checked
    ``from_chars`` for integers, ``int`` ports being 32-bit), or None."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int) and not bounds[0] <= value <= bounds[1]:
        return f"{value} is outside BehaviorTree.CPP's integer range {bounds[0]}..{bounds[1]}"
    if isinstance(value, float) and not reads_as_double(value):
        return f"{value!r} is not a number BehaviorTree.CPP reads (std::stod refuses it)"
    if isinstance(value, (list, tuple)):
        return next((p for p in (literal_problem(item, bounds) for item in value) if p), None)
    return None


def reads_as_double(value: float) -> bool:
    """Does ``std::stod`` read ``repr(value)`` back (finite, and not subnormal: stod reports ERANGE)?"""
    return math.isfinite(value) and (value == 0.0 or abs(value) >= sys.float_info.min)


_INT = re.compile(r"[+-]?\d{1,100}")  # longer is no quantity (and int() refuses past 4300 digits): text
_FLOAT = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")
TRUE_TEXT, _FALSE = ("true", "True", "TRUE", "1"), ("false", "False", "FALSE", "0")  # BT.CPP's booleans


def parse_value(text: str, tp: Any) -> Any:
    """A BT.CPP port value read as a literal of type ``tp``; text it cannot read stays text
    (the mission loader then reports it against the port's declaration)."""
    stripped = text.strip()
    if tp is bool:
        return True if stripped in TRUE_TEXT else False if stripped in _FALSE else text
    if tp is int:
        return int(stripped) if _INT.fullmatch(stripped) else text
    if tp is float:
        return float(stripped) if _FLOAT.fullmatch(stripped) else text
    if tp == list[float]:
        items = [item.strip() for item in stripped.split(";")] if stripped else []
        return [float(item) for item in items] if all(_FLOAT.fullmatch(item) for item in items) else text
    if tp in (str, Key):
        return text
    return _scalar(text)


def _scalar(text: str) -> Any:
    """A value of an untyped port: a number or boolean when it reads as one, else the text."""
    stripped = text.strip()
    if stripped in ("true", "false"):
        return stripped == "true"
    if _INT.fullmatch(stripped):
        return int(stripped)
    if _FLOAT.fullmatch(stripped):
        return float(stripped)
    return text


BTCPP_TYPE = {"float": "double", "int": "int", "bool": "bool", "str": "std::string", "key": "std::string",
              "list[float]": "std::vector<double>", "any": "AnyTypeAllowed"}


def model_type(tp: Any) -> str:
    """The ``type`` a TreeNodesModel port shows in Groot2."""
    name = type_name(tp)
    return BTCPP_TYPE.get(name, name)


# -- scripts -----------------------------------------------------------------------------------
def script_literal(value: Any) -> str | None:
    """``value`` in BT.CPP script syntax, or None when a script cannot write it."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value) if INT64[0] <= value <= INT64[1] else None
    if isinstance(value, float):
        return repr(value) if reads_as_double(value) else None
    if isinstance(value, str) and value.isascii():
        if "'" not in value:
            return f"'{value}'"
        if '"' not in value:
            return f'"{value}"'
    return None


def comparison_script(key: str, op: str, value: Any) -> str | None:
    """``@perception__observation___count >= 50``, or None when ``value`` has no script literal."""
    literal = script_literal(value)
    return None if literal is None else f"{key_to_identifier(key)} {op} {literal}"


@dataclass(frozen=True)
class Comparison:
    """A script of the form ``name op literal``: the one shape bearings can hold (Guard, CheckBlackboard)."""

    name: str  # the identifier as written (``@`` included)
    op: str
    value: Any


_NAME = r"@?[^\W\d]\w*"
_LITERAL = r"'[^']*'|\"[^\"]*\"|[+-]?0[xX][0-9a-fA-F]+|[+-]?\d+(?:\.\d+)?(?:[eE][+-]?\d+)?"
_OPERAND = rf"(?:{_NAME}|{_LITERAL})"
_SCRIPT = re.compile(rf"^\s*(?P<left>{_OPERAND})\s*(?P<op>==|!=|<=|>=|<|>)\s*(?P<right>{_OPERAND})\s*;?\s*$")
_FLIPPED = {"<": ">", ">": "<", "<=": ">=", ">=": "<=", "==": "==", "!=": "!="}


def parse_comparison(script: str) -> Comparison | None:
    """The comparison a script spells (``@x >= 50`` or ``50 <= @x``), or None for any other script."""
    match = _SCRIPT.match(script)
    if not match:
        return None
    left, op, right = match.group("left"), match.group("op"), match.group("right")
    if _is_name(left) and not _is_name(right):
        return Comparison(left, op, _script_value(right))
    if _is_name(right) and not _is_name(left):
        return Comparison(right, _FLIPPED[op], _script_value(left))
    return None


def _is_name(token: str) -> bool:
    return bool(re.fullmatch(_NAME, token)) and token not in ("true", "false")


def _script_value(token: str) -> Any:
    if token in ("true", "false"):
        return token == "true"
    if token[0] in "'\"":
        return token[1:-1]
    if re.fullmatch(r"[+-]?0[xX][0-9a-fA-F]+", token):
        return int(token, 16)
    return int(token) if _INT.fullmatch(token) else float(token)


# -- BehaviorTree.CPP's own node types -----------------------------------------------------------
BUILTIN_PORTS: dict[str, tuple[str, ...]] = {
    "Sequence": (), "ReactiveSequence": (), "Fallback": (), "ReactiveFallback": (),
    "Parallel": ("success_count", "failure_count"), "Inverter": (), "ForceSuccess": (), "ForceFailure": (),
    "RetryUntilSuccessful": ("num_attempts",), "Repeat": ("num_cycles",), "Timeout": ("msec",),
    "RunOnce": ("then_skip",), "AlwaysSuccess": (), "AlwaysFailure": (), "Precondition": ("if", "else"),
    "ScriptCondition": ("code",), "Sleep": ("msec",), "KeepRunningUntilFailure": (),
}  # fmt: skip
"""BT.CPP v4 built-in node types bearings maps onto, with their ports (BT.CPP 4.8 ``providedPorts``)."""

NO_EQUIVALENT: dict[str, str] = {
    "SequenceWithMemory": "it resumes at the failed child after a failure; bearings' Sequence starts over",
    "SequenceStar": "it resumes at the failed child after a failure; bearings' Sequence starts over",
    "AsyncSequence": "it returns RUNNING between children; bearings' Sequence ticks on in the same tick",
    "AsyncFallback": "it returns RUNNING between children; bearings' Selector ticks on in the same tick",
    "ParallelAll": "its max_failures threshold has no equivalent: bearings' Parallel fails at the first failure",
    "IfThenElse": "bearings has no conditional control node: write a Selector of Sequences",
    "WhileDoElse": "bearings has no conditional control node: write a Selector of Sequences with a Guard",
    "Delay": "bearings has no delaying decorator: write a Sequence of Wait and the child",
    "Script": "bearings nodes write the blackboard only through declared output ports",
    "SetBlackboard": "bearings nodes write the blackboard only through declared output ports",
    "UnsetBlackboard": "bearings nodes write the blackboard only through declared output ports",
    "WasEntryUpdated": "bearings does not track blackboard entry updates",
    "SkipUnlessUpdated": "bearings does not track blackboard entry updates",
    "WaitValueUpdate": "bearings does not track blackboard entry updates",
    **{f"Switch{n}": "bearings has no switch on a blackboard value" for n in range(2, 7)},
    **{f"Loop{kind}": "bearings has no loop over a queue" for kind in ("Int", "Bool", "Double", "String")},
}
"""BT.CPP built-in node types with no bearings equivalent, and why (``bearings import`` reports them)."""

BUILTIN_NAMES = frozenset(BUILTIN_PORTS) | frozenset(NO_EQUIVALENT) | {"SubTree"}
"""Every node type BT.CPP registers itself (a node of bearings may not take one of these names)."""

PRE_POST_CONDITIONS = ("_failureIf", "_successIf", "_skipIf", "_while", "_onSuccess", "_onFailure", "_post",
                       "_onHalted")
"""BT.CPP's scripted pre- and post-condition attributes (reserved names, not ports)."""

SENSE_SUFFIX = "_sense"
SENSE_NAME = "sense"
"""A mission's ``sense:`` nodes travel as a second tree, ``<main tree ID>_sense``, holding one
``Sequence`` named ``sense`` (the task tree stays the main tree BT.CPP executes)."""


def is_port_name(name: str) -> bool:
    """Does BT.CPP take an attribute of this name as a port (``IsAllowedPortName``)?"""
    return bool(name) and name[0].isascii() and name[0].isalpha() and name not in ("name", "ID")
