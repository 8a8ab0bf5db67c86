"""Reading a BehaviorTree.CPP file's XML with positions, so every problem can name its line.

``bearings import`` (:mod:`missions.importer`) works on these located elements. The reader is
expat, fed the bytes as UTF-8 (BT.CPP's tinyxml2 reads nothing else); a DOCTYPE is refused
before anything is read from it, so no entity is ever expanded. Text and comments are ignored:
a BT.CPP tree is all elements and attributes.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any
from xml.parsers import expat

from maps.store import Diagnostic, InputError

MODEL_TAGS = ("Action", "Condition", "Control", "Decorator")
"""Generic element tags that name their node type with an ``ID`` attribute (``<Action ID="Drive"/>``)."""


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


def node_tag(element: XmlElement) -> str:
    """The node type an element names: its tag, or its ``ID`` for the generic tags (empty when missing)."""
    return element.attrs.get("ID", "") if element.tag in MODEL_TAGS else element.tag


def walk(element: XmlElement) -> Iterable[XmlElement]:
    """The element and everything under it, depth first."""
    yield element
    for child in element.children:
        yield from walk(child)
