"""JSON Schemas (draft 2020-12) of the files users write, generated from their declarations.

Editors use them to complete and check files (e.g. the YAML language server:
``# yaml-language-server: $schema=bearings-mission.schema.json``). The mission schema takes its
top-level entries from :class:`missions.model.MissionFile` and lists every node type of a
registry with its ports: types, units, defaults and descriptions. Worlds and robot profiles
come straight from their pydantic models.
"""

from __future__ import annotations

from typing import Any

from behaviours.ports import REF_PATTERN, TYPE_NAMES, InputPort, Key, OutputPort, type_name
from behaviours.registry import NodeType, Registry
from missions.model import Evaluation, MissionFile

SCHEMA_ID = "https://bearings.invalid/schemas/mission.schema.json"
INPUT_PATTERN = r"^\s*\$\{[A-Za-z_]\w*\}\s*$"
KEY_SCHEMA = {"type": "string", "pattern": r"^/[A-Za-z_][\w/]*(\.[A-Za-z_]\w*)*$"}
JSON_TYPE: dict[Any, dict[str, Any]] = {
    float: {"type": "number"},
    int: {"type": "integer"},
    bool: {"type": "boolean"},
    str: {"type": "string"},
    Key: KEY_SCHEMA,
    list[float]: {"type": "array", "items": {"type": "number"}},
}
REF_SCHEMA = {"type": "string", "pattern": REF_PATTERN.pattern, "description": "a blackboard key {/ns/key}"}


def _input_schema(port: InputPort) -> dict[str, Any]:
    literal = dict(JSON_TYPE.get(port.type, {}))
    if port.choices:
        literal["enum"] = list(port.choices)
    if port.minimum is not None:
        literal["minimum"] = port.minimum
    if port.maximum is not None:
        literal["maximum"] = port.maximum
    options = [{"type": "string", "pattern": INPUT_PATTERN, "description": "a mission input"}]
    if port.type in JSON_TYPE or not literal:
        options.insert(0, literal)
    if not port.literal_only:
        options.append(REF_SCHEMA)
    unit = f" [{port.unit}]" if port.unit else ""
    schema: dict[str, Any] = {"description": f"{type_name(port.type)}{unit}: {port.doc}".strip(), "anyOf": options}
    if not port.required and isinstance(port.default, (bool, int, float, str, list)):
        schema["default"] = port.default
    return schema


def _output_schema(port: OutputPort) -> dict[str, Any]:
    return {**REF_SCHEMA, "description": f"output {type_name(port.type)}: {port.doc} (default {{{port.key}}})",
            "default": "{" + port.key + "}"}


def _type_schema(node_type: NodeType) -> dict[str, Any]:
    properties: dict[str, Any] = {"name": {"type": "string", "description": "a name for logs and views"}}
    required: list[str] = []
    for port in node_type.inputs:
        properties[port.name] = _input_schema(port)
        if port.required:
            required.append(port.name)
    for out in node_type.outputs:
        properties[out.name] = _output_schema(out)
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


def mission_schema(registry: Registry | None = None) -> dict[str, Any]:
    """The mission schema for the node types of ``registry`` (default: built-ins and entry points)."""
    types = (registry or Registry.default()).all_types()
    defs: dict[str, Any] = {f"type_{t.name}": _type_schema(t) for t in types}
    bare = sorted(t.name for t in types if t.kind in ("action", "condition") and not any(
        p.required for p in t.inputs))
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
    declaration = {"type": "object", "additionalProperties": False, "properties": {
        "type": {"enum": list(TYPE_NAMES)}, "default": {}, "unit": {"type": "string"},
        "description": {"type": "string"}}}
    defs["input"] = {"anyOf": [declaration, {"type": ["number", "string", "boolean", "array"],
                                             "description": "the default value"}]}
    schema = MissionFile.model_json_schema()
    properties = schema["properties"]
    properties["tree"] = {"$ref": "#/$defs/node", "description": properties["tree"].get("description", "")}
    properties["sense"]["items"] = {"$ref": "#/$defs/node"}
    properties["inputs"]["additionalProperties"] = {"$ref": "#/$defs/input"}
    evaluation = _numbers_or_inputs(Evaluation.model_json_schema())
    evaluation.pop("title", None)
    properties["evaluation"] = evaluation
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": SCHEMA_ID,
        **{k: v for k, v in schema.items() if k != "title"},
        "title": "bearings mission",
        "$defs": {**schema.get("$defs", {}), **defs},
    }


def _numbers_or_inputs(schema: Any) -> Any:
    """The schema with every plain number also accepting a ``${input}`` (substituted at load time)."""
    if isinstance(schema, list):
        return [_numbers_or_inputs(item) for item in schema]
    if not isinstance(schema, dict):
        return schema
    if schema.get("type") == "number":
        return {"anyOf": [schema, {"type": "string", "pattern": INPUT_PATTERN}]}
    return {key: _numbers_or_inputs(value) for key, value in schema.items()}
