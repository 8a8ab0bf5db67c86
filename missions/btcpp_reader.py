"""Reading a BehaviorTree.CPP document into drafts of bearings nodes, collecting every problem.

The second step of ``bearings import`` (:mod:`missions.importer`): from the located XML
(:mod:`missions.btcpp_xml`), find the main tree and its ``_sense`` companion, inline every
``<SubTree>`` with its remapping (:mod:`missions.btcpp_scope`), and turn each element into a
:class:`Draft`: a bearings node type with its ports, remembering the element it came from.
Elements of bearings node types keep their ports (read as the declaration types them, blackboard
pointers mapped back to keys); BT.CPP's built-ins with other ports go through
:data:`missions.btcpp_builtins.TRANSLATIONS`. Every problem is collected with the element's line,
so one run reports them all.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass, field, replace
from typing import Any

from behaviours.ports import REQUIRED, InputPort, OutputPort, Ref, parse_ref
from behaviours.registry import NodeType, Registry
from maps.located import suggest
from maps.store import Diagnostic
from missions.btcpp import (
    BUILTIN_PORTS,
    NO_EQUIVALENT,
    PRE_POST_CONDITIONS,
    SENSE_SUFFIX,
    TRUE_TEXT,
    blackboard_pointer,
    is_port_name,
    key_to_identifier,
    parse_value,
)
from missions.btcpp_builtins import TRANSLATIONS
from missions.btcpp_scope import Resolved, Scope
from missions.btcpp_xml import MODEL_TAGS, XmlElement, node_tag, walk
from missions.nodes import MAX_DEPTH, MAX_NODES


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
    """The mission being written: its name (the main tree's ID), task tree and ``sense:`` nodes."""

    name: str
    tree: Draft
    sense: list[Draft]


_BAD = object()  # a port value that could not be read (the problem is reported)


class Reader:
    """Turns located BT.CPP elements into drafts, collecting every problem (:attr:`problems`)."""

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
        tree = self._tree(main, Scope(main))
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
        referenced = {e.attrs.get("ID") for tree in self.trees.values() for e in walk(tree) if e.tag == "SubTree"}
        candidates = [t for t in self.trees if t not in referenced and not (
            t.endswith(SENSE_SUFFIX) and t.removesuffix(SENSE_SUFFIX) in self.trees)]
        if len(candidates) != 1:
            if not self.problems:
                self.error(root, "say which tree is the mission with main_tree_to_execute (candidates: "
                           f"{', '.join(candidates) or 'none'})")
            return None
        return candidates[0]

    def _tree(self, tree_id: str, scope: Scope, chain: tuple[str, ...] = (), depth: int = 0) -> Draft | None:
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
        drafts = [self.node(child, Scope(main), (main + SENSE_SUFFIX,), 1) for child in sequence.children]
        return None if any(d is None for d in drafts) else [d for d in drafts if d is not None]

    # -- one node ------------------------------------------------------------------------------
    def node(self, element: XmlElement, scope: Scope, chain: tuple[str, ...], depth: int) -> Draft | None:
        if not self._within_budget(element, depth):
            return None
        if element.tag == "SubTree":
            return self._subtree(element, scope, chain, depth)
        tag = node_tag(element)
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

    def _made(self, element: XmlElement, tag: str, scope: Scope) -> tuple[NodeType, dict[str, Any]] | None:
        """The bearings node type and ports of a BT.CPP element, or None with the problem reported."""
        translate = TRANSLATIONS.get(tag)
        if translate is not None:
            given = self.given(element, tag, scope)
            made = None if given is None else translate(self, element, given, scope)
            return None if made is None else (self._builtin(made[0]), made[1])
        if tag in NO_EQUIVALENT:
            self.error(element, f"BehaviorTree.CPP's {tag} has no bearings equivalent: {NO_EQUIVALENT[tag]}")
            return None
        node_type = self.types.get(tag)
        if node_type is None:
            self.error(element, self._unknown(tag))
            return None
        ports = self._ports(element, node_type, scope)
        return None if ports is None else (node_type, ports)

    def _builtin(self, name: str) -> NodeType:
        node_type = self.registry.lookup(name)
        assert node_type is not None, f"built-in node type {name} is missing"
        return node_type

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

    def _subtree(self, element: XmlElement, scope: Scope, chain: tuple[str, ...], depth: int) -> Draft | None:
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

    def _subtree_scope(self, element: XmlElement, tree_id: str, scope: Scope) -> Scope | None:
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
            resolved = ("text", text) if pointer is None else scope.pointed(name, pointer)
            if isinstance(resolved, str):
                self.error(element, f"<SubTree ID={tree_id!r}> port {name!r}: {resolved}")
                return None
            remaps[name] = resolved
        return Scope(tree_id, remaps, autoremap, scope)

    # -- ports ---------------------------------------------------------------------------------
    def _is_port(self, element: XmlElement, name: str) -> bool:
        """Is this attribute a port? Scripted pre/post conditions are reported; metadata is skipped."""
        if name in PRE_POST_CONDITIONS:
            self.error(element, f"{name}: scripted pre- and post-conditions have no bearings equivalent (use a "
                       "Guard or a CheckBlackboard)")
            return False
        return is_port_name(name) and not (name == "ID" and element.tag in (*MODEL_TAGS, "SubTree"))

    def _ports(self, element: XmlElement, node_type: NodeType, scope: Scope) -> dict[str, Any] | None:
        """A bearings node's ports from the element's attributes (``name`` and metadata aside)."""
        declared = node_type.ports
        ports = self._each_port(element, node_type.name, declared,
                                lambda name, text: self._port_value(element, node_type, declared[name], text, scope))
        return None if ports is None else {k: v for k, v in ports.items() if not _is_default(declared[k], v)}

    def _port_value(self, element: XmlElement, node_type: NodeType, port: InputPort | OutputPort, text: str,
                    scope: Scope) -> Any:
        owner = f"{node_type.name}.{port.name}"
        pointer = blackboard_pointer(text)
        if pointer is not None:
            resolved = scope.pointed(port.name, pointer)
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

    def given(self, element: XmlElement, tag: str, scope: Scope) -> dict[str, str] | None:
        """The literal attributes of a BT.CPP built-in node (its own ports only, none from the blackboard)."""
        return self._each_port(element, f"BehaviorTree.CPP's {tag}", BUILTIN_PORTS[tag],
                               lambda name, text: self._literal(element, tag, name, text, scope))

    def _each_port(self, element: XmlElement, owner: str, allowed: Collection[str],
                   read: Callable[[str, str], Any]) -> dict[str, Any] | None:
        """Every port attribute of the element, read by ``read(name, text)``; None when any is not one of
        ``allowed`` or cannot be read (every problem reported, in the order of the attributes)."""
        values: dict[str, Any] = {}
        ok = True
        for name, text in element.attrs.items():
            if not self._is_port(element, name):
                ok = ok and name not in PRE_POST_CONDITIONS
                continue
            if name not in allowed:
                takes = ", ".join(allowed) or "no ports"
                self.error(element, f"{owner} has no port {name!r}{suggest(name, allowed)} (it takes: {takes})")
                ok = False
                continue
            value = read(name, text)
            if value is _BAD:
                ok = False
            else:
                values[name] = value
        return values if ok else None

    def _literal(self, element: XmlElement, tag: str, name: str, text: str, scope: Scope) -> Any:
        """A built-in's port as text (a literal, or one a SubTree set), or ``_BAD`` (reported)."""
        pointer = blackboard_pointer(text)
        if pointer is None:
            return text
        resolved = scope.pointed(name, pointer)
        if isinstance(resolved, tuple) and resolved[0] == "text":
            return resolved[1]
        self.error(element, f"{tag}.{name} read from the blackboard has no equivalent: bearings takes it as a "
                   "literal value")
        return _BAD


def _is_default(port: InputPort | OutputPort, value: Any) -> bool:
    if isinstance(port, OutputPort):
        return value == Ref(port.key)
    if port.default is REQUIRED:
        return False
    default = parse_ref(port.default) or port.default
    return type(default) is type(value) and default == value
