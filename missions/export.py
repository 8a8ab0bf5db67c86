"""Views of a mission tree: a unicode outline, Graphviz dot, and BehaviorTree.CPP v4 XML.

The XML (``<root BTCPP_format="4">``) carries a ``TreeNodesModel`` with every bearings node
type's typed ``input_port`` and ``output_port`` declarations, so Groot2 can open and display the
tree; every node writes all its ports, outputs as the ``{/ns/key}`` they write. Composites map
onto their BT.CPP counterparts (``Sequence``/``ReactiveSequence``, ``Fallback``/
``ReactiveFallback``, ...).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

from behaviours.ports import REQUIRED, InputPort, OutputPort, Ref, format_literal, type_name
from behaviours.registry import NodeType, Registry
from missions.language import MissionSpec, NodeSpec

KIND_GLYPH = {"composite": "", "decorator": "", "action": "--> ", "condition": "--? "}
BTCPP_MODEL_TAG = {"action": "Action", "condition": "Condition", "decorator": "Decorator", "composite": "Control"}


BTCPP_TYPE = {"float": "double", "int": "int", "bool": "bool", "str": "std::string", "key": "std::string"}


def _label(node: NodeSpec, registry: Registry) -> str:
    node_type = registry.lookup(node.type)
    shown = {k: v for k, v in node.inputs.items() if v is not None and (not isinstance(v, Ref) or k in node.locations)}
    shown.update({k: Ref(v) for k, v in node.outputs.items() if k in node.locations})  # remapped outputs
    params = ", ".join(f"{k}={format_literal(v)}" for k, v in shown.items())
    title = node.type if node.name == node.type else f"{node.name} ({node.type})"
    suffix = f"  [{params}]" if params else ""
    origin = f"  <- {node.included_from}" if node.included_from else ""
    glyph = KIND_GLYPH.get(node_type.kind if node_type else "action", "")
    return f"{glyph}{title}{suffix}{origin}"


def unicode_tree(mission: MissionSpec) -> str:
    """An indented outline with box-drawing characters, parameters and include origins."""
    lines = [f"{mission.name}: {mission.file}"]
    if mission.sense:
        lines.append("├── sense (added to the data-gathering branch)")
        for i, node in enumerate(mission.sense):
            _outline(node, "│   ", i == len(mission.sense) - 1, lines, mission.registry)
    _outline(mission.tree, "", True, lines, mission.registry)
    return "\n".join(lines) + "\n"


def _outline(node: NodeSpec, prefix: str, last: bool, lines: list[str], registry: Registry) -> None:
    lines.append(f"{prefix}{'└── ' if last else '├── '}{_label(node, registry)}")
    inner = prefix + ("    " if last else "│   ")
    for i, child in enumerate(node.children):
        _outline(child, inner, i == len(node.children) - 1, lines, registry)


def dot_tree(mission: MissionSpec) -> str:
    """Graphviz dot text (render with ``dot -Tsvg``)."""
    out = [f'digraph "{_esc(mission.name)}" {{', "  graph [fontname=\"sans\"];",
           "  node [fontname=\"sans\", fontsize=11];"]
    shapes = {"composite": "box", "decorator": "ellipse", "action": "box", "condition": "ellipse"}
    colours = {"composite": "#c6d9f1", "decorator": "#e8d8f0", "action": "#d9f1c6", "condition": "#f9f0c0"}
    counter = 0

    def visit(node: NodeSpec) -> str:
        nonlocal counter
        counter += 1
        ident = f"n{counter}"
        node_type = mission.registry.lookup(node.type)
        kind = node_type.kind if node_type else "action"
        label = _label(node, mission.registry).removeprefix(KIND_GLYPH.get(kind, ""))
        out.append(f'  {ident} [label="{_esc(label)}", shape={shapes[kind]}, style=filled, '
                   f'fillcolor="{colours[kind]}"];')
        for child in node.children:
            out.append(f"  {ident} -> {visit(child)};")
        return ident

    visit(mission.tree)
    out.append("}")
    return "\n".join(out) + "\n"


def btcpp_xml(mission: MissionSpec) -> str:
    """BehaviorTree.CPP v4 XML with a TreeNodesModel, for Groot2."""
    root = ET.Element("root", {"BTCPP_format": "4", "main_tree_to_execute": _ident(mission.name)})
    tree = ET.SubElement(root, "BehaviorTree", {"ID": _ident(mission.name)})
    used: dict[str, NodeType] = {}
    tree.append(_xml_node(mission.tree, used, mission.registry))
    model = ET.SubElement(root, "TreeNodesModel")
    for tag, node_type in sorted(used.items()):
        if tag in BTCPP_BUILTIN:
            continue
        element = ET.SubElement(model, BTCPP_MODEL_TAG[node_type.kind], {"ID": tag})
        ports: list[InputPort | OutputPort] = [*node_type.inputs, *node_type.outputs]
        for port in ports:
            _model_port(element, port)
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


BTCPP_BUILTIN = {"Sequence", "ReactiveSequence", "Fallback", "ReactiveFallback", "Parallel", "Inverter",
                 "ForceSuccess", "ForceFailure", "RetryUntilSuccessful", "Repeat", "Timeout", "RunOnce",
                 "AlwaysSuccess", "AlwaysFailure", "Precondition"}


def _model_port(element: ET.Element, port: InputPort | OutputPort) -> None:
    """One ``input_port``/``output_port`` of a node type in the TreeNodesModel."""
    name = type_name(port.type)
    attrs = {"name": port.name, "type": BTCPP_TYPE.get(name, name)}
    if isinstance(port, OutputPort):
        attrs["default"] = "{" + port.key + "}"
    elif port.default is not REQUIRED and port.default is not None:
        attrs["default"] = format_literal(port.default)
    tag = "output_port" if isinstance(port, OutputPort) else "input_port"
    ET.SubElement(element, tag, attrs).text = port.doc + (f" [{port.unit}]" if port.unit else "")


def _reactive(node: NodeSpec, params: dict[str, Any], tag: str) -> tuple[str, dict[str, str]]:
    return (tag if params.pop("memory", True) else "Reactive" + tag), {}


def _timeout(node: NodeSpec, params: dict[str, Any], tag: str) -> tuple[str, dict[str, str]]:
    return tag, {"msec": str(round(params.pop("duration") * 1000))}


def _parallel(node: NodeSpec, params: dict[str, Any], tag: str) -> tuple[str, dict[str, str]]:
    policy, _ = params.pop("policy"), params.pop("synchronise")
    count = len(node.children) if policy == "all" else 1
    return tag, {"success_count": str(count), "failure_count": "1"}


def _run_once(node: NodeSpec, params: dict[str, Any], tag: str) -> tuple[str, dict[str, str]]:
    params.pop("policy")
    return tag, {"then_skip": "true"}


def _precondition(node: NodeSpec, params: dict[str, Any], tag: str) -> tuple[str, dict[str, str]]:
    key, op, value = params.pop("key"), params.pop("op"), params.pop("value")
    return tag, {"if": f"{{{key}}} {op} {format_literal(value)}", "else": "FAILURE"}


# Where a bearings control node's ports differ from its BT.CPP counterpart's attributes.
_TRANSLATE = {"Sequence": _reactive, "Selector": _reactive, "Timeout": _timeout, "Parallel": _parallel,
              "OneShot": _run_once, "Guard": _precondition}


def _xml_node(node: NodeSpec, used: dict[str, NodeType], registry: Registry) -> ET.Element:
    node_type = registry.lookup(node.type)
    if node_type is None:
        raise ValueError(f"unknown node type {node.type!r}")
    params: dict[str, Any] = dict(node.inputs)
    translate = _TRANSLATE.get(node.type)
    tag, attrs = translate(node, params, node_type.btcpp) if translate else (node_type.btcpp, {})
    for key, value in params.items():
        if value is not None:
            attrs[key] = format_literal(value)
    for key, target in node.outputs.items():
        attrs[key] = "{" + target + "}"
    if node.name != node.type:
        attrs = {"name": node.name, **attrs}
    used[tag] = node_type
    element = ET.Element(tag, attrs)
    for child in node.children:
        element.append(_xml_node(child, used, registry))
    return element


def _ident(text: str) -> str:
    return "".join(c if c.isalnum() or c == "_" else "_" for c in text) or "MainTree"


def _esc(text: str) -> str:
    return text.replace("\\", "\\\\").replace('"', '\\"')
