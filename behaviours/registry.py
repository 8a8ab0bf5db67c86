"""The registry of node types a mission may name.

A mission can only instantiate registered node types: built-in composites and decorators, the
bearings behaviours, and behaviours registered by plugins the mission lists explicitly or by
installed packages through the ``bearings.behaviours`` entry-point group.
"""

from __future__ import annotations

import importlib
import importlib.metadata
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import py_trees

from behaviours.base import BearingsBehaviour
from behaviours.ports import Param

Kind = Literal["action", "condition", "decorator", "composite"]
ENTRY_POINT_GROUP = "bearings.behaviours"


@dataclass(frozen=True)
class NodeType:
    """What the loader, the schema and the exporters know about one node type.

    ``factory(name=..., **params)`` builds leaves; decorators also get ``child=``, composites
    ``children=``. ``btcpp`` is the element name used when exporting BehaviorTree.CPP XML.
    """

    name: str
    kind: Kind
    factory: Callable[..., py_trees.behaviour.Behaviour]
    params: tuple[Param, ...] = ()
    reads: tuple[str, ...] = ()
    writes: tuple[str, ...] = ()
    doc: str = ""
    btcpp: str | None = None
    min_children: int = 0
    max_children: int | None = None
    module: str = ""

    @property
    def takes_children(self) -> bool:
        return self.kind in ("decorator", "composite")


_REGISTRY: dict[str, NodeType] = {}
_entry_points_loaded = False


def register_type(node_type: NodeType) -> NodeType:
    """Add a node type; a name can be registered once (re-registering the same module is fine)."""
    old = _REGISTRY.get(node_type.name)
    if old is not None and old.module != node_type.module:
        raise ValueError(f"node type {node_type.name!r} is already registered by {old.module}")
    _REGISTRY[node_type.name] = node_type
    return node_type


def register(cls: type[BearingsBehaviour]) -> type[BearingsBehaviour]:
    """Class decorator: register a :class:`BearingsBehaviour` under its class name."""
    if not (isinstance(cls, type) and issubclass(cls, BearingsBehaviour)):
        raise TypeError("@register takes a BearingsBehaviour subclass")
    if not cls.__name__[:1].isupper():
        raise ValueError(f"behaviour names are CamelCase: {cls.__name__!r}")
    register_type(
        NodeType(
            name=cls.__name__,
            kind="condition" if cls.KIND == "condition" else "action",
            factory=cls,
            params=cls.PARAMS,
            reads=cls.READS,
            writes=cls.WRITES,
            doc=_first_paragraph(cls.__doc__),
            module=cls.__module__,
        )
    )
    return cls


def lookup(name: str) -> NodeType | None:
    _load_entry_points()
    return _REGISTRY.get(name)


def all_types() -> list[NodeType]:
    _load_entry_points()
    return sorted(_REGISTRY.values(), key=lambda t: (t.kind, t.name))


def import_plugin(module: str) -> None:
    """Import a user plugin module (it registers its behaviours on import)."""
    importlib.import_module(module)


def _load_entry_points() -> None:
    global _entry_points_loaded
    if _entry_points_loaded:
        return
    _entry_points_loaded = True
    for entry in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        entry.load()


def _first_paragraph(doc: str | None) -> str:
    if not doc:
        return ""
    return " ".join(doc.strip().split("\n\n", 1)[0].split())
