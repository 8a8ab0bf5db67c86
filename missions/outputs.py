"""Where a mission's files go: its ports that name files, resolved and confined before anything runs.

Node types declare which input ports name a file they read or write (``InputPort(file=READS |
WRITES)``, :mod:`behaviours.ports`), built-in or plugin alike, so the rules below reach every
file a mission names without knowing its node types:

- **Relative paths** resolve against the mission's *output folder*: ``--output-dir`` when given,
  else the mission's own folder (where its includes and plugins come from), else, for a mission
  shipped with bearings, the current directory (``bearings run teach_route --set map=r.ltmap``
  writes ``./r.ltmap``). Reads and writes resolve alike, so a mission that writes a map and
  reads it back names one file.
- **Written files are confined**: once every symbolic link on the way is followed, a written
  file lies inside the output folder or the mission's folder; anything else (``/any/where``,
  ``..``, a link inside the folder pointing out) is a located error at load time, exit 2. The
  node is then built with the resolved absolute path, and a write checks that no link was put
  in its way since (:func:`maps.store.check_not_redirected`).

What this cannot stop: a plugin is Python code and may open any file itself (docs/failure.md).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

from behaviours.ports import WRITES, InputPort, Ref
from behaviours.registry import Registry
from maps.store import Diagnostic, InputError, OutputFolders, output_problem
from missions.language import MissionSpec, NodeSpec


def output_folders(mission_file: Path, output_dir: str | os.PathLike | None, library: Path) -> OutputFolders:
    """The output folders of the mission in ``mission_file`` (``library``: the shipped missions' folder)."""
    folder = mission_file.resolve().parent
    shipped = folder == library.resolve()
    if output_dir is not None:
        return OutputFolders.of(output_dir, *(() if shipped else (folder,)))
    return OutputFolders.of(Path.cwd() if shipped else folder)


def file_ports(nodes: Iterable[NodeSpec], registry: Registry) -> Iterator[tuple[NodeSpec, InputPort, str]]:
    """Every port of ``nodes`` (and their subtrees) that names a file, with its literal text (not empty)."""
    for top in nodes:
        for spec in top.walk():
            node_type = registry.lookup(spec.type)
            for port in node_type.inputs if node_type is not None else ():
                value = spec.inputs.get(port.name)
                if port.file and isinstance(value, str) and value:
                    yield spec, port, value


def written_files(nodes: Iterable[NodeSpec], registry: Registry, folders: OutputFolders
                  ) -> list[tuple[NodeSpec, str, Path]]:
    """(node, port name, resolved path) of every file the nodes would write."""
    return [(spec, port.name, folders.resolve(text)) for spec, port, text in file_ports(nodes, registry)
            if port.file == WRITES]


def confinement_problems(nodes: Iterable[NodeSpec], registry: Registry, folders: OutputFolders) -> list[Diagnostic]:
    """A located diagnostic for every written file outside the output folders."""
    problems = []
    for spec, port, text in file_ports(nodes, registry):
        problem = folders.outside(text) if port.file == WRITES else None
        if problem:
            where = spec.where(port.name)
            problems.append(Diagnostic(where.file, where.line, where.col, f"{spec.type}.{port.name}: {problem}"))
    return problems


def resolved_ports(spec: NodeSpec, node_type: Any, folders: OutputFolders | None) -> dict[str, Any]:
    """``spec``'s ports with every file path made absolute (what the node is built with)."""
    ports = spec.ports
    if folders is None:
        return ports
    for port in node_type.inputs:
        value = ports.get(port.name)
        if port.file and isinstance(value, str) and value and not isinstance(value, Ref):
            ports[port.name] = str(folders.resolve(value))
    return ports


def prepare_written_files(mission: MissionSpec, announce: Callable[[str], None]) -> None:
    """Before the first tick: create the output folder when the mission writes into it and it is
    missing (saying so through ``announce``), and check every file the mission writes can be
    written (:func:`maps.store.output_problem`); :class:`InputError` naming the ports otherwise."""
    folders = mission.folders
    if folders is None:
        return
    written = written_files([*mission.sense, mission.tree], mission.registry, folders)
    base = folders.base
    if any(base in path.parents for _, _, path in written) and not base.exists():
        try:
            base.mkdir(parents=True)
            announce(f"created the output folder {base}")
        except OSError:
            pass  # each file's own check below says why it cannot be written
    problems = []
    for spec, port, path in written:
        problem = output_problem(path)
        if problem:
            where = spec.where(port)
            problems.append(Diagnostic(where.file, where.line, where.col, f"{spec.type}.{port}: cannot write "
                                       f"{path}: {problem}"))
    if problems:
        raise InputError(problems)
