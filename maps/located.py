"""Declared file models checked against located YAML: every problem as ``file:line:col: message``.

Worlds, robot profiles, map-file headers and the top level of missions are declared once as
pydantic models (every quantity with its unit, range and description); this module is the one
layer that validates located data (:mod:`maps.store`) against such a model and turns pydantic's
error paths into :class:`~maps.store.Diagnostic` values with the line and column of the
offending key or value, a "did you mean" for unknown keys, and the field's unit. The mission
loader uses :func:`suggest` and :func:`describe_value` for its own node checks, so every input
file speaks with one voice.

Why pydantic: the model *is* the typed value, its ``model_json_schema()`` is the JSON Schema
editors use (``bearings schema --world``), and its errors carry paths we can locate. Models are
validated in strict mode (no text-to-number coercion: ``height: "2"`` is an error, as in
missions) with non-finite floats refused.
"""

from __future__ import annotations

import difflib
import types
import typing
from collections.abc import Iterable
from typing import Any, TypeVar, Union

from pydantic import BaseModel, ConfigDict, ValidationError
from pydantic.fields import FieldInfo

from maps.store import Diagnostic, InputError, Mark, YamlList, YamlMap, mark_of

M = TypeVar("M", bound=BaseModel)

FILE_MODEL_CONFIG = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True)
"""The configuration every declared file model uses (unknown keys are errors, no coercion)."""


def closest(word: Any, options: Iterable[Any]) -> str | None:
    """The option most like ``word`` (a likely typo of it), or None."""
    close = difflib.get_close_matches(str(word), [str(o) for o in options], n=1, cutoff=0.6)
    return close[0] if close else None


def suggest(word: Any, options: Iterable[Any]) -> str:
    """``"; did you mean 'x'?"`` for the closest option, or an empty string."""
    match = closest(word, options)
    return f"; did you mean {match!r}?" if match else ""


def describe_value(value: Any) -> str:
    """A value as error messages name it: 'a mapping', 'a list of 3', 'nothing (null)' or its repr
    (shortened: a message stays one readable line whatever the file holds)."""
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    if value is None:
        return "nothing (null)"
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:45]}... ({len(text)} characters)"


def validate(model: type[M], data: Any, *, file: str, path: tuple[Any, ...] = (),
             context: dict[str, Any] | None = None) -> M:
    """``model`` from located data; :class:`InputError` with every problem located in ``file``.

    ``path`` is where ``data`` sits in the file (``("inputs", "side")``), for the messages.
    """
    try:
        return model.model_validate(data, context=context)
    except ValidationError as exc:
        raise InputError(diagnose(exc, data, file=file, model=model, path=path)) from None


def diagnose(exc: ValidationError, data: Any, *, file: str, model: type[BaseModel] | None = None,
             path: tuple[Any, ...] = ()) -> list[Diagnostic]:
    """The located diagnostics of a pydantic error raised on ``data`` (found at ``path`` in the file)."""
    out = []
    for error in exc.errors(include_url=False):
        mark, steps = _locate(data, error["loc"], key_mark=error["type"] == "extra_forbidden")
        field, allowed, annotation = _field(model, error["loc"])
        out.append(Diagnostic(file, mark.line, mark.col,
                              _message(error, [*path, *steps], field, allowed, _unit(field, annotation))))
    return sorted(set(out), key=lambda d: (d.line, d.col, d.message))


# -- where -----------------------------------------------------------------------------------------
def _locate(data: Any, loc: tuple[Any, ...], *, key_mark: bool) -> tuple[Mark, list[Any]]:
    """The mark of the value (or, for unknown keys, of the key) at ``loc``, and the data path to it.

    Elements of ``loc`` that are not in the data (pydantic's union tags) are skipped.
    """
    located = isinstance(data, (YamlMap, YamlList))
    node, mark, path = data, mark_of(data, Mark(1, 1) if located else Mark(0, 0)), []
    for index, step in enumerate(loc):
        last = index == len(loc) - 1
        if isinstance(node, YamlMap) and step in node:
            mark = node.mark_of(step) if (last and key_mark) else node.value_mark_of(step)
            node = node[step]
        elif isinstance(node, YamlList) and isinstance(step, int) and 0 <= step < len(node):
            mark, node = node.mark_of(step), node[step]
        elif isinstance(node, dict) and step in node:  # plain data (command-line values): no marks
            node = node[step]
        elif isinstance(node, (dict, list)) or isinstance(step, int):
            continue  # a union tag, or a missing key: stay at the container
        else:
            break
        path.append(step)
    return mark, path


def _where(path: list[Any]) -> str:
    text = ""
    for step in path:
        text += f"[{step}]" if isinstance(step, int) else (f".{step}" if text else str(step))
    return text


# -- what ------------------------------------------------------------------------------------------
def _message(error: Any, path: list[Any], field: FieldInfo | None, allowed: list[str], unit: str) -> str:
    kind, loc, ctx = error["type"], error["loc"], error.get("ctx", {})
    where, given = _where(path), error.get("input")
    if kind == "extra_forbidden":
        key = loc[-1]
        inside = f" in {_where(path[:-1])}" if len(path) > 1 else ""
        listed = f" (allowed: {', '.join(allowed)})" if allowed else ""
        return f"unknown key {key!r}{inside}{suggest(key, allowed)}{listed}"
    if kind == "missing":
        about = f" ({field.description})" if field is not None and field.description else ""
        return f"{_where(path) or 'the file'} needs {loc[-1]!r}{about}"
    bound = _BOUNDS.get(kind)
    if bound is not None:
        return f"{where} must be {bound} {_num(ctx[_CTX[kind]])}{unit}, got {describe_value(given)}"
    if kind in ("too_short", "too_long"):
        size = ctx.get("min_length") if kind == "too_short" else ctx.get("max_length")
        return f"{where} must have {'at least' if kind == 'too_short' else 'at most'} {size} items, got " \
               f"{ctx.get('actual_length')}"
    if kind in ("float_type", "int_type", "int_from_float", "finite_number", "float_parsing", "int_parsing"):
        wanted = "a whole number" if kind.startswith("int") else "a finite number"
        return f"{where} expects {wanted}{' in ' + unit.strip() if unit else ''}, got {describe_value(given)}"
    if kind in ("literal_error", "enum"):
        return f"{where} must be one of {ctx.get('expected')}, got {describe_value(given)}"
    if kind == "union_tag_invalid":
        return f"{where}: unknown {ctx.get('discriminator', 'kind')} {ctx.get('tag')!r} (known: " \
               f"{ctx.get('expected_tags')})"
    if kind == "value_error":
        return f"{where}: {error['msg'].removeprefix('Value error, ')}" if where else \
            error["msg"].removeprefix("Value error, ")
    return f"{where}: {_lower(error['msg'])}, got {describe_value(given)}" if where else _lower(error["msg"])


_BOUNDS = {"greater_than_equal": ">=", "greater_than": ">", "less_than_equal": "<=", "less_than": "<"}
_CTX = {"greater_than_equal": "ge", "greater_than": "gt", "less_than_equal": "le", "less_than": "lt"}


def _num(value: Any) -> str:
    return f"{value:g}" if isinstance(value, (int, float)) else str(value)


def _lower(text: str) -> str:
    return text[:1].lower() + text[1:]


def _unit(field: FieldInfo | None, annotation: Any) -> str:
    """The declared unit of the value: on the field, or on the annotated type it holds."""
    infos = [field] if field is not None else []
    pending = [annotation]
    while pending:
        tp = pending.pop()
        if typing.get_origin(tp) is typing.Annotated:
            infos += [m for m in typing.get_args(tp)[1:] if isinstance(m, FieldInfo)]
            pending.append(typing.get_args(tp)[0])
        elif typing.get_origin(tp) in (Union, types.UnionType):
            pending += list(typing.get_args(tp))
    for info in infos:
        extra = info.json_schema_extra
        if isinstance(extra, dict) and extra.get("unit"):
            return f" {extra['unit']}"
    return ""


# -- the declaration at a path ---------------------------------------------------------------------
def _field(model: type[BaseModel] | None, loc: tuple[Any, ...]) -> tuple[FieldInfo | None, list[str], Any]:
    """The field declared at ``loc``, the field names of the model that holds it, and the type at ``loc``."""
    current: Any = model
    field: FieldInfo | None = None
    allowed: list[str] = []
    for step in loc:
        models = _models_in(current)
        if isinstance(step, int) or not models:
            current = _item_type(current)
            field = None if isinstance(step, int) else field  # an item of a list has its own declaration
            continue
        holder = next((m for m in models if _named(m, step) is not None), None)
        if holder is None:
            tagged = [m for m in models if _tag_of(m) == step]
            current = tagged[0] if tagged else current
            allowed = sorted(models[0].model_fields) if not tagged else allowed
            continue
        allowed = sorted(holder.model_fields)
        field = _named(holder, step)
        current = field.annotation if field is not None else None
    return field, allowed, current


def _named(model: type[BaseModel], step: Any) -> FieldInfo | None:
    """A model's field by its name or its alias (command-line options are aliases: ``--rate``)."""
    if step in model.model_fields:
        return model.model_fields[step]
    return next((f for f in model.model_fields.values() if f.alias == step), None)


def _models_in(tp: Any) -> list[type[BaseModel]]:
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return [tp]
    if typing.get_origin(tp) in (Union, types.UnionType, typing.Annotated):
        return [m for arg in typing.get_args(tp) for m in _models_in(arg)]
    return []


def _item_type(tp: Any) -> Any:
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin is typing.Annotated:
        return _item_type(args[0])
    if origin in (Union, types.UnionType):
        inner = [a for a in args if a is not type(None)]
        return _item_type(inner[0]) if len(inner) == 1 else tp
    if origin in (list, tuple) and args:
        return args[0]
    if origin is None and isinstance(tp, type) and issubclass(tp, (list, dict)):
        return Any
    if origin is dict and len(args) == 2:
        return args[1]
    return tp


def _tag_of(model: type[BaseModel]) -> Any:
    for name in ("kind", "driver"):
        field = model.model_fields.get(name)
        if field is not None and typing.get_origin(field.annotation) is typing.Literal:
            return typing.get_args(field.annotation)[0]
    return None
