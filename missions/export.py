"""Views of a mission tree: a unicode outline, Graphviz dot, and BehaviorTree.CPP v4 XML.

The XML (``<root BTCPP_format="4">``) loads in BehaviorTree.CPP and opens in Groot2. Control
nodes become their BT.CPP counterparts (``Sequence``/``ReactiveSequence``, ``Fallback``/
``ReactiveFallback``, ``Precondition``, ``RunOnce``, ...) with BT.CPP's own ports; every other node
type (leaves, Nav2's ``RecoveryNode`` and ``RateController``, what BT.CPP lacks) is declared in
the ``TreeNodesModel`` with its typed ``input_port``/``output_port``s, and every node writes all
its ports. Blackboard keys are written with the one reversible mapping of :mod:`missions.btcpp`
(``{@robot__odometry}``, scripts ``@perception__observation___count >= 50``). ``bearings import``
(:mod:`missions.importer`) reads the same XML back into the same tree.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Callable

from behaviours.ports import REQUIRED, InputPort, OutputPort, Ref, format_literal, parse_ref
from behaviours.registry import NodeType, Registry
from maps.store import Diagnostic, InputError
from missions.btcpp import (
    BUILTIN_NAMES,
    SENSE_NAME,
    SENSE_SUFFIX,
    UINT32,
    blackboard_pointer,
    comparison_script,
    format_value,
    is_port_name,
    literal_problem,
    model_type,
    remap,
)
from missions.language import MissionSpec, NodeSpec

KIND_GLYPH = {"composite": "", "decorator": "", "action": "--> ", "condition": "--? "}
BTCPP_MODEL_TAG = {"action": "Action", "condition": "Condition", "decorator": "Decorator", "composite": "Control"}


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
    """BehaviorTree.CPP v4 XML with a TreeNodesModel, for BT.CPP and Groot2.

    The task tree is the main tree; the ``sense:`` nodes, if any, are a second tree
    (:data:`~missions.btcpp.SENSE_SUFFIX`). Every attribute written is a declared port: BT.CPP's
    own for its built-in nodes, the TreeNodesModel's for the others. A construct BT.CPP cannot
    express raises :class:`~maps.store.InputError` located at the node.
    """
    exporter = _BtcppExporter(mission.registry)
    task = exporter.element(mission.tree)
    sense = [exporter.element(node) for node in mission.sense]
    if exporter.problems:
        raise InputError(exporter.problems)
    main_id = _ident(mission.name)
    if main_id in BUILTIN_NAMES or main_id in exporter.models:  # BT.CPP: a tree ID is no node type's name
        main_id += "Tree"
    root = ET.Element("root", {"BTCPP_format": "4", "main_tree_to_execute": main_id})
    ET.SubElement(root, "BehaviorTree", {"ID": main_id}).append(task)
    if sense:
        tree = ET.SubElement(root, "BehaviorTree", {"ID": main_id + SENSE_SUFFIX})
        ET.SubElement(tree, "Sequence", {"name": SENSE_NAME}).extend(sense)
    model = ET.SubElement(root, "TreeNodesModel")
    for tag, node_type in sorted(exporter.models.items()):
        element = ET.SubElement(model, BTCPP_MODEL_TAG[node_type.kind], {"ID": tag})
        ports: list[InputPort | OutputPort] = [*node_type.inputs, *node_type.outputs]
        for port in ports:
            _model_port(element, port)
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def _model_port(element: ET.Element, port: InputPort | OutputPort) -> None:
    """One ``input_port``/``output_port`` of a node type in the TreeNodesModel."""
    attrs = {"name": port.name, "type": model_type(port.type)}
    if isinstance(port, OutputPort):
        attrs["default"] = remap(port.key)
    elif port.default is not REQUIRED and port.default is not None:
        default = parse_ref(port.default) or port.default
        attrs["default"] = format_value(default)
    tag = "output_port" if isinstance(port, OutputPort) else "input_port"
    ET.SubElement(element, tag, attrs).text = port.doc + (f" [{port.unit}]" if port.unit else "")


Attributes = dict[str, str]
Translation = tuple[str, Attributes] | str  # (BT.CPP tag, its attributes), or why there is none


def _memory(tag: str) -> Callable[[NodeSpec], Translation]:
    def translate(node: NodeSpec) -> Translation:
        return (tag if node.inputs["memory"] else "Reactive" + tag), {}
    return translate


def _parallel(node: NodeSpec) -> Translation:
    if not node.inputs["synchronise"]:
        return ("Parallel with synchronise: false has no BehaviorTree.CPP equivalent (BT.CPP's Parallel never "
                "ticks a child again once it succeeded)")
    success = -1 if node.inputs["policy"] == "all" else 1
    return "Parallel", {"success_count": str(success), "failure_count": "1"}


def _timeout(node: NodeSpec) -> Translation:
    duration = node.inputs["duration"]
    msec = round(duration * 1000) if math.isfinite(duration) else -1
    if msec / 1000 != duration:
        return f"Timeout.duration {duration!r} s is not a whole number of milliseconds (BT.CPP's Timeout takes msec)"
    problem = literal_problem(msec, UINT32)
    return f"Timeout.duration: {problem}" if problem else ("Timeout", {"msec": str(msec)})


def _one_shot(node: NodeSpec) -> Translation:
    if node.inputs["policy"] == "on_completion":
        return "RunOnce", {"then_skip": "false"}
    return "OneShot", {"policy": "on_success"}  # BT.CPP lacks it: declared in the TreeNodesModel


def _scripted(tag: str, script_port: str, others: Attributes) -> Callable[[NodeSpec], Translation]:
    """A comparison ``key op value`` as BT.CPP's script node ``tag`` (Guard: ``Precondition if``,
    CheckBlackboard: ``ScriptCondition code``), with its ``others`` ports."""
    def translate(node: NodeSpec) -> Translation:
        script = comparison_script(node.inputs["key"], node.inputs["op"], node.inputs["value"])
        if script is None:
            return f"{node.type}.value {node.inputs['value']!r} cannot be written in a BehaviorTree.CPP script"
        return tag, {script_port: script, **others}
    return translate


TRANSLATIONS: dict[str, Callable[[NodeSpec], Translation]] = {
    "Sequence": _memory("Sequence"), "Selector": _memory("Fallback"), "Parallel": _parallel, "Timeout": _timeout,
    "OneShot": _one_shot, "Guard": _scripted("Precondition", "if", {"else": "FAILURE"}),
    "CheckBlackboard": _scripted("ScriptCondition", "code", {}),
}  # fmt: skip
"""bearings' control nodes whose ports differ from their BT.CPP counterpart's."""

SAME_PORTS = frozenset({"Retry", "Repeat", "Inverter", "ForceSuccess", "ForceFailure", "Success", "Failure"})
"""bearings' node types that are a BT.CPP built-in with the same ports, under their ``BTCPP`` name."""


class _BtcppExporter:
    """Turns NodeSpecs into BT.CPP elements, collecting the node types the TreeNodesModel declares."""

    def __init__(self, registry: Registry) -> None:
        self.registry = registry
        self.models: dict[str, NodeType] = {}
        self.problems: list[Diagnostic] = []

    def problem(self, node: NodeSpec, message: str) -> None:
        where = node.location
        self.problems.append(Diagnostic(where.file, where.line, where.col, message))

    def element(self, node: NodeSpec) -> ET.Element:
        node_type = self.registry.lookup(node.type)
        if node_type is None:
            raise ValueError(f"unknown node type {node.type!r}")
        tag, attrs = self._translate(node, node_type)
        if node.name != node.type:
            attrs = {"name": node.name, **attrs}
        element = ET.Element(tag, attrs)
        element.extend(self.element(child) for child in node.children)
        return element

    def _translate(self, node: NodeSpec, node_type: NodeType) -> tuple[str, Attributes]:
        translate = TRANSLATIONS.get(node.type)
        translated = translate(node) if translate else (node_type.btcpp, self._ports(node, node_type))
        if isinstance(translated, str):
            self.problem(node, translated)
            return node_type.btcpp, {}
        tag, attrs = translated
        if tag in BUILTIN_NAMES:
            if translate is None and node.type not in SAME_PORTS:
                self.problem(node, f"{node.type} is exported as <{tag}>, the name of a BehaviorTree.CPP built-in "
                             "node: give it another BTCPP name")
        else:
            self.models[tag] = node_type
        return tag, attrs

    def _ports(self, node: NodeSpec, node_type: NodeType) -> Attributes:
        """Every port of a node as BT.CPP reads it (inputs as literals or ``{@key}``, outputs as ``{@key}``)."""
        attrs: Attributes = {}
        for name, value in node.inputs.items():
            if value is None:
                continue
            text = format_value(value)
            problem = None if isinstance(value, Ref) else literal_problem(value)
            if problem:
                self.problem(node, f"{node.type}.{name}: {problem}")
            elif not isinstance(value, Ref) and blackboard_pointer(text) is not None:
                self.problem(node, f"{node.type}.{name}: the text {text!r} would be a blackboard reference in "
                             "BehaviorTree.CPP")
            attrs[name] = text
        attrs.update({name: remap(key) for name, key in node.outputs.items()})
        for name in attrs:
            if not is_port_name(name):
                self.problem(node, f"{node.type}.{name}: BehaviorTree.CPP takes only port names that start with a "
                             "letter")
        return attrs


def _ident(text: str) -> str:
    return "".join(c if c.isalnum() or c == "_" else "_" for c in text) or "MainTree"


def _esc(text: str) -> str:
    return text.replace("\\", "\\\\").replace('"', '\\"')
