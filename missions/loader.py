"""Load a mission file: parse safely, import its plugins, substitute inputs, resolve includes,
and validate every node against the registry, reporting all problems of all files in one pass.

Everything is checked here, before anything ticks: unknown node types, unknown, missing or
mistyped parameters, references to unknown blackboard keys, unknown inputs, include cycles,
malformed YAML, empty files and non-UTF-8 bytes. Problems are :class:`~maps.store.Diagnostic`
values raised together in one :class:`~maps.store.InputError`.
"""

from __future__ import annotations

import contextlib
import difflib
import importlib
import importlib.util
import os
import re
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

import behaviours  # noqa: F401  (registers the built-in node types)
from behaviours.keys import key_spec
from behaviours.ports import REQUIRED, TYPES, Param, check_ref, check_value, describe_value, parse_ref
from behaviours.registry import NodeType, all_types, lookup
from maps.store import Diagnostic, InputError, Mark, YamlList, YamlMap, load_yaml, mark_of
from missions.language import Location, MissionSpec, NodeSpec

LIBRARY = Path(__file__).parent / "library"
PATH_ENV = "BEARINGS_PATH"
MAX_DEPTH = 100
TOP_KEYS = ("mission", "description", "version", "inputs", "plugins", "rate", "max_time", "cameras", "sense",
            "tree", "evaluation")
INCLUDE_KEYS = ("include", "inputs", "name")
STRUCTURE_KEYS = ("name", "children", "child")
INPUT_KEYS = ("type", "default", "unit", "description")
SUBST = re.compile(r"\$\{([^}]*)\}")
IDENT = re.compile(r"^[A-Za-z_]\w*$")
MODULE = re.compile(r"^[A-Za-z_]\w*(\.[A-Za-z_]\w*)*$")


@dataclass
class _Scope:
    """What nodes of one file see: its file name, its input values and where it sits."""

    file: str
    values: dict[str, Any]
    in_sense: bool = False
    chain: tuple[Path, ...] = ()


@dataclass
class _Loader:
    search_path: list[Path]
    diagnostics: list[Diagnostic] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    plugins: list[str] = field(default_factory=list)

    # -- reporting ---------------------------------------------------------------------------
    def error(self, file: str, mark: Mark, message: str) -> None:
        self.diagnostics.append(Diagnostic(file, mark.line, mark.col, message))

    # -- documents ---------------------------------------------------------------------------
    def document(self, path: Path) -> YamlMap | None:
        """A mission file's top-level mapping, or None (with diagnostics) when unusable."""
        try:
            doc = load_yaml(path)
        except InputError as exc:
            self.diagnostics.extend(exc.diagnostics)
            return None
        self.files.append(str(path))
        if not isinstance(doc, YamlMap):
            self.error(str(path), mark_of(doc, Mark(1, 1)),
                       "a mission file is a mapping with at least a 'tree:' entry")
            return None
        for key in doc:
            if key not in TOP_KEYS:
                self.error(str(path), doc.mark_of(key), f"unknown mission entry {key!r}{_suggest(key, TOP_KEYS)}")
        return doc

    def inputs(self, doc: YamlMap, file: str) -> dict[str, Param]:
        """The declared inputs: ``name: default`` or ``name: {type, default, unit, description}``."""
        raw = doc.get("inputs")
        if raw is None:
            return {}
        if not isinstance(raw, YamlMap):
            self.error(file, doc.value_mark_of("inputs"), "'inputs:' is a mapping of input names")
            return {}
        declared: dict[str, Param] = {}
        for name, spec in raw.items():
            mark = raw.mark_of(name)
            if not isinstance(name, str) or not IDENT.match(name):
                self.error(file, mark, f"input name {name!r} must be an identifier (letters, digits, _)")
                continue
            if isinstance(spec, YamlMap):
                for key in spec:
                    if key not in INPUT_KEYS:
                        self.error(file, spec.mark_of(key),
                                   f"unknown input field {key!r}{_suggest(key, INPUT_KEYS)}")
                kind = spec.get("type", None)
                default = spec.get("default", None)
                if kind is None:
                    kind = _infer_type(default) if "default" in spec else "any"
                if kind not in TYPES:
                    self.error(file, spec.value_mark_of("type"),
                               f"input {name!r}: unknown type {kind!r} (one of {', '.join(TYPES)})")
                    continue
                unit, doc_text = spec.get("unit", ""), spec.get("description", "")
                param = Param(name, kind, default if "default" in spec else REQUIRED,
                              unit=str(unit or ""), doc=str(doc_text or ""))
            elif isinstance(spec, YamlList):
                param = Param(name, _infer_type(list(spec)), list(spec))
            else:
                param = Param(name, _infer_type(spec), spec)
            if not param.required and param.type != "key":
                value, problem = check_value(param, param.default)
                if problem:
                    self.error(file, mark, f"input {name!r}: default {problem}")
                    continue
                param = Param(name, param.type, value, unit=param.unit, doc=param.doc)
            declared[name] = param
        return declared

    def bind_inputs(
        self,
        declared: Mapping[str, Param],
        given: Mapping[str, Any],
        *,
        file: str,
        where: Mapping[str, Mark],
        default_mark: Mark,
        text_values: bool = False,
    ) -> dict[str, Any]:
        """Input values: defaults overridden by ``given``; unknown or missing inputs are errors."""
        values: dict[str, Any] = {}
        for name, value in given.items():
            mark = where.get(name, default_mark)
            param = declared.get(name)
            if param is None:
                known = ", ".join(declared) or "none"
                self.error(file, mark, f"unknown input {name!r}{_suggest(name, declared)} (inputs: {known})")
                continue
            if text_values and param.type != "str":
                with contextlib.suppress(yaml.YAMLError):  # not YAML: keep the text, the type check says why
                    value = yaml.safe_load(value)
            value, problem = check_value(param, value)
            if problem:
                self.error(file, mark, f"input {name!r} {problem}")
                value = param.default  # keep checking the rest without a cascade of errors
            values[name] = value
        for name, param in declared.items():
            if name not in values and name not in given:
                if param.required:
                    self.error(file, default_mark, f"input {name!r} has no default and was not given")
                else:
                    values[name] = param.default
        return values

    def import_plugins(self, doc: YamlMap, path: Path) -> None:
        """Import the modules a mission lists under ``plugins:`` (and nothing else)."""
        raw = doc.get("plugins")
        if raw is None:
            return
        file = str(path)
        if not isinstance(raw, YamlList):
            self.error(file, doc.value_mark_of("plugins"), "'plugins:' is a list of Python modules")
            return
        for index, module in enumerate(raw):
            mark = raw.mark_of(index)
            if not isinstance(module, str):
                self.error(file, mark, f"a plugin is a module name or a .py file, got {module!r}")
                continue
            problem = _import_plugin(module, path.parent)
            if problem:
                self.error(file, mark, problem)
            else:
                self.plugins.append(module)

    # -- nodes -------------------------------------------------------------------------------
    def node(self, raw: Any, mark: Mark, scope: _Scope, depth: int) -> NodeSpec | None:
        file = scope.file
        if depth > MAX_DEPTH:
            self.error(file, mark, f"the tree is nested deeper than {MAX_DEPTH} levels")
            return None
        if isinstance(raw, str):
            type_name, body, body_mark = raw, None, mark
        elif isinstance(raw, YamlMap):
            if "include" in raw:
                return self.include(raw, scope, depth)
            if len(raw) != 1:
                keys = ", ".join(repr(k) for k in raw) or "nothing"
                self.error(file, raw.mark, "a node is one 'TypeName: {parameters}' entry (or 'include: file'); "
                           f"found {keys}")
                return None
            ((type_name, body),) = raw.items()
            mark, body_mark = raw.mark_of(type_name), raw.value_mark_of(type_name)
        else:
            self.error(file, mark, f"expected a node like 'Drive: {{distance: 1.0}}', found {describe_value(raw)}")
            return None
        node_type = lookup(type_name) if isinstance(type_name, str) else None
        if node_type is None:
            names = [t.name for t in all_types()]
            self.error(file, mark, f"unknown node type {type_name!r}{_suggest(str(type_name), names)}")
            return None
        if body is None:
            body = YamlMap()
            body.mark, body.key_marks, body.value_marks = body_mark, {}, {}
        if not isinstance(body, YamlMap):
            self.error(file, body_mark,
                       f"{type_name}: parameters are a mapping 'name: value', found {describe_value(body)}")
            return None
        name = body.get("name", type_name)
        if not isinstance(name, str) or not name.strip():
            self.error(file, body.value_mark_of("name"), f"{type_name}: 'name' must be non-empty text")
            name = type_name
        children = self.children(node_type, body, scope, depth)
        params = self.params(node_type, body, scope, mark)
        if not scope.in_sense:
            sense_keys = [k for k in node_type.writes if (spec := key_spec(k)) is not None and spec.writer == "sense"]
            if sense_keys:
                self.error(file, mark, f"{type_name} writes {', '.join(sense_keys)}, which only the data-gathering "
                           "branch writes: list it under 'sense:'")
        if children is None or params is None:
            return None
        return NodeSpec(type_name, name, params, tuple(children), Location(file, mark.line, mark.col))

    def children(self, node_type: NodeType, body: YamlMap, scope: _Scope, depth: int) -> list[NodeSpec] | None:
        file, name = scope.file, node_type.name
        if node_type.kind == "composite":
            if "child" in body:
                self.error(file, body.mark_of("child"), f"{name} takes 'children:' (a list), not 'child:'")
                return None
            raw = body.get("children")
            if not isinstance(raw, YamlList):
                where = body.value_mark_of("children") if "children" in body else body.mark
                self.error(file, where, f"{name} needs 'children:', a list of nodes")
                return None
            count_ok = len(raw) >= node_type.min_children and (
                node_type.max_children is None or len(raw) <= node_type.max_children)
            if not count_ok:
                wanted = (f"exactly {node_type.min_children}" if node_type.max_children == node_type.min_children
                          else f"at least {node_type.min_children}")
                self.error(file, body.value_mark_of("children"), f"{name} takes {wanted} children, got {len(raw)}")
            items = [self.node(child, raw.mark_of(i), scope, depth + 1) for i, child in enumerate(raw)]
            return None if any(item is None for item in items) or not count_ok else items
        if node_type.kind == "decorator":
            if "children" in body:
                self.error(file, body.mark_of("children"), f"{name} decorates one node: use 'child:'")
                return None
            if "child" not in body:
                self.error(file, body.mark, f"{name} needs 'child:', the node it decorates")
                return None
            child = self.node(body["child"], body.value_mark_of("child"), scope, depth + 1)
            return None if child is None else [child]
        for key in ("child", "children"):
            if key in body:
                self.error(file, body.mark_of(key), f"{name} is a leaf and takes no {key}")
                return None
        return []

    def params(self, node_type: NodeType, body: YamlMap, scope: _Scope, mark: Mark) -> dict[str, Any] | None:
        file, declared = scope.file, {p.name: p for p in node_type.params}
        bound: dict[str, Any] = {}
        ok = True
        for key, raw in body.items():
            if key in STRUCTURE_KEYS:
                continue
            where = body.value_mark_of(key)
            param = declared.get(key)
            if param is None:
                takes = ", ".join(declared) or "no parameters"
                self.error(file, body.mark_of(key), f"{node_type.name} has no parameter {key!r}"
                           f"{_suggest(str(key), declared)} (it takes: {takes})")
                ok = False
                continue
            value, problem = substitute(raw, scope.values)
            if problem:
                self.error(file, where, f"{node_type.name}.{key}: {problem}")
                ok = False
                continue
            ref = parse_ref(value)
            if ref is not None:
                problem = check_ref(param, ref)
                value = ref
            else:
                value, problem = check_value(param, value)
            if problem:
                self.error(file, where, f"{node_type.name}.{key} {problem}")
                ok = False
                continue
            bound[key] = value
        for param in node_type.params:
            if param.name not in bound and param.name not in body:
                if param.required:
                    self.error(file, mark, f"{node_type.name} needs parameter {param.name!r}: {param.doc}")
                    ok = False
                else:
                    bound[param.name] = param.default
        return bound if ok else None

    def include(self, raw: YamlMap, scope: _Scope, depth: int) -> NodeSpec | None:
        file = scope.file
        ok = True
        for key in raw:
            if key not in INCLUDE_KEYS:
                self.error(file, raw.mark_of(key), f"unknown include entry {key!r}{_suggest(key, INCLUDE_KEYS)}"
                           " (an include takes: include, inputs, name)")
                ok = False
        target = raw["include"]
        mark = raw.value_mark_of("include")
        if not isinstance(target, str) or not target.strip():
            self.error(file, mark, "'include:' names a mission file")
            return None
        path = self.resolve(target, Path(file).parent)
        if path is None:
            where = ", ".join(str(p) for p in [Path(file).parent, *self.search_path])
            self.error(file, mark, f"cannot find included mission {target!r} (looked in {where})")
            return None
        if path in scope.chain:
            cycle = " -> ".join(p.name for p in (*scope.chain[scope.chain.index(path):], path))
            self.error(file, mark, f"include cycle: {cycle}")
            return None
        given = raw.get("inputs")
        if given is None:
            given = YamlMap()
            given.mark, given.key_marks, given.value_marks = raw.mark, {}, {}
        if not isinstance(given, YamlMap):
            self.error(file, raw.value_mark_of("inputs"), "an include's 'inputs:' is a mapping name: value")
            return None
        substituted: dict[str, Any] = {}
        for key, value in given.items():
            value, problem = substitute(value, scope.values)
            if problem:
                self.error(file, given.value_mark_of(key), f"include input {key!r}: {problem}")
                ok = False
            substituted[key] = value
        doc = self.document(path)
        if doc is None:
            return None
        if "sense" in doc:  # rate, max_time, cameras and evaluation of an included mission are not used
            self.error(str(path), doc.mark_of("sense"), "'sense:' of an included mission would be lost: move "
                       "these nodes to the top-level mission's 'sense:'")
        self.import_plugins(doc, path)
        declared = self.inputs(doc, str(path))
        marks = {k: given.value_mark_of(k) for k in given}
        values = self.bind_inputs(declared, substituted, file=file, where=marks, default_mark=mark)
        if "tree" not in doc:
            self.error(str(path), doc.mark, "the included mission has no 'tree:'")
            return None
        child_scope = _Scope(str(path), values, scope.in_sense, (*scope.chain, path))
        tree = self.node(doc["tree"], doc.value_mark_of("tree"), child_scope, depth + 1)
        if tree is None or not ok:
            return None
        name = raw.get("name", tree.name)
        if not isinstance(name, str):
            self.error(file, raw.value_mark_of("name"), "'name' must be text")
            return None
        return NodeSpec(tree.type, name, tree.params, tree.children, tree.location, included_from=str(path))

    def resolve(self, target: str, here: Path) -> Path | None:
        candidate = Path(target).expanduser()
        if candidate.is_absolute():
            return candidate.resolve() if candidate.is_file() else None
        for folder in (here, *self.search_path, LIBRARY):
            path = folder / candidate
            if path.is_file():
                return path.resolve()
        return None


def load_mission(
    path: str | os.PathLike,
    *,
    overrides: Mapping[str, str] | None = None,
    search_path: Iterable[str | os.PathLike] = (),
) -> MissionSpec:
    """Load and validate a mission file; raise :class:`InputError` listing every problem found.

    ``overrides`` are ``--set name=value`` texts, parsed as YAML scalars and checked against the
    inputs' types. ``search_path`` is where ``include:`` looks after the including file's folder
    (then ``$BEARINGS_PATH``, then the shipped mission library).
    """
    env = [Path(p) for p in os.environ.get(PATH_ENV, "").split(os.pathsep) if p]
    loader = _Loader(search_path=[Path(p) for p in search_path] + env)
    file_path = resolve_mission_path(path)
    file = str(file_path)
    doc = loader.document(file_path)
    if doc is None:
        raise InputError(loader.diagnostics)
    loader.import_plugins(doc, file_path)
    declared = loader.inputs(doc, file)
    values = loader.bind_inputs(declared, dict(overrides or {}), file="--set", where={},
                                default_mark=Mark(0, 0), text_values=True)
    scope = _Scope(file, values, chain=(file_path.resolve(),))
    name = doc.get("mission", file_path.stem)
    if not isinstance(name, str):
        loader.error(file, doc.value_mark_of("mission"), "'mission:' is the mission's name (text)")
        name = file_path.stem
    description = doc.get("description", "")
    if not isinstance(description, str):
        loader.error(file, doc.value_mark_of("description"), "'description:' is text")
        description = ""
    rate = _number(loader, doc, "rate", file, default=10.0, low=0.1, high=1000.0, unit="Hz")
    max_time = _number(loader, doc, "max_time", file, default=None, low=0.0, high=1e7, unit="s")
    sense = _sense(loader, doc, scope)
    cameras = _cameras(loader, doc, file)
    tree = None
    if "tree" not in doc:
        loader.error(file, doc.mark, "the mission has no 'tree:' (the root node of the mission)")
    else:
        tree = loader.node(doc["tree"], doc.value_mark_of("tree"), scope, 0)
    evaluation = _evaluation(loader, doc, scope)
    if loader.diagnostics or tree is None:
        raise InputError(loader.diagnostics)
    return MissionSpec(
        name=name, file=file, tree=tree, description=description, inputs=declared, values=values,
        sense=sense, plugins=tuple(loader.plugins), rate_hz=rate, max_time_s=max_time,
        evaluation=evaluation, files=tuple(dict.fromkeys(loader.files)), cameras=cameras,
    )


def resolve_mission_path(path: str | os.PathLike) -> Path:
    """A mission given by path, or by the name of a shipped mission (``square``)."""
    candidate = Path(path)
    if not candidate.exists() and not candidate.suffix and (LIBRARY / f"{candidate}.yaml").is_file():
        return LIBRARY / f"{candidate}.yaml"
    return candidate


def substitute(value: Any, values: Mapping[str, Any]) -> tuple[Any, str | None]:
    """Replace ``${input}`` in a parameter value: a whole ``${x}`` keeps x's type."""
    if isinstance(value, str):
        whole = SUBST.fullmatch(value.strip())
        if whole:
            name = whole.group(1)
            if name not in values:
                return value, f"unknown input ${{{name}}}{_suggest(name, values)}"
            return values[name], None
        problem = None

        def text(match: re.Match) -> str:
            nonlocal problem
            if match.group(1) not in values:
                problem = f"unknown input ${{{match.group(1)}}}{_suggest(match.group(1), values)}"
                return match.group(0)
            return str(values[match.group(1)])

        return SUBST.sub(text, value), problem
    if isinstance(value, list):
        out = []
        for item in value:
            item, problem = substitute(item, values)
            if problem:
                return value, problem
            out.append(item)
        return out, None
    if isinstance(value, dict):
        out_map = {}
        for key, item in value.items():
            item, problem = substitute(item, values)
            if problem:
                return value, problem
            out_map[key] = item
        if parse_ref(value) is not None:
            return value, None
        return out_map, None
    return value, None


def _sense(loader: _Loader, doc: YamlMap, scope: _Scope) -> tuple[NodeSpec, ...]:
    raw = doc.get("sense")
    if raw is None:
        return ()
    if not isinstance(raw, YamlList):
        loader.error(scope.file, doc.value_mark_of("sense"), "'sense:' is a list of nodes added to the "
                     "data-gathering branch")
        return ()
    sense_scope = _Scope(scope.file, scope.values, in_sense=True, chain=scope.chain)
    nodes = [loader.node(item, raw.mark_of(i), sense_scope, 1) for i, item in enumerate(raw)]
    return tuple(n for n in nodes if n is not None)


def _cameras(loader: _Loader, doc: YamlMap, file: str) -> tuple[str, ...] | None:
    raw = doc.get("cameras")
    if raw is None:
        return None
    if not isinstance(raw, YamlList) or not all(isinstance(c, str) and c for c in raw):
        loader.error(file, doc.value_mark_of("cameras"), "'cameras:' is a list of camera names")
        return None
    return tuple(raw)


def _evaluation(loader: _Loader, doc: YamlMap, scope: _Scope) -> dict[str, Any]:
    raw = doc.get("evaluation")
    if raw is None:
        return {}
    file = scope.file
    if not isinstance(raw, YamlMap):
        loader.error(file, doc.value_mark_of("evaluation"), "'evaluation:' is a mapping (goal, reference_path)")
        return {}
    out: dict[str, Any] = {}
    for key, value in raw.items():
        mark = raw.value_mark_of(key)
        value, problem = substitute(value, scope.values)
        if problem:
            loader.error(file, mark, f"evaluation.{key}: {problem}")
            continue
        if key == "goal":
            if not _is_point(value):
                loader.error(file, mark, "evaluation.goal is a point [x, y] in metres (world frame)")
                continue
            out["goal"] = [float(v) for v in value]
        elif key == "frame":
            if value not in ("world", "start"):
                loader.error(file, mark, "evaluation.frame is 'world' (the world's coordinates) or 'start' "
                             "(relative to the robot's true start pose)")
                continue
            out["frame"] = value
        elif key == "reference_path":
            if not isinstance(value, list) or len(value) < 2 or not all(_is_point(p) for p in value):
                loader.error(file, mark, "evaluation.reference_path is a list of at least two points [x, y]")
                continue
            out["reference_path"] = [[float(v) for v in p] for p in value]
        else:
            loader.error(file, raw.mark_of(key), f"unknown evaluation entry {key!r}"
                         f"{_suggest(str(key), ('goal', 'reference_path', 'frame'))}")
    return out


def _number(loader: _Loader, doc: YamlMap, key: str, file: str, *, default: float | None, low: float,
            high: float, unit: str) -> float | None:
    if key not in doc:
        return default
    value = doc[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high:
        loader.error(file, doc.value_mark_of(key), f"'{key}:' is a number of {unit} between {low:g} and {high:g}")
        return default
    return float(value)


def _is_point(value: Any) -> bool:
    return (isinstance(value, list) and len(value) == 2
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value))


def _infer_type(value: Any) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "int"
    if isinstance(value, float):
        return "float"
    if isinstance(value, str):
        return "str"
    if isinstance(value, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        return "list[float]"
    return "any"


def _import_plugin(module: str, here: Path) -> str | None:
    """Import one plugin; the problem as text, or None when it imported."""
    try:
        if module.endswith(".py"):
            path = (here / module).resolve()
            if not path.is_file():
                return f"plugin file {module!r} not found next to the mission"
            name = f"bearings_plugin_{path.stem}"
            if name not in sys.modules:
                spec = importlib.util.spec_from_file_location(name, path)
                if spec is None or spec.loader is None:
                    return f"cannot load plugin file {module!r}"
                mod = importlib.util.module_from_spec(spec)
                sys.modules[name] = mod
                try:
                    spec.loader.exec_module(mod)
                except BaseException:
                    del sys.modules[name]
                    raise
            return None
        if not MODULE.match(module):
            return f"plugin {module!r} is neither a module name (a.b.c) nor a .py file"
        importlib.import_module(module)
        return None
    except ModuleNotFoundError as exc:
        return f"plugin {module!r} cannot be imported: no module named {exc.name!r}"
    except Exception as exc:  # noqa: BLE001 - a broken plugin is the user's input error
        return f"plugin {module!r} failed to import: {type(exc).__name__}: {exc}"


def _suggest(word: Any, options: Iterable[Any]) -> str:
    options = [str(o) for o in options]
    close = difflib.get_close_matches(str(word), options, n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else ""
