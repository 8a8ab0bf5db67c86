"""BehaviorTree.CPP's built-in nodes mapped back onto bearings' node types (``bearings import``).

Most BT.CPP built-ins are a bearings node type under its ``BTCPP`` name with the same ports
(``Inverter``, ``RetryUntilSuccessful``, ...); those need nothing here. The ones whose ports
differ are translated by :data:`TRANSLATIONS`: ``ReactiveSequence`` is a ``Sequence`` with
``memory: false``, ``Timeout msec`` a ``Timeout duration``, ``Precondition if=`` a ``Guard``,
``ScriptCondition code=`` a ``CheckBlackboard`` (a script that is one comparison of a blackboard
entry with a literal), and so on. What has no equivalent is reported at the element.

A translation receives the element's literal ports already read and checked against BT.CPP's
own (``given``, by :meth:`missions.btcpp_reader.Reader.given`) and returns the bearings node
type's name and ports, or None after reporting why not.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Protocol

from missions.btcpp import Comparison, parse_comparison, parse_value
from missions.btcpp_scope import Scope
from missions.btcpp_xml import XmlElement, node_tag

Made = tuple[str, dict[str, Any]] | None
"""A bearings node type's name and its ports, or None (the problem is reported)."""


class Reporting(Protocol):
    """Where a translation reports a problem (the reader, which collects them all)."""

    def error(self, element: XmlElement, message: str) -> None: ...


Translation = Callable[[Reporting, XmlElement, Mapping[str, str], Scope], Made]


def _memory(node_type: str, memory: bool) -> Translation:
    """``Sequence``/``Fallback`` and their reactive variants: bearings' ``memory`` port."""
    def translate(reading: Reporting, element: XmlElement, given: Mapping[str, str], scope: Scope) -> Made:
        return node_type, {} if memory else {"memory": False}
    return translate


def _integer(reading: Reporting, element: XmlElement, owner: str, text: str | None, default: int) -> int | None:
    if text is None:
        return default
    value = parse_value(text, int)
    if not isinstance(value, int):
        reading.error(element, f"{owner} expects a whole number, got {text!r}")
        return None
    return value


def _parallel(reading: Reporting, element: XmlElement, given: Mapping[str, str], scope: Scope) -> Made:
    count = len(element.children)
    success = _integer(reading, element, "Parallel.success_count", given.get("success_count"), -1)
    failure = _integer(reading, element, "Parallel.failure_count", given.get("failure_count"), 1)
    if success is None or failure is None:
        return None
    policy = "one" if success == 1 else "all" if success in (-1, count) else None
    if policy is None:
        reading.error(element, f"Parallel success_count {success} has no equivalent: bearings' Parallel succeeds "
                      "when all children did (-1) or when one did (1)")
    if failure != 1 and not (failure == -1 and count == 1):
        reading.error(element, f"Parallel failure_count {failure} has no equivalent: bearings' Parallel fails as "
                      "soon as one child fails (1)")
        return None
    return ("Parallel", {} if policy == "all" else {"policy": policy}) if policy else None


def _milliseconds(node_type: str, port: str) -> Translation:
    """``Timeout``/``Sleep msec``: a bearings duration in seconds."""
    def translate(reading: Reporting, element: XmlElement, given: Mapping[str, str], scope: Scope) -> Made:
        tag = node_tag(element)
        if "msec" not in given:
            reading.error(element, f"{tag} needs msec")
            return None
        msec = _integer(reading, element, f"{tag}.msec", given["msec"], 0)
        return None if msec is None else (node_type, {port: msec / 1000})
    return translate


def _run_once(reading: Reporting, element: XmlElement, given: Mapping[str, str], scope: Scope) -> Made:
    then_skip = parse_value(given.get("then_skip", "true"), bool)
    if then_skip is not False:
        reading.error(element, "RunOnce with then_skip=\"true\" (its default) has no equivalent: it returns "
                      "SKIPPED after the first run; then_skip=\"false\" is bearings' OneShot policy on_completion")
        return None
    return "OneShot", {"policy": "on_completion"}


def _script(attribute: str, needs: str, node_type: str) -> Translation:
    """A node whose script ``attribute`` is one comparison (``Precondition if``: a ``Guard``,
    ``ScriptCondition code``: a ``CheckBlackboard``)."""
    def translate(reading: Reporting, element: XmlElement, given: Mapping[str, str], scope: Scope) -> Made:
        tag = node_tag(element)
        if given.get("else", "FAILURE").strip() != "FAILURE":  # only Precondition has an else
            reading.error(element, f"{tag} else={given['else']!r} has no equivalent: a Guard fails when its "
                          "condition does not hold")
            return None
        if attribute not in given:
            reading.error(element, f"{tag} needs its {needs}")
            return None
        ports = comparison(reading, element, f"{tag}.{attribute}", given[attribute], scope)
        return None if ports is None else (node_type, ports)
    return translate


def comparison(reading: Reporting, element: XmlElement, owner: str, script: str, scope: Scope
               ) -> dict[str, Any] | None:
    """Guard/CheckBlackboard ports from a script ``name op literal``."""
    parsed: Comparison | None = parse_comparison(script)
    if parsed is None:
        reading.error(element, f"{owner}: the script {script!r} has no bearings equivalent (bearings compares one "
                      "blackboard entry with a literal: '@robot__odometry___x >= 1.5')")
        return None
    resolved = scope.resolve(parsed.name)
    if isinstance(resolved, str) or resolved[0] != "key":
        problem = resolved if isinstance(resolved, str) else f"{parsed.name} is a constant, not an entry"
        reading.error(element, f"{owner}: {problem}")
        return None
    return {"key": resolved[1], "op": parsed.op, "value": parsed.value}


def _keep_running(reading: Reporting, element: XmlElement, given: Mapping[str, str], scope: Scope) -> Made:
    return "Repeat", {"num_cycles": -1}


TRANSLATIONS: dict[str, Translation] = {
    "Sequence": _memory("Sequence", True), "ReactiveSequence": _memory("Sequence", False),
    "Fallback": _memory("Selector", True), "ReactiveFallback": _memory("Selector", False),
    "Parallel": _parallel, "Timeout": _milliseconds("Timeout", "duration"), "Sleep": _milliseconds("Wait", "duration"),
    "RunOnce": _run_once, "Precondition": _script("if", "if script", "Guard"),
    "ScriptCondition": _script("code", "code", "CheckBlackboard"), "KeepRunningUntilFailure": _keep_running,
}  # fmt: skip
"""BT.CPP built-ins whose ports differ from their bearings counterpart's (the others keep theirs)."""
