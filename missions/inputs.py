"""Mission inputs: their declarations, the values given for them, and ``${name}`` substitution.

An input is declared like a node's input port (a type, a unit, a default, a description) and is
substituted wherever a mission writes ``${name}`` (load time); the runner also publishes each
top-level input as ``/mission/<name>`` for nodes that read it at run time.
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import yaml

from behaviours.ports import REQUIRED, TYPE_NAMES, InputPort, assignable, check_literal, parse_ref, type_name
from maps.located import suggest
from maps.store import Diagnostic, InputError, Mark, YamlList, parse_yaml

SUBST = re.compile(r"\$\{([^}]*)\}")


@dataclass(frozen=True)
class Unbound:
    """A required input not given, while a mission is only checked (``bearings validate``, ``show``).

    It stands where ``${name}`` is written: ports check that the input's type fits them, text
    shows ``${name}``. ``bearings run`` never gets one: there a required input not given stops
    the run before anything moves (exit 2).
    """

    name: str
    type: Any

    def __str__(self) -> str:
        return "${" + self.name + "}"


def check_value(port: InputPort, value: Any) -> tuple[Any, str | None]:
    """A literal checked against a port (:func:`check_literal`); an :class:`Unbound` input by its type."""
    if isinstance(value, Unbound):
        if assignable(value.type, port.type):
            return value, None
        return value, f"takes {type_name(port.type)}, but input ${{{value.name}}} is {type_name(value.type)}"
    return check_literal(port, value)
IDENT = re.compile(r"^[A-Za-z_]\w*$")


def infer_type(value: Any) -> Any:
    """The input type a bare default implies."""
    if isinstance(value, bool):
        return bool
    if isinstance(value, int):
        return int
    if isinstance(value, float):
        return float
    if isinstance(value, str):
        return str
    if isinstance(value, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        return list[float]
    return Any


def declaration(name: str, spec: Any, explicit: dict[str, Any] | None) -> tuple[InputPort | None, str | None]:
    """The input port an ``inputs:`` entry declares; (port, problem).

    ``explicit`` holds the fields of a ``{type, default, unit, description}`` mapping (already
    validated against :class:`missions.model.InputDeclaration`), or None for the shorthand
    ``name: default``.
    """
    if explicit is None:
        default = list(spec) if isinstance(spec, YamlList) else spec
        port = InputPort(name, infer_type(default), default)
    else:
        has_default = "default" in explicit
        kind = explicit.get("type")
        tp = TYPE_NAMES[kind] if kind else (infer_type(explicit["default"]) if has_default else Any)
        port = InputPort(name, tp, explicit["default"] if has_default else REQUIRED,
                         unit=explicit.get("unit", ""), doc=explicit.get("description", ""))
    if port.required:
        return port, None
    value, problem = check_literal(port, port.default)
    if problem:
        return None, f"input {name!r}: default {problem}"
    return InputPort(name, port.type, value, unit=port.unit, doc=port.doc), None


def parse_override(port: InputPort, text: str) -> Any:
    """A ``--set name=text`` value: YAML 1.2 scalar syntax (``1e-3`` is a number), text for ``str``."""
    if port.type is str:
        return text
    with contextlib.suppress(InputError, yaml.YAMLError):
        return parse_yaml(text, file="--set") if text.strip() else text
    return text


def bind(declared: Mapping[str, InputPort], given: Mapping[str, Any], *, file: str, marks: Mapping[str, Mark],
         default_mark: Mark, texts: bool = False, require: bool = True) -> tuple[dict[str, Any], list[Diagnostic]]:
    """Input values: defaults overridden by ``given``; unknown, missing or mistyped inputs are problems.

    With ``texts`` the given values are ``--set`` texts (parsed by :func:`parse_override`). A
    required input not given is :class:`Unbound` (checking goes on without a cascade of errors),
    and a problem unless ``require`` is false (a mission only checked, not run).
    """
    values: dict[str, Any] = {}
    problems: list[Diagnostic] = []

    def problem(mark: Mark, message: str) -> None:
        problems.append(Diagnostic(file, mark.line, mark.col, message))

    for name, value in given.items():
        mark = marks.get(name, default_mark)
        port = declared.get(name)
        if port is None:
            known = ", ".join(declared) or "none"
            problem(mark, f"unknown input {name!r}{suggest(name, declared)} (inputs: {known})")
            continue
        value, error = check_value(port, parse_override(port, value) if texts else value)
        if error:
            problem(mark, f"input {name!r} {error}")
            value = None if port.required else port.default  # keep checking without a cascade of errors
        values[name] = value
    for name, port in declared.items():
        if name not in given:
            if port.required:
                values[name] = Unbound(name, port.type)
                if require:
                    how = f": give it with --set {name}=VALUE" if texts else " (the include's inputs: do not give it)"
                    problem(default_mark, f"input {name!r} is required{how}" + (f" ({port.doc})" if port.doc else ""))
            else:
                values[name] = port.default
    return values, problems


def substitute(value: Any, values: Mapping[str, Any]) -> tuple[Any, str | None]:
    """Replace ``${input}`` in a value: a whole ``${x}`` keeps x's type, inside text it is formatted."""
    if isinstance(value, str):
        return _substitute_text(value, values)
    if isinstance(value, list):
        items = [substitute(item, values) for item in value]
        problem = next((p for _, p in items if p), None)
        return (value, problem) if problem else ([v for v, _ in items], None)
    if isinstance(value, dict):
        if parse_ref(value) is not None:
            return value, None
        entries = {key: substitute(item, values) for key, item in value.items()}
        problem = next((p for _, p in entries.values() if p), None)
        return (value, problem) if problem else ({k: v for k, (v, _) in entries.items()}, None)
    return value, None


def _substitute_text(text: str, values: Mapping[str, Any]) -> tuple[Any, str | None]:
    whole = SUBST.fullmatch(text.strip())
    if whole:
        name = whole.group(1)
        if name not in values:
            return text, f"unknown input ${{{name}}}{suggest(name, values)}"
        return values[name], None
    unknown = [m.group(1) for m in SUBST.finditer(text) if m.group(1) not in values]
    if unknown:
        return text, f"unknown input ${{{unknown[0]}}}{suggest(unknown[0], values)}"
    return SUBST.sub(lambda m: str(values[m.group(1)]), text), None
