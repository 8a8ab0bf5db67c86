"""How a name inside one BehaviorTree.CPP tree instance reaches the blackboard (SubTree remapping).

BT.CPP gives every SubTree instance a blackboard of its own, joined to its parent's only through
the ports the ``<SubTree>`` element remaps (or all of them with ``_autoremap``); ``@name`` always
means the root blackboard. bearings has one blackboard, so ``bearings import`` inlines subtrees
and resolves every name to a bearings key (with the one mapping of :mod:`missions.btcpp`) or to
the literal a ``<SubTree>`` set, through the chain of scopes here. A name that stays local to a
subtree has no bearings equivalent and is reported.
"""

from __future__ import annotations

from dataclasses import dataclass

from behaviours.ports import key_problem
from missions.btcpp import identifier_to_key

Resolved = tuple[str, str]  # ("key", bearings key) or ("text", a literal a SubTree set)


@dataclass(frozen=True)
class Scope:
    """How names inside one tree instance reach the blackboard (BT.CPP's SubTree remapping)."""

    tree: str
    remaps: dict[str, Resolved] | None = None  # None: the root blackboard
    autoremap: bool = False
    parent: Scope | None = None

    def resolve(self, name: str) -> Resolved | str:
        """What a blackboard name means here, or why it means nothing in bearings."""
        if name.startswith("@") or self.remaps is None:
            key = key_of(name)
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

    def pointed(self, port: str, pointer: str) -> Resolved | str:
        """What the pointer ``{...}`` of port ``port`` means here (``{=}`` names the entry after the port)."""
        return self.resolve(port if pointer == "=" else pointer)


def key_of(name: str) -> str | None:
    """The bearings key of an identifier (``@robot__odometry``) or a key written as it is."""
    body = name.removeprefix("@")
    if body.startswith("/"):
        return body if key_problem(body) is None else None
    return identifier_to_key(body)
