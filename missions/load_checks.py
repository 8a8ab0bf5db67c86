"""Load-time checks that need what a file holds: a target name against the roadmap file, at load.

The data flow (:mod:`missions.dataflow`) checks keys and types; some mistakes only show against
the content of a file a node reads when it runs: ``goto_target`` with a target the roadmap does
not have turned a full circle before it failed. Two optional hooks on a node class bring those
checks before anything moves, without the loader knowing any capability:

- ``preview_outputs(inputs) -> dict``: what the node will write, when it can tell at load time
  (``LoadRoadmap`` reads its roadmap file when it exists), by output port name; nothing when it
  cannot (the file is written earlier in the same mission, say);
- ``check_inputs(inputs) -> list[str]``: problems with the node's inputs, where an input that
  references a key gets the value previewed for that key (or None): ``NavigateToTarget`` checks
  its target against the roadmap it will read.

A preview that fails is no problem here: the node reports it when it runs, as before.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from behaviours.ports import Ref
from maps.store import Diagnostic
from missions.language import MissionSpec, NodeSpec


def load_checks(mission: MissionSpec) -> list[Diagnostic]:
    """The problems the nodes' ``check_inputs`` find, with what the ``preview_outputs`` tell."""
    previews = _previews(mission)
    problems = []
    for spec, cls in _typed_nodes(mission):
        check = getattr(cls, "check_inputs", None)
        if not callable(check):
            continue
        inputs = {name: previews.get(value.base) if isinstance(value, Ref) else value
                  for name, value in spec.inputs.items()}
        where = spec.location
        problems += [Diagnostic(where.file, where.line, where.col, f"{spec.name}: {message}")
                     for message in check(inputs)]
    return problems


def _previews(mission: MissionSpec) -> dict[str, Any]:
    """Blackboard key -> the value a node will write there, as far as the nodes can tell at load time."""
    found: dict[str, Any] = {}
    for spec, cls in _typed_nodes(mission):
        preview = getattr(cls, "preview_outputs", None)
        if not callable(preview):
            continue
        try:
            values = preview(dict(spec.inputs))
        except Exception:  # noqa: BLE001 - a file that cannot be read now is the node's to report when it runs
            continue
        for port, value in values.items():
            if port in spec.outputs:
                found[spec.outputs[port]] = value
    return found


def _typed_nodes(mission: MissionSpec) -> Iterator[tuple[NodeSpec, type]]:
    for root in (*mission.sense, mission.tree):
        for spec in root.walk():
            node_type = mission.registry.lookup(spec.type)
            if node_type is not None:
                yield spec, node_type.cls
