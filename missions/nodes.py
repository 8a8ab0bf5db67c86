"""Reading the nodes of a mission: node types, children and ports, checked against the registry.

One node is ``TypeName: {ports..., name, child | children}`` (or the bare ``TypeName``). Every
port given is checked against the node type's declaration (:mod:`behaviours.ports`): inputs take
a literal of the port's type, unit and range, or a ``{/ns/key}`` reference; outputs take the
``{/ns/key}`` the node should write instead of its default. Problems are collected, never
raised one by one, so ``bearings validate`` shows all of them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from behaviours.ports import InputPort, OutputPort, key_problem, parse_ref
from behaviours.registry import NodeType, Registry
from maps.located import describe_value, suggest
from maps.store import Diagnostic, Mark, YamlList, YamlMap
from missions.inputs import check_value, substitute
from missions.language import Location, NodeSpec

MAX_DEPTH = 100
MAX_NODES = 10_000  # an expanded mission tree larger than this is refused (include bombs)
STRUCTURE_KEYS = ("name", "children", "child")


@dataclass
class Scope:
    """What nodes of one file see: its file name, its input values and the include chain to it."""

    file: str
    values: dict[str, Any]
    chain: tuple[Path, ...] = ()


class NodeReader:
    """Turns located YAML into :class:`NodeSpec` values, collecting diagnostics."""

    def __init__(self, registry: Registry, diagnostics: list[Diagnostic],
                 include: Callable[[YamlMap, Scope, int], NodeSpec | None]) -> None:
        self.registry = registry
        self.diagnostics = diagnostics
        self.include = include
        self.count = 0

    def error(self, file: str, mark: Mark, message: str) -> None:
        self.diagnostics.append(Diagnostic(file, mark.line, mark.col, message))

    # -- one node ----------------------------------------------------------------------------
    def node(self, raw: Any, mark: Mark, scope: Scope, depth: int) -> NodeSpec | None:
        if not self._within_budget(scope.file, mark, depth):
            return None
        if isinstance(raw, YamlMap) and "include" in raw:
            return self.include(raw, scope, depth)
        parsed = self._split(raw, mark, scope.file)
        if parsed is None:
            return None
        type_name, body, mark = parsed
        node_type = self.registry.lookup(type_name) if isinstance(type_name, str) else None
        if node_type is None:
            self.error(scope.file, mark, f"unknown node type {type_name!r}{suggest(type_name, self.registry.names())}")
            return None
        name = self._name(node_type, body, scope)
        children = self._children(node_type, body, scope, depth)
        ports = self._ports(node_type, body, scope, mark)
        if children is None or ports is None:
            return None
        inputs, outputs, locations = ports
        return NodeSpec(node_type.name, name, inputs, tuple(children), Location(scope.file, mark.line, mark.col),
                        outputs=outputs, locations=locations)

    def _within_budget(self, file: str, mark: Mark, depth: int) -> bool:
        self.count += 1
        if depth > MAX_DEPTH:
            self.error(file, mark, f"the tree is nested deeper than {MAX_DEPTH} levels")
            return False
        if self.count == MAX_NODES + 1:
            self.error(file, mark, f"the mission expands to more than {MAX_NODES} nodes (an include repeated "
                       "too often?)")
        return self.count <= MAX_NODES

    def _split(self, raw: Any, mark: Mark, file: str) -> tuple[Any, YamlMap, Mark] | None:
        """(type name, body mapping, mark of the type name) of a node entry."""
        if isinstance(raw, str):
            return raw, _empty_body(mark), mark
        if not isinstance(raw, YamlMap):
            self.error(file, mark, f"expected a node like 'Drive: {{distance: 1.0}}', found {describe_value(raw)}")
            return None
        if len(raw) != 1:
            keys = ", ".join(repr(k) for k in raw) or "nothing"
            self.error(file, raw.mark, f"a node is one 'TypeName: {{ports}}' entry (or 'include: file'); found {keys}")
            return None
        ((type_name, body),) = raw.items()
        if body is None:
            return type_name, _empty_body(raw.value_mark_of(type_name)), raw.mark_of(type_name)
        if not isinstance(body, YamlMap):
            self.error(file, raw.value_mark_of(type_name),
                       f"{type_name}: ports are a mapping 'name: value', found {describe_value(body)}")
            return None
        return type_name, body, raw.mark_of(type_name)

    def _name(self, node_type: NodeType, body: YamlMap, scope: Scope) -> str:
        name, problem = substitute(body.get("name", node_type.name), scope.values)
        if problem or not isinstance(name, str) or not name.strip():
            self.error(scope.file, body.value_mark_of("name"), problem or f"{node_type.name}: 'name' must be "
                       "non-empty text")
            return node_type.name
        return name

    # -- children ----------------------------------------------------------------------------
    def _children(self, node_type: NodeType, body: YamlMap, scope: Scope, depth: int) -> list[NodeSpec] | None:
        file, name = scope.file, node_type.name
        wrong, right = {"composite": ("child", "children"), "decorator": ("children", "child")}.get(
            node_type.kind, (None, None))
        if right is None:
            present = [key for key in ("child", "children") if key in body]
            if present:
                self.error(file, body.mark_of(present[0]), f"{name} is a leaf and takes no {present[0]}")
                return None
            return []
        if wrong in body:
            self.error(file, body.mark_of(wrong), f"{name} takes 'children:' (a list), not 'child:'"
                       if right == "children" else f"{name} decorates one node: use 'child:'")
            return None
        raw = body.get(right)
        if right == "child":
            if raw is None:
                self.error(file, body.mark, f"{name} needs 'child:', the node it decorates")
                return None
            child = self.node(raw, body.value_mark_of("child"), scope, depth + 1)
            return None if child is None else [child]
        return self._child_list(node_type, body, scope, depth)

    def _child_list(self, node_type: NodeType, body: YamlMap, scope: Scope, depth: int) -> list[NodeSpec] | None:
        raw = body.get("children")
        if not isinstance(raw, YamlList):
            where = body.value_mark_of("children") if "children" in body else body.mark
            self.error(scope.file, where, f"{node_type.name} needs 'children:', a list of nodes")
            return None
        low, high = node_type.min_children, node_type.max_children
        count_ok = len(raw) >= low and (high is None or len(raw) <= high)
        if not count_ok:
            wanted = f"exactly {low}" if high == low else f"at least {low}"
            self.error(scope.file, body.value_mark_of("children"),
                       f"{node_type.name} takes {wanted} children, got {len(raw)}")
        items = [self.node(child, raw.mark_of(i), scope, depth + 1) for i, child in enumerate(raw)]
        children = [item for item in items if item is not None]
        return children if count_ok and len(children) == len(items) else None

    # -- ports -------------------------------------------------------------------------------
    def _ports(self, node_type: NodeType, body: YamlMap, scope: Scope, mark: Mark
               ) -> tuple[dict[str, Any], dict[str, str], dict[str, Location]] | None:
        declared = node_type.ports
        inputs: dict[str, Any] = {}
        outputs: dict[str, str] = {}
        locations: dict[str, Location] = {}
        ok = True
        for key, raw in body.items():
            if key in STRUCTURE_KEYS:
                continue
            port = declared.get(key)
            if port is None:
                takes = ", ".join(declared) or "no ports"
                self.error(scope.file, body.mark_of(key), f"{node_type.name} has no port {key!r}"
                           f"{suggest(key, declared)} (it takes: {takes})")
                ok = False
                continue
            where = body.value_mark_of(key)
            value, problem = self._port_value(node_type, port, raw, scope)
            if problem:
                self.error(scope.file, where, problem)
                ok = False
                continue
            (outputs if isinstance(port, OutputPort) else inputs)[key] = value
            locations[key] = Location(scope.file, where.line, where.col)
        ok = self._defaults(node_type, body, scope, mark, inputs, outputs) and ok
        return (inputs, outputs, locations) if ok else None

    def _port_value(self, node_type: NodeType, port: InputPort | OutputPort, raw: Any, scope: Scope
                    ) -> tuple[Any, str | None]:
        owner = f"{node_type.name}.{port.name}"
        value, problem = substitute(raw, scope.values)
        if problem:
            return value, f"{owner}: {problem}"
        ref = parse_ref(value)
        if isinstance(port, OutputPort):
            if ref is None:
                return value, f"{owner} is an output: write the key it should write, like {{{port.key}}}"
            problem = key_problem(ref.key, attributes=False)
            return ref.key, f"{owner}: {problem}" if problem else None
        if ref is None:
            value, problem = check_value(port, value)
            return value, f"{owner} {problem}" if problem else None
        if port.literal_only:
            return ref, f"{owner} takes a literal value, not a blackboard reference"
        problem = key_problem(ref.key)
        return ref, f"{owner}: {problem}" if problem else None

    def _defaults(self, node_type: NodeType, body: YamlMap, scope: Scope, mark: Mark, inputs: dict[str, Any],
                  outputs: dict[str, str]) -> bool:
        ok = True
        for port in node_type.inputs:
            if port.name in body:
                continue
            if port.required:
                self.error(scope.file, mark, f"{node_type.name} needs input {port.name!r}: {port.doc}")
                ok = False
            else:
                inputs[port.name] = parse_ref(port.default) or port.default
        for out in node_type.outputs:
            outputs.setdefault(out.name, out.key)
        return ok


def _empty_body(mark: Mark) -> YamlMap:
    body = YamlMap()
    body.mark, body.key_marks, body.value_marks = mark, {}, {}
    return body

