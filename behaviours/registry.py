"""Node types and the registries a mission is loaded against.

Every node type, leaf or control, is one class that declares itself with class attributes::

    @register
    class Drive(BearingsBehaviour):
        \"\"\"Drive straight ``distance`` metres.\"\"\"
        KIND = "action"                       # action | condition | decorator | composite
        PORTS = (InputPort("distance", float, unit="m"), OutputPort("command", VelocityCommand,
                 "/robot/command"))
        BTCPP = None                          # its name in BehaviorTree.CPP XML (default: the class name)
        CHILDREN = (0, 0)                     # fewest and most children (None: no limit)

``@register`` only marks the class; nothing is added to a process-wide table. A
:class:`Registry` collects marked classes from the modules it is given: the built-in one holds
bearings' own node types, :meth:`Registry.default` adds installed packages' entry points
(group ``bearings.behaviours``), and each mission's plugins go into a :meth:`Registry.child` of
its own, so a sweep that loads many missions in one process never leaks one mission's plugins
into the next.
"""

from __future__ import annotations

import functools
import importlib
import importlib.metadata
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from types import ModuleType
from typing import Any, ClassVar, Literal

import py_trees

from behaviours.ports import InputPort, OutputPort, Port, file_port_problem

Kind = Literal["action", "condition", "decorator", "composite"]
KINDS: tuple[Kind, ...] = ("action", "condition", "decorator", "composite")
ENTRY_POINT_GROUP = "bearings.behaviours"
BUILTIN_MODULES = (
    "behaviours.control", "behaviours.composites", "behaviours.decorators", "behaviours.motion", "behaviours.wait",
    "behaviours.conditions", "behaviours.perceive", "behaviours.avoidance",
    # teach and repeat (the LT-map)
    "behaviours.landmark_tree", "behaviours.teach", "behaviours.route", "behaviours.route_skip", "behaviours.search",
    "behaviours.teleop",
    "behaviours.waypoints", "behaviours.choice",
    # the roadmap between target images
    *(f"behaviours.roadmap.{m}" for m in ("targets", "calibration", "room", "coverage", "travel", "scan", "homing",
                                          "graph", "navigate")),
    # exploration with the stereo pair on the pan-tilt unit
    *(f"behaviours.exploration.{m}" for m in ("localise", "map_stereo", "select_goal", "follow_path", "gaze",
                                              "look_around")),
)  # fmt: skip
_MARK = "__bearings_node_type__"


class Declared:
    """The declaration every node class carries (defaults for a leaf action with no ports)."""

    KIND: ClassVar[Kind] = "action"
    PORTS: ClassVar[tuple[Port, ...]] = ()
    BTCPP: ClassVar[str | None] = None
    CHILDREN: ClassVar[tuple[int, int | None]] = (0, 0)


def register(cls: type) -> type:
    """Class decorator: mark a node class so registries built from its module include it."""
    if not (isinstance(cls, type) and issubclass(cls, py_trees.behaviour.Behaviour)):
        raise TypeError("@register takes a py_trees Behaviour subclass with a bearings declaration")
    NodeType.of(cls)  # fail at import, not at load, if the declaration is malformed
    setattr(cls, _MARK, True)
    return cls


def is_registered(cls: Any) -> bool:
    return isinstance(cls, type) and _MARK in cls.__dict__


@dataclass(frozen=True)
class NodeType:
    """What the loader, the data-flow check, the schema and the exporters know about a node class."""

    name: str
    cls: type
    kind: Kind
    inputs: tuple[InputPort, ...]
    outputs: tuple[OutputPort, ...]
    doc: str
    btcpp: str
    min_children: int
    max_children: int | None

    @classmethod
    def of(cls, node_cls: type) -> NodeType:
        """The node type a class declares; ``ValueError`` when the declaration is malformed."""
        name = node_cls.__name__
        kind: Kind = getattr(node_cls, "KIND", "action")
        ports = tuple(getattr(node_cls, "PORTS", ()))
        low, high = getattr(node_cls, "CHILDREN", (0, 0))
        problems = _declaration_problems(name, kind, ports, low, high)
        if problems:
            raise ValueError(f"node type {name} ({node_cls.__module__}): {'; '.join(problems)}")
        return cls(
            name=name, cls=node_cls, kind=kind,
            inputs=tuple(p for p in ports if isinstance(p, InputPort)),
            outputs=tuple(p for p in ports if isinstance(p, OutputPort)),
            doc=_first_paragraph(node_cls.__doc__), btcpp=getattr(node_cls, "BTCPP", None) or name,
            min_children=low, max_children=high,
        )  # fmt: skip

    @property
    def module(self) -> str:
        return self.cls.__module__

    @property
    def takes_children(self) -> bool:
        return self.kind in ("decorator", "composite")

    @property
    def ports(self) -> dict[str, Port]:
        declared: list[Port] = [*self.inputs, *self.outputs]
        return {p.name: p for p in declared}

    def build(self, *, name: str, children: list[py_trees.behaviour.Behaviour], ports: dict[str, Any]
              ) -> py_trees.behaviour.Behaviour:
        """An instance: ``cls(name=..., [child=... | children=...], **ports)``."""
        if self.kind == "composite":
            return self.cls(name=name, children=children, **ports)
        if self.kind == "decorator":
            return self.cls(name=name, child=children[0], **ports)
        return self.cls(name=name, **ports)


def _declaration_problems(name: str, kind: Any, ports: tuple[Any, ...], low: Any, high: Any) -> list[str]:
    problems = []
    if not name[:1].isupper():
        problems.append("node type names are CamelCase")
    if kind not in KINDS:
        problems.append(f"KIND must be one of {', '.join(KINDS)}, not {kind!r}")
    names = [getattr(p, "name", None) for p in ports]
    if not all(isinstance(p, (InputPort, OutputPort)) for p in ports):
        problems.append("PORTS holds InputPort and OutputPort values only")
    elif len(set(names)) != len(names) or {"name", "child", "children"} & set(names):
        problems.append("port names must be unique and not 'name', 'child' or 'children'")
    else:
        problems += [p for p in (file_port_problem(port) for port in ports if isinstance(port, InputPort)) if p]
    leaf = kind in ("action", "condition")
    if not (isinstance(low, int) and (high is None or isinstance(high, int))) or (leaf and (low, high) != (0, 0)):
        problems.append("CHILDREN is (fewest, most); leaves take (0, 0)")
    elif not leaf and (low < 1 or (high is not None and high < low)):
        problems.append("a control node takes at least one child")
    return problems


class Registry:
    """The node types one mission may name: its own, then its parent's (lookups fall through)."""

    def __init__(self, parent: Registry | None = None) -> None:
        self.parent = parent
        self._types: dict[str, NodeType] = {}

    # -- building --------------------------------------------------------------------------
    @classmethod
    def builtin(cls) -> Registry:
        """bearings' own node types (shared, read-only by convention: extend a :meth:`child`)."""
        return _builtin()

    @classmethod
    def default(cls) -> Registry:
        """A fresh registry over the built-ins and installed entry points, for one mission."""
        return _with_entry_points().child()

    def child(self) -> Registry:
        return Registry(parent=self)

    def add(self, node_cls: type) -> NodeType:
        """Add one node class; a name already known here or in a parent is an error."""
        node_type = NodeType.of(node_cls)
        existing = self.lookup(node_type.name)
        if existing is not None and existing.cls is not node_cls:
            raise ValueError(f"node type {node_type.name!r} from {node_type.module} clashes with the one from "
                             f"{existing.module}")
        self._types[node_type.name] = node_type
        return node_type

    def add_module(self, module: ModuleType) -> list[NodeType]:
        """Add every class ``@register`` marked that ``module`` defines; the node types added."""
        classes = [obj for obj in vars(module).values() if is_registered(obj) and obj.__module__ == module.__name__]
        return [self.add(c) for c in classes]

    # -- reading ---------------------------------------------------------------------------
    def lookup(self, name: str) -> NodeType | None:
        found = self._types.get(name)
        if found is None and self.parent is not None:
            return self.parent.lookup(name)
        return found

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and self.lookup(name) is not None

    def __iter__(self) -> Iterator[NodeType]:
        return iter(self.all_types())

    def all_types(self) -> list[NodeType]:
        merged = {t.name: t for t in (self.parent.all_types() if self.parent else [])}
        merged.update(self._types)
        return sorted(merged.values(), key=lambda t: (KINDS.index(t.kind), t.name))

    def names(self) -> list[str]:
        return [t.name for t in self.all_types()]


@functools.cache
def _builtin() -> Registry:
    registry = Registry()
    for name in BUILTIN_MODULES:
        registry.add_module(importlib.import_module(name))
    return registry


@functools.cache
def _with_entry_points() -> Registry:
    """Built-ins plus the node types of installed packages (entry point group ``bearings.behaviours``)."""
    registry = _builtin().child()
    for entry in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        add_entry_point(registry, entry.load)
    return registry


def add_entry_point(registry: Registry, load: Callable[[], Any]) -> None:
    """An entry point names a module (all its marked classes) or one node class."""
    target = load()
    if isinstance(target, ModuleType):
        registry.add_module(target)
    else:
        registry.add(target)


def _first_paragraph(doc: str | None) -> str:
    if not doc:
        return ""
    return " ".join(doc.strip().split("\n\n", 1)[0].split())


def node_types(classes: Iterable[type]) -> list[NodeType]:
    """Node types of classes that are not in any registry (the runner's own sense nodes)."""
    return [NodeType.of(c) for c in classes]
