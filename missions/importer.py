"""``bearings import``: a BehaviorTree.CPP v4 XML file, as Groot2 saves it, to a bearings mission.

The file's main tree (``main_tree_to_execute``, or the one tree no other references) becomes the
mission's ``tree:``; a tree named ``<main>_sense`` (what the export writes for ``sense:``)
becomes its ``sense:``. Nodes whose BT.CPP name is a bearings node type's (its ``BTCPP`` name or
its own) keep their ports; BT.CPP's control nodes map back onto bearings' (``ReactiveSequence``
-> ``Sequence`` with ``memory: false``, ``Timeout msec`` -> ``Timeout duration``, ``Precondition``
-> ``Guard``, ...); blackboard keys and scripts are read with the mapping of
:mod:`missions.btcpp`.

``<SubTree>`` references are inlined: BT.CPP resolves a subtree's port remapping per instance,
which is exactly what inlining does, while bearings' includes substitute inputs at load time and
have no blackboard remapping; one self-contained file is also what Groot2 users hand over. A
SubTree's ``name`` becomes the name of the subtree's root node, as an include's ``name`` does.

Everything with no bearings equivalent (an unknown node or port, BT.CPP nodes bearings lacks,
scripts other than one comparison, scripted pre/post conditions, subtree-local blackboard
entries, ...) is reported as ``file:line:col: message``; the mission written is then loaded
with :func:`missions.loader.load_mission` and its problems are reported at the XML node they
came from. Nothing is written unless the mission validates.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any
from xml.parsers import expat

from behaviours.ports import REQUIRED, InputPort, OutputPort, Ref, key_problem, parse_ref
from behaviours.registry import NodeType, Registry
from maps.located import suggest
from maps.store import (
    MAX_FILE_BYTES,
    Diagnostic,
    InputError,
    Mark,
    YamlList,
    YamlMap,
    dump_yaml,
    parse_yaml,
    read_bytes,
)
from missions.btcpp import (
    BUILTIN_PORTS,
    NO_EQUIVALENT,
    PRE_POST_CONDITIONS,
    SENSE_SUFFIX,
    TRUE_TEXT,
    Comparison,
    blackboard_pointer,
    identifier_to_key,
    is_port_name,
    key_to_identifier,
    parse_comparison,
    parse_value,
)
from missions.loader import load_mission
from missions.nodes import MAX_DEPTH, MAX_NODES

MODEL_TAGS = ("Action", "Condition", "Control", "Decorator")


# -- XML with positions ------------------------------------------------------------------------
@dataclass
class XmlElement:
    """An XML element with where it starts (1-based line and column)."""

    tag: str
    attrs: dict[str, str]
    line: int
    col: int
    children: list[XmlElement] = field(default_factory=list)


class _Refused(Exception):
    """A construct the reader refuses before it can do harm (a DOCTYPE, so no entities at all)."""


def parse_xml(data: bytes, file: str) -> XmlElement:
    """Parse XML bytes into located elements; malformed XML and any DOCTYPE (hence any entity
    declaration) are an :class:`InputError` at their line. The bytes are read as UTF-8 whatever
    the declaration says (BT.CPP's tinyxml2 reads nothing else). Text and comments are ignored."""
    parser = expat.ParserCreate(encoding="UTF-8")
    stack: list[XmlElement] = []
    roots: list[XmlElement] = []

    def start(tag: str, attrs: dict[str, str]) -> None:
        element = XmlElement(tag, dict(attrs), parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)
        (stack[-1].children if stack else roots).append(element)
        stack.append(element)

    def refuse(*_: Any) -> None:
        raise _Refused("a DOCTYPE is not allowed in a BehaviorTree.CPP file (no entities are read)")

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda _tag: stack.pop()
    parser.StartDoctypeDeclHandler = refuse
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise InputError([Diagnostic(file, exc.lineno, exc.offset + 1,
                                     f"malformed XML: {expat.ErrorString(exc.code)}")]) from None
    except _Refused as exc:
        at = data.find(b"<!DOCTYPE")
        line, col = (data.count(b"\n", 0, at) + 1, at - data.rfind(b"\n", 0, at)) if at >= 0 else (
            parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)
        raise InputError([Diagnostic(file, line, col, str(exc))]) from None
    return roots[0]


# -- what the conversion produces ---------------------------------------------------------------
@dataclass
class Draft:
    """One node of the mission being written, with the XML element it came from."""

    type: NodeType
    name: str | None
    ports: dict[str, Any]
    element: XmlElement
    children: list[Draft] = field(default_factory=list)


@dataclass
class MissionDraft:
    name: str
    tree: Draft
    sense: list[Draft]


Resolved = tuple[str, str]  # ("key", bearings key) or ("text", a literal a SubTree set)


@dataclass(frozen=True)
class _Scope:
    """How names inside one tree instance reach the blackboard (BT.CPP's SubTree remapping)."""

    tree: str
    remaps: dict[str, Resolved] | None = None  # None: the root blackboard
    autoremap: bool = False
    parent: _Scope | None = None

    def resolve(self, name: str) -> Resolved | str:
        """What a blackboard name means here, or why it means nothing in bearings."""
        if name.startswith("@") or self.remaps is None:
            key = _key_of(name)
            if key is None:
                return (f"{{{name}}} is not a bearings blackboard key (keys are written like @robot__odometry or "
                        "@perception__observation___count; see docs/missions.md)")
            return "key", key
        if name in self.remaps:
            return self.remaps[name]
        if self.autoremap and self.parent is not None:
            return self.parent.resolve(name)
        return (f"blackboard entry {name!r} is local to subtree {self.tree} (bearings has one blackboard: remap it "
                f"in the <SubTree>, e.g. {name}=\"{{@map__{name}}}\", or set _autoremap=\"true\")")


def _key_of(name: str) -> str | None:
    """The bearings key of an identifier (``@robot__odometry``) or a key written as it is."""
    body = name.removeprefix("@")
    if body.startswith("/"):
        return body if key_problem(body) is None else None
    return identifier_to_key(body)


_BAD = object()


class _Importer:
    """Turns located BT.CPP elements into drafts, collecting every problem."""

    def __init__(self, file: str, registry: Registry) -> None:
        self.file = file
        self.registry = registry
        self.problems: list[Diagnostic] = []
        self.trees: dict[str, XmlElement] = {}
        self.subtree_models: dict[str, dict[str, str | None]] = {}
        self.declared: set[str] = set()
        self.count = 0
        self.types: dict[str, NodeType] = {}
        for node_type in registry.all_types():
            self.types.setdefault(node_type.btcpp, node_type)
        for node_type in registry.all_types():
            self.types.setdefault(node_type.name, node_type)

    def error(self, element: XmlElement, message: str) -> None:
        self.problems.append(Diagnostic(self.file, element.line, element.col, message))

    # -- the document ----------------------------------------------------------------------
    def mission(self, root: XmlElement) -> MissionDraft | None:
        if root.tag != "root":
            self.error(root, f"a BehaviorTree.CPP file starts with <root>, not <{root.tag}>")
            return None
        version = root.attrs.get("BTCPP_format", "4")
        if version != "4":
            self.error(root, f"BTCPP_format {version!r}: bearings reads BehaviorTree.CPP v4 files (BT.CPP's "
                       "convert_v3_to_v4.py converts v3 files)")
            return None
        self._contents(root)
        main = self._main(root)
        if main is None:
            return None
        tree = self._tree(main, _Scope(main))
        sense = self._sense(main)
        if tree is None or sense is None:
            return None
        return MissionDraft(main, tree, sense)

    def _contents(self, root: XmlElement) -> None:
        single = sum(e.tag == "BehaviorTree" for e in root.children) == 1
        for element in root.children:
            if element.tag == "BehaviorTree":
                self._behavior_tree(element, single=single)
            elif element.tag == "TreeNodesModel":
                self._model(element)
            elif element.tag == "include":
                self.error(element, "<include> has no equivalent: bearings reads one file (inline the included "
                           "trees in Groot2, or import each file)")
            else:
                self.error(element, f"unknown element <{element.tag}> in <root> (expected BehaviorTree, "
                           "TreeNodesModel)")

    def _behavior_tree(self, element: XmlElement, *, single: bool) -> None:
        tree_id = element.attrs.get("ID", "MainTree" if single else None)
        if tree_id is None:
            self.error(element, "a <BehaviorTree> needs an ID when the file holds several")
        elif tree_id in self.trees:
            self.error(element, f"a second <BehaviorTree> with ID {tree_id!r}")
        elif len(element.children) != 1:
            self.error(element, f"<BehaviorTree ID={tree_id!r}> holds exactly one node, found "
                       f"{len(element.children)}")
        else:
            self.trees[tree_id] = element

    def _model(self, element: XmlElement) -> None:
        for entry in element.children:
            entry_id = entry.attrs.get("ID", "")
            self.declared.add(entry_id)
            if entry.tag == "SubTree":
                self.subtree_models[entry_id] = {
                    port.attrs.get("name", ""): port.attrs.get("default") for port in entry.children
                    if port.tag in ("input_port", "output_port", "inout_port")}

    def _main(self, root: XmlElement) -> str | None:
        named = root.attrs.get("main_tree_to_execute")
        if named is not None:
            if named not in self.trees:
                self.error(root, f"main_tree_to_execute names {named!r}, which no <BehaviorTree> has"
                           f"{suggest(named, self.trees)}")
                return None
            return named
        referenced = {e.attrs.get("ID") for tree in self.trees.values() for e in _walk(tree) if e.tag == "SubTree"}
        candidates = [t for t in self.trees if t not in referenced and not (
            t.endswith(SENSE_SUFFIX) and t.removesuffix(SENSE_SUFFIX) in self.trees)]
        if len(candidates) != 1:
            if not self.problems:
                self.error(root, "say which tree is the mission with main_tree_to_execute (candidates: "
                           f"{', '.join(candidates) or 'none'})")
            return None
        return candidates[0]

    def _tree(self, tree_id: str, scope: _Scope, chain: tuple[str, ...] = (), depth: int = 0) -> Draft | None:
        element = self.trees[tree_id]
        return self.node(element.children[0], scope, (*chain, tree_id), depth)

    def _sense(self, main: str) -> list[Draft] | None:
        element = self.trees.get(main + SENSE_SUFFIX)
        if element is None:
            return []
        sequence = element.children[0]
        if sequence.tag != "Sequence":
            self.error(sequence, f"tree {main + SENSE_SUFFIX} holds the mission's sense: nodes in one <Sequence>")
            return None
        drafts = [self.node(child, _Scope(main), (main + SENSE_SUFFIX,), 1) for child in sequence.children]
        return None if any(d is None for d in drafts) else [d for d in drafts if d is not None]

    # -- one node ------------------------------------------------------------------------------
    def node(self, element: XmlElement, scope: _Scope, chain: tuple[str, ...], depth: int) -> Draft | None:
        if not self._within_budget(element, depth):
            return None
        if element.tag == "SubTree":
            return self._subtree(element, scope, chain, depth)
        tag = element.attrs.get("ID", "") if element.tag in MODEL_TAGS else element.tag
        if not tag:
            self.error(element, f"<{element.tag}> names its node type with an ID attribute")
            return None
        made = self._made(element, tag, scope)
        children = [self.node(child, scope, chain, depth + 1) for child in element.children]
        if made is None or any(child is None for child in children):
            return None
        node_type, ports = made
        if not self._children_fit(element, node_type, len(children)):
            return None
        return Draft(node_type, element.attrs.get("name"), ports, element, [c for c in children if c is not None])

    def _within_budget(self, element: XmlElement, depth: int) -> bool:
        self.count += 1
        if depth > MAX_DEPTH:
            self.error(element, f"the tree is nested deeper than {MAX_DEPTH} levels")
            return False
        if self.count == MAX_NODES + 1:
            self.error(element, f"the tree expands to more than {MAX_NODES} nodes (a SubTree repeated too often?)")
        return self.count <= MAX_NODES

    def _made(self, element: XmlElement, tag: str, scope: _Scope) -> tuple[NodeType, dict[str, Any]] | None:
        """The bearings node type and ports of a BT.CPP element, or None with the problem reported."""
        translate = TRANSLATIONS.get(tag)
        if translate is not None:
            return translate(self, element, scope)
        if tag in NO_EQUIVALENT:
            self.error(element, f"BehaviorTree.CPP's {tag} has no bearings equivalent: {NO_EQUIVALENT[tag]}")
            return None
        node_type = self.types.get(tag)
        if node_type is None:
            self.error(element, self._unknown(tag))
            return None
        ports = self._ports(element, node_type, scope)
        return None if ports is None else (node_type, ports)

    def _unknown(self, tag: str) -> str:
        if tag in self.declared:
            return (f"node type {tag!r} is declared in the file's TreeNodesModel but bearings has no such node "
                    "type (write it as a behaviour and list it under plugins:)")
        return f"unknown node type {tag!r}{suggest(tag, [*self.types, *TRANSLATIONS])}"

    def _children_fit(self, element: XmlElement, node_type: NodeType, count: int) -> bool:
        low, high = node_type.min_children, node_type.max_children
        if low <= count and (high is None or count <= high):
            return True
        if high == 0:
            wanted = "no children (it is a leaf)"
        elif high == low:
            wanted = f"exactly {low} {'child' if low == 1 else 'children'}"
        else:
            wanted = f"at least {low} {'child' if low == 1 else 'children'}"
        self.error(element, f"<{element.tag}> ({node_type.name}) takes {wanted}, found {count}")
        return False

    def _subtree(self, element: XmlElement, scope: _Scope, chain: tuple[str, ...], depth: int) -> Draft | None:
        tree_id = element.attrs.get("ID")
        if tree_id is None or tree_id not in self.trees:
            self.error(element, f"<SubTree> names tree {tree_id!r}, which the file does not hold"
                       f"{suggest(tree_id, self.trees)}")
            return None
        if tree_id in chain:
            self.error(element, f"subtree cycle: {' -> '.join((*chain[chain.index(tree_id):], tree_id))}")
            return None
        inner = self._subtree_scope(element, tree_id, scope)
        draft = self._tree(tree_id, inner, chain, depth + 1) if inner is not None else None
        if draft is not None and "name" in element.attrs:
            draft = replace(draft, name=element.attrs["name"])
        return draft

    def _subtree_scope(self, element: XmlElement, tree_id: str, scope: _Scope) -> _Scope | None:
        """The remapping of one SubTree instance: its attributes, then its model's defaults."""
        autoremap = element.attrs.get("_autoremap", "false").strip() in TRUE_TEXT
        given = {name: text for name, text in element.attrs.items() if self._is_port(element, name)}
        for port, default in self.subtree_models.get(tree_id, {}).items():
            if port in given or autoremap:
                continue
            if default is None:
                self.error(element, f"<SubTree ID={tree_id!r}> must remap port {port!r} (its model gives no default)")
                return None
            given[port] = default
        remaps: dict[str, Resolved] = {}
        for name, text in given.items():
            pointer = blackboard_pointer(text)
            resolved = ("text", text) if pointer is None else scope.resolve(name if pointer == "=" else pointer)
            if isinstance(resolved, str):
                self.error(element, f"<SubTree ID={tree_id!r}> port {name!r}: {resolved}")
                return None
            remaps[name] = resolved
        return _Scope(tree_id, remaps, autoremap, scope)

    # -- ports ---------------------------------------------------------------------------------
    def _is_port(self, element: XmlElement, name: str) -> bool:
        """Is this attribute a port? Scripted pre/post conditions are reported; metadata is skipped."""
        if name in PRE_POST_CONDITIONS:
            self.error(element, f"{name}: scripted pre- and post-conditions have no bearings equivalent (use a "
                       "Guard or a CheckBlackboard)")
            return False
        return is_port_name(name) and not (name == "ID" and element.tag in (*MODEL_TAGS, "SubTree"))

    def _ports(self, element: XmlElement, node_type: NodeType, scope: _Scope) -> dict[str, Any] | None:
        """A bearings node's ports from the element's attributes (``name`` and metadata aside)."""
        declared = node_type.ports
        ports: dict[str, Any] = {}
        ok = True
        for name, text in element.attrs.items():
            if not self._is_port(element, name):
                ok = ok and name not in PRE_POST_CONDITIONS
                continue
            port = declared.get(name)
            if port is None:
                takes = ", ".join(declared) or "no ports"
                self.error(element, f"{node_type.name} has no port {name!r}{suggest(name, declared)} (it takes: "
                           f"{takes})")
                ok = False
                continue
            value = self._port_value(element, node_type, port, text, scope)
            if value is _BAD:
                ok = False
            elif not _is_default(port, value):
                ports[name] = value
        return ports if ok else None

    def _port_value(self, element: XmlElement, node_type: NodeType, port: InputPort | OutputPort, text: str,
                    scope: _Scope) -> Any:
        owner = f"{node_type.name}.{port.name}"
        pointer = blackboard_pointer(text)
        if pointer is not None:
            resolved = scope.resolve(port.name if pointer == "=" else pointer)
            if isinstance(resolved, str):
                self.error(element, f"{owner}: {resolved}")
                return _BAD
            kind, value = resolved
            if kind == "key":
                return Ref(value)
            text = value  # a literal a SubTree set
        if isinstance(port, OutputPort):
            self.error(element, f"{owner} is an output: write the blackboard entry it writes, like "
                       f"{{{key_to_identifier(port.key)}}}")
            return _BAD
        return parse_value(text, port.type)

    def given(self, element: XmlElement, tag: str, scope: _Scope) -> dict[str, str] | None:
        """The literal attributes of a BT.CPP built-in node (its own ports only, none from the blackboard)."""
        allowed = BUILTIN_PORTS[tag]
        values: dict[str, str] = {}
        ok = True
        for name, text in element.attrs.items():
            if not self._is_port(element, name):
                ok = ok and name not in PRE_POST_CONDITIONS
                continue
            if name not in allowed:
                takes = ", ".join(allowed) or "no ports"
                self.error(element, f"BehaviorTree.CPP's {tag} has no port {name!r}{suggest(name, allowed)} (it "
                           f"takes: {takes})")
                ok = False
                continue
            value = self._literal(element, tag, name, text, scope)
            ok = ok and value is not None
            values[name] = value or ""
        return values if ok else None

    def _literal(self, element: XmlElement, tag: str, name: str, text: str, scope: _Scope) -> str | None:
        pointer = blackboard_pointer(text)
        if pointer is None:
            return text
        resolved = scope.resolve(name if pointer == "=" else pointer)
        if isinstance(resolved, tuple) and resolved[0] == "text":
            return resolved[1]
        self.error(element, f"{tag}.{name} read from the blackboard has no equivalent: bearings takes it as a "
                   "literal value")
        return None

    def comparison(self, element: XmlElement, owner: str, script: str, scope: _Scope) -> dict[str, Any] | None:
        """Guard/CheckBlackboard ports from a script ``name op literal``."""
        parsed: Comparison | None = parse_comparison(script)
        if parsed is None:
            self.error(element, f"{owner}: the script {script!r} has no bearings equivalent (bearings compares one "
                       "blackboard entry with a literal: '@robot__odometry___x >= 1.5')")
            return None
        resolved = scope.resolve(parsed.name)
        if isinstance(resolved, str) or resolved[0] != "key":
            problem = resolved if isinstance(resolved, str) else f"{parsed.name} is a constant, not an entry"
            self.error(element, f"{owner}: {problem}")
            return None
        return {"key": resolved[1], "op": parsed.op, "value": parsed.value}


def _is_default(port: InputPort | OutputPort, value: Any) -> bool:
    if isinstance(port, OutputPort):
        return value == Ref(port.key)
    if port.default is REQUIRED:
        return False
    default = parse_ref(port.default) or port.default
    return type(default) is type(value) and default == value


def _walk(element: XmlElement) -> Iterable[XmlElement]:
    yield element
    for child in element.children:
        yield from _walk(child)


# -- BT.CPP's built-in nodes, mapped back ---------------------------------------------------------
Made = tuple[NodeType, dict[str, Any]] | None
Translation = Callable[[_Importer, XmlElement, _Scope], Made]


def _builtin(importer: _Importer, name: str) -> NodeType:
    node_type = importer.registry.lookup(name)
    assert node_type is not None, f"built-in node type {name} is missing"
    return node_type


def _memory(tag: str, node_type: str, memory: bool) -> Translation:
    def translate(importer: _Importer, element: XmlElement, scope: _Scope) -> Made:
        if importer.given(element, tag, scope) is None:
            return None
        return _builtin(importer, node_type), {} if memory else {"memory": False}
    return translate


def _integer(importer: _Importer, element: XmlElement, owner: str, text: str | None, default: int) -> int | None:
    if text is None:
        return default
    value = parse_value(text, int)
    if not isinstance(value, int):
        importer.error(element, f"{owner} expects a whole number, got {text!r}")
        return None
    return value


def _parallel(importer: _Importer, element: XmlElement, scope: _Scope) -> Made:
    given = importer.given(element, "Parallel", scope)
    if given is None:
        return None
    count = len(element.children)
    success = _integer(importer, element, "Parallel.success_count", given.get("success_count"), -1)
    failure = _integer(importer, element, "Parallel.failure_count", given.get("failure_count"), 1)
    if success is None or failure is None:
        return None
    policy = "one" if success == 1 else "all" if success in (-1, count) else None
    if policy is None:
        importer.error(element, f"Parallel success_count {success} has no equivalent: bearings' Parallel succeeds "
                       "when all children did (-1) or when one did (1)")
    if failure != 1 and not (failure == -1 and count == 1):
        importer.error(element, f"Parallel failure_count {failure} has no equivalent: bearings' Parallel fails as "
                       "soon as one child fails (1)")
        return None
    return (_builtin(importer, "Parallel"), {} if policy == "all" else {"policy": policy}) if policy else None


def _milliseconds(tag: str, node_type: str, port: str) -> Translation:
    def translate(importer: _Importer, element: XmlElement, scope: _Scope) -> Made:
        given = importer.given(element, tag, scope)
        if given is None:
            return None
        if "msec" not in given:
            importer.error(element, f"{tag} needs msec")
            return None
        msec = _integer(importer, element, f"{tag}.msec", given["msec"], 0)
        return None if msec is None else (_builtin(importer, node_type), {port: msec / 1000})
    return translate


def _run_once(importer: _Importer, element: XmlElement, scope: _Scope) -> Made:
    given = importer.given(element, "RunOnce", scope)
    if given is None:
        return None
    then_skip = parse_value(given.get("then_skip", "true"), bool)
    if then_skip is not False:
        importer.error(element, "RunOnce with then_skip=\"true\" (its default) has no equivalent: it returns "
                       "SKIPPED after the first run; then_skip=\"false\" is bearings' OneShot policy on_completion")
        return None
    return _builtin(importer, "OneShot"), {"policy": "on_completion"}


def _precondition(importer: _Importer, element: XmlElement, scope: _Scope) -> Made:
    given = importer.given(element, "Precondition", scope)
    if given is None:
        return None
    if given.get("else", "FAILURE").strip() != "FAILURE":
        importer.error(element, f"Precondition else={given['else']!r} has no equivalent: a Guard fails when its "
                       "condition does not hold")
        return None
    if "if" not in given:
        importer.error(element, "Precondition needs its if script")
        return None
    ports = importer.comparison(element, "Precondition.if", given["if"], scope)
    return None if ports is None else (_builtin(importer, "Guard"), ports)


def _script_condition(importer: _Importer, element: XmlElement, scope: _Scope) -> Made:
    given = importer.given(element, "ScriptCondition", scope)
    if given is None:
        return None
    if "code" not in given:
        importer.error(element, "ScriptCondition needs its code")
        return None
    ports = importer.comparison(element, "ScriptCondition.code", given["code"], scope)
    return None if ports is None else (_builtin(importer, "CheckBlackboard"), ports)


def _keep_running(importer: _Importer, element: XmlElement, scope: _Scope) -> Made:
    if importer.given(element, "KeepRunningUntilFailure", scope) is None:
        return None
    return _builtin(importer, "Repeat"), {"num_cycles": -1}


TRANSLATIONS: dict[str, Translation] = {
    "Sequence": _memory("Sequence", "Sequence", True),
    "ReactiveSequence": _memory("ReactiveSequence", "Sequence", False),
    "Fallback": _memory("Fallback", "Selector", True),
    "ReactiveFallback": _memory("ReactiveFallback", "Selector", False),
    "Parallel": _parallel, "Timeout": _milliseconds("Timeout", "Timeout", "duration"),
    "Sleep": _milliseconds("Sleep", "Wait", "duration"), "RunOnce": _run_once, "Precondition": _precondition,
    "ScriptCondition": _script_condition, "KeepRunningUntilFailure": _keep_running,
}  # fmt: skip
"""BT.CPP built-ins whose ports differ from their bearings counterpart's (the others keep theirs)."""


# -- writing and checking the mission -------------------------------------------------------------
def _plain(draft: Draft) -> Any:
    """A draft as mission YAML writes it: ``Type: {name, ports, child | children}`` or the bare name."""
    body: dict[str, Any] = {}
    if draft.name is not None and draft.name != draft.type.name:
        body["name"] = draft.name
    body.update({k: str(v) if isinstance(v, Ref) else v for k, v in draft.ports.items()})
    if draft.type.kind == "decorator":
        body["child"] = _plain(draft.children[0])
    elif draft.type.kind == "composite":
        body["children"] = [_plain(child) for child in draft.children]
    return {draft.type.name: body} if body else draft.type.name


def dump_mission(document: dict[str, Any]) -> str:
    """Plain mission data as YAML text the mission loader reads back to the same values."""
    return dump_yaml(document)


def render(mission: MissionDraft, source: str) -> str:
    """The mission file's text."""
    document: dict[str, Any] = {"mission": mission.name}
    if mission.sense:
        document["sense"] = [_plain(node) for node in mission.sense]
    document["tree"] = _plain(mission.tree)
    return f"# Imported from {source} (BehaviorTree.CPP v4) by bearings import.\n{dump_mission(document)}"


Start = tuple[int, int]  # line, column in the rendered mission text


def _node_starts(text: str, mission: MissionDraft) -> list[tuple[Start, Draft]]:
    """Where each draft starts in the rendered text, in order (to report the loader's problems in the XML)."""
    data = parse_yaml(text)
    out: list[tuple[Start, Draft]] = []
    sense = data.get("sense", [])
    for index, node in enumerate(mission.sense):
        _lines(sense[index], sense.mark_of(index), node, out)
    _lines(data["tree"], data.value_mark_of("tree"), mission.tree, out)
    return sorted(out, key=lambda item: item[0])


def _lines(raw: Any, mark: Mark, draft: Draft, out: list[tuple[Start, Draft]]) -> None:
    out.append(((mark.line, mark.col), draft))
    if not draft.children:
        return
    body = raw[draft.type.name]
    if isinstance(body, YamlMap) and draft.type.kind == "decorator":
        _lines(body["child"], body.value_mark_of("child"), draft.children[0], out)
    elif isinstance(body, YamlMap) and isinstance(body.get("children"), YamlList):
        items = body["children"]
        for index, child in enumerate(draft.children):
            _lines(items[index], items.mark_of(index), child, out)


def _validated(text: str, mission: MissionDraft, file: str, registry: Registry | None) -> None:
    """Load the written mission as ``bearings validate`` would; its problems, located in the XML."""
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "imported.yaml")
        Path(path).write_text(text, encoding="utf-8")
        try:
            load_mission(path, registry=registry)
        except InputError as exc:
            starts = _node_starts(text, mission)
            raise InputError([_in_xml(d, path, file, starts) for d in exc.diagnostics]) from None


def _in_xml(diagnostic: Diagnostic, path: str, file: str, starts: list[tuple[Start, Draft]]) -> Diagnostic:
    """A problem of the written mission, at the XML node it came from (naming the bearings type
    the node became when the names differ: ``<RetryUntilSuccessful> as Retry: ...``)."""
    if diagnostic.file != path:
        return diagnostic
    draft = next((d for start, d in reversed(starts) if start <= (diagnostic.line, diagnostic.col)), None)
    if draft is None:
        return Diagnostic(file, 0, 0, diagnostic.message)
    element = draft.element
    tag = element.attrs.get("ID", "") if element.tag in MODEL_TAGS else element.tag
    prefix = "" if tag == draft.type.name else f"<{tag}> as {draft.type.name}: "
    return Diagnostic(file, element.line, element.col, prefix + diagnostic.message)


def import_btcpp(path: str | os.PathLike, *, registry: Registry | None = None) -> str:
    """The mission text for a BehaviorTree.CPP v4 file, validated; :class:`InputError` with every problem."""
    file = str(path)
    data = read_bytes(path, limit=MAX_FILE_BYTES, what="a BehaviorTree.CPP XML file")
    root = parse_xml(data, file)
    importer = _Importer(file, registry or Registry.default())
    mission = importer.mission(root)
    if importer.problems or mission is None:
        raise InputError(importer.problems)
    text = render(mission, Path(file).name)
    _validated(text, mission, file, registry)
    return text
