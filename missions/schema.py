"""A JSON Schema (draft 2020-12) of the mission language, generated from the registry.

Editors use it to complete and check mission files (e.g. the YAML language server:
``# yaml-language-server: $schema=bearings-mission.schema.json``). It lists every registered
node type with its parameters, their types, units, defaults and descriptions.
"""

from __future__ import annotations

from typing import Any

from behaviours.ports import REF_PATTERN, TYPES, Param
from behaviours.registry import NodeType, all_types
from missions.export import format_value

SCHEMA_ID = "https://bearings.invalid/schemas/mission.schema.json"
INPUT_PATTERN = r"^\s*\$\{[A-Za-z_]\w*\}\s*$"
JSON_TYPE = {
    "float": {"type": "number"},
    "int": {"type": "integer"},
    "bool": {"type": "boolean"},
    "str": {"type": "string"},
    "key": {"type": "string", "pattern": r"^/[A-Za-z_][\w/]*(\.[A-Za-z_]\w*)*$"},
    "list[float]": {"type": "array", "items": {"type": "number"}},
    "any": {},
}


def _param_schema(param: Param) -> dict[str, Any]:
    literal = dict(JSON_TYPE[param.type])
    if param.choices:
        literal["enum"] = list(param.choices)
    if param.minimum is not None:
        literal["minimum"] = param.minimum
    if param.maximum is not None:
        literal["maximum"] = param.maximum
    options = [literal, {"type": "string", "pattern": INPUT_PATTERN, "description": "a mission input"}]
    if param.refs:
        options.append({"type": "string", "pattern": REF_PATTERN.pattern, "description": "a blackboard key"})
    unit = f" [{param.unit}]" if param.unit else ""
    schema: dict[str, Any] = {"description": f"{param.doc}{unit}".strip(), "anyOf": options}
    if not param.required:
        schema["default"] = param.default if not isinstance(param.default, float) else float(
            format_value(param.default))
    return schema


def _type_schema(node_type: NodeType) -> dict[str, Any]:
    properties: dict[str, Any] = {"name": {"type": "string", "description": "a name for logs and views"}}
    required: list[str] = []
    for param in node_type.params:
        properties[param.name] = _param_schema(param)
        if param.required:
            required.append(param.name)
    if node_type.kind == "composite":
        children: dict[str, Any] = {"type": "array", "items": {"$ref": "#/$defs/node"},
                                    "minItems": node_type.min_children}
        if node_type.max_children is not None:
            children["maxItems"] = node_type.max_children
        properties["children"] = children
        required.append("children")
    elif node_type.kind == "decorator":
        properties["child"] = {"$ref": "#/$defs/node"}
        required.append("child")
    body: dict[str, Any] = {"type": "object", "properties": properties, "additionalProperties": False}
    if required:
        body["required"] = required
    else:
        body = {"anyOf": [body, {"type": "null"}]}
    return {
        "type": "object",
        "description": f"{node_type.kind}: {node_type.doc}",
        "properties": {node_type.name: body},
        "required": [node_type.name],
        "additionalProperties": False,
    }


def mission_schema() -> dict[str, Any]:
    """The schema as a JSON-serialisable dict."""
    types = all_types()
    defs: dict[str, Any] = {f"type_{t.name}": _type_schema(t) for t in types}
    bare = sorted(t.name for t in types if t.kind in ("action", "condition") and not any(
        p.required for p in t.params))
    defs["include"] = {
        "type": "object",
        "description": "another mission file as a subtree, with its own inputs",
        "properties": {
            "include": {"type": "string", "description": "file, relative to this one or on the search path"},
            "inputs": {"type": "object", "description": "values for the included mission's inputs"},
            "name": {"type": "string"},
        },
        "required": ["include"],
        "additionalProperties": False,
    }
    defs["node"] = {
        "anyOf": [{"$ref": "#/$defs/include"}, {"type": "string", "enum": bare},
                  *({"$ref": f"#/$defs/type_{t.name}"} for t in types)],
    }
    point = {"type": "array", "items": {"type": ["number", "string"]}, "minItems": 2, "maxItems": 2}
    defs["input"] = {
        "anyOf": [
            {"type": "object", "additionalProperties": False, "properties": {
                "type": {"enum": list(TYPES)}, "default": {}, "unit": {"type": "string"},
                "description": {"type": "string"}}},
            {"type": ["number", "string", "boolean", "array"], "description": "the default value"},
        ]
    }
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": SCHEMA_ID,
        "title": "bearings mission",
        "type": "object",
        "properties": {
            "mission": {"type": "string", "description": "the mission's name"},
            "description": {"type": "string"},
            "version": {"type": "integer"},
            "inputs": {"type": "object", "additionalProperties": {"$ref": "#/$defs/input"},
                       "description": "values substituted as ${name}; override with --set name=value"},
            "plugins": {"type": "array", "items": {"type": "string"},
                        "description": "Python modules (or .py files next to the mission) that register behaviours"},
            "rate": {"type": "number", "minimum": 0.1, "maximum": 1000, "description": "tick rate [Hz]"},
            "max_time": {"type": "number", "minimum": 0, "description": "time limit [s]; FAILURE after it"},
            "cameras": {"type": "array", "items": {"type": "string"},
                        "description": "the cameras the mission grabs (default: every camera of the robot)"},
            "sense": {"type": "array", "items": {"$ref": "#/$defs/node"},
                      "description": "nodes added to the data-gathering branch"},
            "tree": {"$ref": "#/$defs/node"},
            "evaluation": {"type": "object", "additionalProperties": False, "properties": {
                "goal": point, "frame": {"enum": ["world", "start"]},
                "reference_path": {"type": "array", "items": point, "minItems": 2}},
                "description": "ground-truth references for simulation reports (world frame)"},
        },
        "required": ["tree"],
        "additionalProperties": False,
        "$defs": defs,
    }
