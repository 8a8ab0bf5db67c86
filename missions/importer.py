"""``bearings import``: a BehaviorTree.CPP v4 XML file, as Groot2 saves it, to a bearings mission.

The file's main tree (``main_tree_to_execute``, or the one tree no other references) becomes the
mission's ``tree:``; a tree named ``<main>_sense`` (what the export writes for ``sense:``)
becomes its ``sense:``. Nodes whose BT.CPP name is a bearings node type's (its ``BTCPP`` name or
its own) keep their ports; BT.CPP's control nodes map back onto bearings' (``ReactiveSequence``
-> ``Sequence`` with ``memory: false``, ``Timeout msec`` -> ``Timeout duration``, ``Precondition``
-> ``Guard``, ...); blackboard keys and scripts are read with the mapping of
:mod:`missions.btcpp`.

``<SubTree>`` references are inlined: BT.CPP resolves a subtree's port remapping per instance,
which is exactly what inlining does, while bearings' includes substitute inputs at load time and
have no blackboard remapping; one self-contained file is also what Groot2 users hand over. A
SubTree's ``name`` becomes the name of the subtree's root node, as an include's ``name`` does.

Everything with no bearings equivalent (an unknown node or port, BT.CPP nodes bearings lacks,
scripts other than one comparison, scripted pre/post conditions, subtree-local blackboard
entries, ...) is reported as ``file:line:col: message``; the mission written is then loaded
with :func:`missions.loader.load_mission` and its problems are reported at the XML node they
came from. Nothing is written unless the mission validates.

The steps, one module each: :mod:`missions.btcpp_xml` reads the XML with positions,
:mod:`missions.btcpp_reader` turns it into drafts of bearings nodes (SubTree scopes in
:mod:`missions.btcpp_scope`, BT.CPP's built-ins in :mod:`missions.btcpp_builtins`), and this
module writes the mission and checks it with the loader.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Any

from behaviours.ports import Ref
from behaviours.registry import Registry
from maps.store import (
    MAX_FILE_BYTES,
    Diagnostic,
    InputError,
    Mark,
    YamlList,
    YamlMap,
    dump_yaml,
    parse_yaml,
    read_bytes,
)
from missions.btcpp_reader import Draft, MissionDraft, Reader
from missions.btcpp_xml import node_tag, parse_xml
from missions.loader import load_mission
from missions.plugins import PluginError, load_plugin


# -- writing and checking the mission -------------------------------------------------------------
def _plain(draft: Draft) -> Any:
    """A draft as mission YAML writes it: ``Type: {name, ports, child | children}`` or the bare name."""
    body: dict[str, Any] = {}
    if draft.name is not None and draft.name != draft.type.name:
        body["name"] = draft.name
    body.update({k: str(v) if isinstance(v, Ref) else v for k, v in draft.ports.items()})
    if draft.type.kind == "decorator":
        body["child"] = _plain(draft.children[0])
    elif draft.type.kind == "composite":
        body["children"] = [_plain(child) for child in draft.children]
    return {draft.type.name: body} if body else draft.type.name


def dump_mission(document: dict[str, Any]) -> str:
    """Plain mission data as YAML text the mission loader reads back to the same values."""
    return dump_yaml(document)


def render(mission: MissionDraft, source: str, plugins: tuple[str, ...] = ()) -> str:
    """The mission file's text (listing ``plugins``, whose node types the tree uses)."""
    document: dict[str, Any] = {"mission": mission.name}
    if plugins:
        document["plugins"] = list(plugins)
    if mission.sense:
        document["sense"] = [_plain(node) for node in mission.sense]
    document["tree"] = _plain(mission.tree)
    return f"# Imported from {source} (BehaviorTree.CPP v4) by bearings import.\n{dump_mission(document)}"


Start = tuple[int, int]  # line, column in the rendered mission text


def _node_starts(text: str, mission: MissionDraft) -> list[tuple[Start, Draft]]:
    """Where each draft starts in the rendered text, in order (to report the loader's problems in the XML)."""
    data = parse_yaml(text)
    out: list[tuple[Start, Draft]] = []
    sense = data.get("sense", [])
    for index, node in enumerate(mission.sense):
        _lines(sense[index], sense.mark_of(index), node, out)
    _lines(data["tree"], data.value_mark_of("tree"), mission.tree, out)
    return sorted(out, key=lambda item: item[0])


def _lines(raw: Any, mark: Mark, draft: Draft, out: list[tuple[Start, Draft]]) -> None:
    out.append(((mark.line, mark.col), draft))
    if not draft.children:
        return
    body = raw[draft.type.name]
    if isinstance(body, YamlMap) and draft.type.kind == "decorator":
        _lines(body["child"], body.value_mark_of("child"), draft.children[0], out)
    elif isinstance(body, YamlMap) and isinstance(body.get("children"), YamlList):
        items = body["children"]
        for index, child in enumerate(draft.children):
            _lines(items[index], items.mark_of(index), child, out)


def _validated(text: str, mission: MissionDraft, file: str, registry: Registry | None) -> None:
    """Load the written mission as ``bearings validate`` would; its problems, located in the XML."""
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "imported.yaml")
        Path(path).write_text(text, encoding="utf-8")
        try:
            load_mission(path, registry=registry)
        except InputError as exc:
            starts = _node_starts(text, mission)
            raise InputError([_in_xml(d, path, file, starts) for d in exc.diagnostics]) from None


def _in_xml(diagnostic: Diagnostic, path: str, file: str, starts: list[tuple[Start, Draft]]) -> Diagnostic:
    """A problem of the written mission, at the XML node it came from (naming the bearings type
    the node became when the names differ: ``<RetryUntilSuccessful> as Retry: ...``)."""
    if diagnostic.file != path:
        return diagnostic
    draft = next((d for start, d in reversed(starts) if start <= (diagnostic.line, diagnostic.col)), None)
    if draft is None:
        return Diagnostic(file, 0, 0, diagnostic.message)
    element = draft.element
    tag = node_tag(element)
    prefix = "" if tag == draft.type.name else f"<{tag}> as {draft.type.name}: "
    return Diagnostic(file, element.line, element.col, prefix + diagnostic.message)


def import_btcpp(path: str | os.PathLike, *, registry: Registry | None = None, plugins: tuple[str, ...] = (),
                 plugin_folder: str | os.PathLike = ".") -> str:
    """The mission text for a BehaviorTree.CPP v4 file, validated; :class:`InputError` with every problem.

    ``plugins`` (modules, or ``.py`` files in ``plugin_folder``, the folder the mission will be in)
    provide node types the XML uses that bearings does not have: they are loaded for the import and
    listed under the mission's ``plugins:``, so a mission with plugins survives the round trip.
    """
    file = str(path)
    data = read_bytes(path, limit=MAX_FILE_BYTES, what="a BehaviorTree.CPP XML file")
    root = parse_xml(data, file)
    types = _with_plugins(registry or Registry.default(), plugins, Path(plugin_folder))
    reader = Reader(file, types)
    mission = reader.mission(root)
    if reader.problems or mission is None:
        raise InputError(reader.problems)
    _validated(render(mission, Path(file).name), mission, file, types)  # the plugins' types already in
    return render(mission, Path(file).name, plugins)


def _with_plugins(registry: Registry, plugins: tuple[str, ...], folder: Path) -> Registry:
    """A child of ``registry`` with the node types of ``plugins``; a plugin that fails is an InputError."""
    if not plugins:
        return registry
    types = registry.child()
    problems = []
    for spec in plugins:
        try:
            load_plugin(spec, folder, types)
        except PluginError as exc:
            problems.append(Diagnostic(f"--plugin {spec}", 0, 0, str(exc)))
    if problems:
        raise InputError(problems)
    return types
