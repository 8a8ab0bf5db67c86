"""Load a mission file: parse safely, take its plugins' node types, substitute inputs, resolve
includes, validate every node against the registry and check the data flow, reporting all
problems of all files in one pass.

Everything is checked here, before anything ticks: the top-level entries (declared in
:mod:`missions.model`), unknown node types, unknown, missing or mistyped ports, references,
the data flow between nodes (:mod:`missions.dataflow`), unknown inputs, include cycles and size,
malformed YAML, empty files and non-UTF-8 bytes. Problems are
:class:`~maps.store.Diagnostic` values raised together in one :class:`~maps.store.InputError`.

A load gets its own :class:`~behaviours.registry.Registry` (a child of the default one), so
plugins of one mission are never visible to the next mission loaded in the same process.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from behaviours.ports import InputPort
from behaviours.registry import Registry
from maps.located import diagnose, suggest
from maps.store import Diagnostic, InputError, Mark, YamlList, YamlMap, load_yaml, mark_of
from missions.camera_use import cameras_read
from missions.dataflow import check_dataflow
from missions.inputs import IDENT, bind, declaration, substitute
from missions.language import MissionSpec, NodeSpec
from missions.load_checks import load_checks
from missions.model import Evaluation, InputDeclaration, MissionFile
from missions.nodes import NodeReader, Scope
from missions.outputs import confinement_problems, output_folders
from missions.plugins import PluginError, load_plugin

LIBRARY = Path(__file__).parent / "library"
PATH_ENV = "BEARINGS_PATH"
INCLUDE_KEYS = ("include", "inputs", "name")


@dataclass
class _Document:
    """One parsed mission file: its located data and validated top level."""

    path: Path
    data: YamlMap
    header: MissionFile


@dataclass
class _Loader:
    search_path: list[Path]
    registry: Registry
    diagnostics: list[Diagnostic] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    plugins: list[str] = field(default_factory=list)
    _documents: dict[Path, _Document | None] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.reader = NodeReader(self.registry, self.diagnostics, self.include)

    def error(self, file: str, mark: Mark, message: str) -> None:
        self.diagnostics.append(Diagnostic(file, mark.line, mark.col, message))

    # -- documents ---------------------------------------------------------------------------
    def document(self, path: Path) -> _Document | None:
        """A mission file's data and top level (parsed once per load), or None with diagnostics."""
        key = path.resolve()
        if key in self._documents:
            return self._documents[key]
        self._documents[key] = None
        try:
            data = load_yaml(path)
            if not isinstance(data, YamlMap):
                raise InputError([Diagnostic(str(path), *_at(mark_of(data, Mark(1, 1))),
                                             "a mission file is a mapping with at least a 'tree:' entry")])
        except InputError as exc:
            self.diagnostics.extend(exc.diagnostics)
            return None
        header = self._header(path, data)
        if header is None:
            return None
        self.files.append(str(path))
        self._documents[key] = _Document(path, data, header)
        self.take_plugins(self._documents[key])  # type: ignore[arg-type]
        return self._documents[key]

    def _header(self, path: Path, data: YamlMap) -> MissionFile | None:
        """The validated top level; with problems, the valid entries only (checking goes on below)."""
        try:
            return MissionFile.model_validate(data)
        except ValidationError as exc:
            self.diagnostics.extend(diagnose(exc, data, file=str(path), model=MissionFile))
            broken = {error["loc"][0] for error in exc.errors() if error["loc"]}
        if "tree" not in data:
            return None
        return MissionFile.model_construct(**{k: v for k, v in data.items() if k in MissionFile.model_fields
                                              and k not in broken})

    def inputs(self, doc: _Document) -> dict[str, InputPort]:
        """The declared inputs: ``name: default`` or ``name: {type, default, unit, description}``."""
        raw = doc.data.get("inputs")
        declared: dict[str, InputPort] = {}
        if not isinstance(raw, YamlMap):
            return declared  # absent, or already reported by the top-level check
        for name, spec in raw.items():
            mark = raw.mark_of(name)
            if not isinstance(name, str) or not IDENT.match(name):
                self.error(str(doc.path), mark, f"input name {name!r} must be an identifier (letters, digits, _)")
                continue
            explicit = self._input_fields(doc, name, spec) if isinstance(spec, YamlMap) else None
            if isinstance(spec, YamlMap) and explicit is None:
                continue
            port, problem = declaration(name, spec, explicit)
            if problem or port is None:
                self.error(str(doc.path), mark, problem or f"input {name!r} is malformed")
                continue
            declared[name] = port
        return declared

    def _input_fields(self, doc: _Document, name: str, spec: YamlMap) -> dict[str, Any] | None:
        try:
            fields = InputDeclaration.model_validate(spec)
        except ValidationError as exc:
            self.diagnostics.extend(diagnose(exc, spec, file=str(doc.path), model=InputDeclaration,
                                             path=("inputs", name)))
            return None
        return {key: getattr(fields, key) for key in fields.model_fields_set}

    def take_plugins(self, doc: _Document) -> None:
        """Add the node types of the modules a mission lists under ``plugins:`` to this load's registry."""
        raw = doc.data.get("plugins")
        if not isinstance(raw, YamlList):
            return  # absent, or already reported by the top-level check
        for index, module in enumerate(doc.header.plugins):
            try:
                self.plugins.append(load_plugin(module, doc.path.parent, self.registry))
            except PluginError as exc:
                self.error(str(doc.path), raw.mark_of(index), str(exc))

    # -- includes ----------------------------------------------------------------------------
    def include(self, raw: YamlMap, scope: Scope, depth: int) -> NodeSpec | None:
        file = scope.file
        unknown = [key for key in raw if key not in INCLUDE_KEYS]
        for key in unknown:
            self.error(file, raw.mark_of(key), f"unknown include entry {key!r}{suggest(key, INCLUDE_KEYS)}"
                       " (an include takes: include, inputs, name)")
        target, mark = raw["include"], raw.value_mark_of("include")
        path = self._include_path(target, scope, mark)
        given = raw.get("inputs", {})
        if path is None or not isinstance(given, dict):
            if not isinstance(given, dict):
                self.error(file, raw.value_mark_of("inputs"), "an include's 'inputs:' is a mapping name: value")
            return None
        doc = self.document(path)
        if doc is None:
            return None
        if doc.data.get("sense"):
            self.error(str(path), doc.data.mark_of("sense"), "'sense:' of an included mission would be lost: move "
                       "these nodes to the top-level mission's 'sense:'")
        values, ok = self._include_values(raw, given, doc, scope)
        tree = self.reader.node(doc.data["tree"], doc.data.value_mark_of("tree"),
                                Scope(str(path), values, (*scope.chain, path)), depth + 1)
        if tree is None or unknown or not ok:
            return None
        name, problem = substitute(raw.get("name", tree.name), scope.values)
        if problem or not isinstance(name, str):
            self.error(file, raw.value_mark_of("name"), problem or "'name' must be text")
            return None
        return NodeSpec(tree.type, name, tree.inputs, tree.children, tree.location, included_from=str(path),
                        outputs=tree.outputs, locations=tree.locations)

    def _include_path(self, target: Any, scope: Scope, mark: Mark) -> Path | None:
        file = scope.file
        if not isinstance(target, str) or not target.strip():
            self.error(file, mark, "'include:' names a mission file")
            return None
        path = self.resolve(target, Path(file).parent)
        if path is None:
            where = ", ".join(str(p) for p in [Path(file).parent, *self.search_path])
            self.error(file, mark, f"cannot find included mission {target!r} in the mission's folder or the "
                       f"search path (looked in {where}, and the mission library)")
            return None
        if path in scope.chain:
            cycle = " -> ".join(p.name for p in (*scope.chain[scope.chain.index(path):], path))
            self.error(file, mark, f"include cycle: {cycle}")
            return None
        return path

    def _include_values(self, raw: YamlMap, given: Mapping[str, Any], doc: _Document, scope: Scope
                        ) -> tuple[dict[str, Any], bool]:
        """The included file's input values (checking goes on with what is valid) and whether all are."""
        substituted: dict[str, Any] = {}
        ok = True
        for key, value in given.items():
            value, problem = substitute(value, scope.values)
            if problem:
                self.error(scope.file, given.value_mark_of(key), f"include input {key!r}: {problem}")  # type: ignore[attr-defined]
                ok = False
            substituted[key] = value
        marks = {k: given.value_mark_of(k) for k in given} if isinstance(given, YamlMap) else {}
        values, problems = bind(self.inputs(doc), substituted, file=scope.file, marks=marks,
                                default_mark=raw.value_mark_of("include"))
        self.diagnostics.extend(problems)
        return values, ok and not problems

    def resolve(self, target: str, here: Path) -> Path | None:
        """An included file: inside the including file's folder, then the search path, then the library.

        Absolute paths and ``..`` that leave those folders are refused (a mission is data and
        reads nothing outside the folders the user named).
        """
        roots = (here, *self.search_path, LIBRARY)
        for root in roots:
            path = (root / target).resolve()
            if path.is_file() and _inside(path, root):
                return path
        return None


def load_mission(
    path: str | os.PathLike,
    *,
    overrides: Mapping[str, str] | None = None,
    search_path: Iterable[str | os.PathLike] = (),
    registry: Registry | None = None,
    output_dir: str | os.PathLike | None = None,
    require_inputs: bool = False,
) -> MissionSpec:
    """Load and validate a mission file; raise :class:`InputError` listing every problem found.

    ``overrides`` are ``--set name=value`` texts, parsed as YAML scalars and checked against the
    inputs' types. ``search_path`` is where ``include:`` looks after the including file's folder
    (then ``$BEARINGS_PATH``, then the shipped mission library). ``registry`` is the set of node
    types the mission may use before its own plugins (default: built-ins and entry points); the
    mission's plugins are added to a child of it, never to it. ``output_dir``: where the mission's
    files go (``--output-dir``; see :mod:`missions.outputs`: relative paths resolve there, and a
    file written outside it and the mission's folder is refused).
    mission's plugins are added to a child of it, never to it. A required input (declared without
    a default) that ``overrides`` does not give is a problem with ``require_inputs`` (a mission to
    run: ``bearings run`` says so before anything moves); without it the mission is checked with
    the input :class:`~missions.inputs.Unbound` (``bearings validate``, ``show``).
    """
    env = [Path(p) for p in os.environ.get(PATH_ENV, "").split(os.pathsep) if p]
    loader = _Loader(search_path=[Path(p).resolve() for p in [*search_path, *env]],
                     registry=(registry or Registry.default()).child())
    file_path = resolve_mission_path(path)
    if not file_path.exists():
        raise InputError([_not_found(file_path)])
    doc = loader.document(file_path)
    if doc is None:
        raise InputError(loader.diagnostics)
    declared = loader.inputs(doc)
    values, problems = bind(declared, dict(overrides or {}), file="--set", marks={}, default_mark=Mark(0, 0),
                            texts=True, require=require_inputs)
    loader.diagnostics.extend(problems)
    scope = Scope(str(file_path), values, chain=(file_path.resolve(),))
    before_nodes = len(loader.diagnostics)
    sense = _sense(loader, doc, scope)
    tree = loader.reader.node(doc.data["tree"], doc.data.value_mark_of("tree"), scope, 0)
    nodes_whole = tree is not None and len(loader.diagnostics) == before_nodes
    evaluation = _evaluation(loader, doc, scope)
    cameras = _cameras(loader, doc, scope)
    folders = output_folders(file_path, output_dir, LIBRARY)
    loader.diagnostics.extend(confinement_problems([*sense, *([tree] if tree else [])], loader.registry, folders))
    if tree is None or not nodes_whole:  # a node left out would make its outputs look unwritten below
        raise InputError(loader.diagnostics)
    header = doc.header
    mission = MissionSpec(
        name=header.mission or file_path.stem, file=str(file_path), tree=tree, description=header.description,
        inputs=declared, values=values, sense=sense, plugins=tuple(loader.plugins), rate_hz=header.rate,
        max_time_s=header.max_time, overrun_s=header.overrun, evaluation=evaluation,
        files=tuple(dict.fromkeys(loader.files)),
        cameras=cameras, registry=loader.registry, folders=folders,
    )  # fmt: skip
    problems = [*loader.diagnostics, *check_dataflow(mission)]  # every problem at once, not in stages
    if not problems:
        problems = load_checks(mission)  # against what the files hold: only a mission whose flow is sound
    if problems:
        raise InputError(problems)
    if cameras is None:  # grab what the nodes read, no more (missions/camera_use.py)
        mission = replace(mission, cameras=cameras_read(mission))
    return mission


def resolve_mission_path(path: str | os.PathLike) -> Path:
    """A mission given by path, or by the name of a shipped mission (``square``)."""
    candidate = Path(path)
    if not candidate.exists() and not candidate.suffix and (LIBRARY / f"{candidate}.yaml").is_file():
        return LIBRARY / f"{candidate}.yaml"
    return candidate


def _not_found(path: Path) -> Diagnostic:
    """A mission that is neither a file nor a shipped name: the shipped name it is most like, if any."""
    shipped = sorted(p.stem for p in LIBRARY.glob("*.yaml"))
    if path.suffix or len(path.parts) > 1:
        return Diagnostic(str(path), 0, 0, "no such file")
    return Diagnostic(str(path), 0, 0, f"no such file, and no shipped mission of that name{suggest(path.name, shipped)}"
                      f" (bearings missions lists them: {', '.join(shipped)})")


def _sense(loader: _Loader, doc: _Document, scope: Scope) -> tuple[NodeSpec, ...]:
    raw = doc.data.get("sense")
    if not isinstance(raw, YamlList):
        return ()  # absent, or already reported by the top-level check
    nodes = [loader.reader.node(item, raw.mark_of(i), scope, 1) for i, item in enumerate(raw)]
    return tuple(n for n in nodes if n is not None)


def _cameras(loader: _Loader, doc: _Document, scope: Scope) -> tuple[str, ...] | None:
    """The cameras the mission grabs, inputs substituted (``cameras: ["${camera}"]``)."""
    raw = doc.data.get("cameras")
    if doc.header.cameras is None or not isinstance(raw, YamlList):
        return None
    names = []
    for index, entry in enumerate(doc.header.cameras):
        name, problem = substitute(entry, scope.values)
        if problem or not isinstance(name, str) or not name:
            loader.error(scope.file, raw.mark_of(index), f"cameras[{index}]: {problem or 'a camera name is text'}")
            continue
        names.append(name)
    return tuple(dict.fromkeys(names))


def _evaluation(loader: _Loader, doc: _Document, scope: Scope) -> dict[str, Any]:
    raw = doc.data.get("evaluation")
    if not isinstance(raw, YamlMap):
        return {}  # absent, or already reported by the top-level check
    file = scope.file
    values: dict[str, Any] = {}
    for key, value in raw.items():
        values[key], problem = substitute(value, scope.values)
        if problem:
            loader.error(file, raw.value_mark_of(key), f"evaluation.{key}: {problem}")
            return {}
    substituted = _relocated(raw, values)
    try:
        model = Evaluation.model_validate(substituted)
    except ValidationError as exc:
        loader.diagnostics.extend(diagnose(exc, substituted, file=file, model=Evaluation, path=("evaluation",)))
        return {}
    return model.model_dump(exclude_none=True, exclude_unset=True)


def _relocated(raw: YamlMap, values: dict[str, Any]) -> YamlMap:
    """Substituted values under the marks of the original entries (so errors point at the file)."""
    out = YamlMap(values)
    out.mark, out.key_marks, out.value_marks = raw.mark, raw.key_marks, raw.value_marks
    return out


def _inside(path: Path, root: Path) -> bool:
    try:
        path.relative_to(root.resolve())
    except ValueError:
        return False
    return True


def _at(mark: Mark) -> tuple[int, int]:
    return mark.line, mark.col

