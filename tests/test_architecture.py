"""The shape of the house: no import cycles, imports point down the layers, modules stay small.

The import graph is read from the source (every ``import`` statement anywhere in a module,
including those inside functions and ``TYPE_CHECKING`` blocks), so a lazy import that hides a
loop from the interpreter is still a loop here. Layers (docs/architecture.md):

    experiments -> missions -> behaviours -> maps, drivers -> perception

with two narrow doors: every layer may use the file boundary of ``maps`` (``store``, ``located``,
``mapfile``), and behaviours see only ``drivers.interfaces`` of the drivers.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("perception", "maps", "drivers", "behaviours", "missions", "experiments")
FILE_BOUNDARY = ("maps.store", "maps.located", "maps.mapfile")
ALLOWED = {  # what each layer may import, besides itself
    "perception": (),
    "maps": ("perception",),
    "drivers": ("perception", *FILE_BOUNDARY),
    "behaviours": ("maps", "perception", "drivers.interfaces"),
    "missions": ("behaviours", "maps", "drivers", "perception"),
    "experiments": ("missions", "behaviours", "maps", "drivers", "perception"),
}
MAX_LINES = 600


def project_modules() -> dict[str, Path]:
    """Dotted module name -> file, for every module of the project's packages."""
    modules = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return modules


def _imported_names(module: str, path: Path) -> set[str]:
    """Every dotted name an import statement of the module names (relative imports resolved)."""
    names: set[str] = set()
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package
                for _ in range(node.level - 1):
                    anchor = anchor.rpartition(".")[0]
                base = f"{anchor}.{base}" if base else anchor
            names.add(base)
            names.update(f"{base}.{alias.name}" for alias in node.names)
    return names


def import_graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports (a name resolves to its longest known module)."""
    modules = project_modules()

    def resolve(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    graph = {}
    for module, path in modules.items():
        targets = {resolve(name) for name in _imported_names(module, path)}
        graph[module] = {t for t in targets if t is not None and t != module}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module."""
    names = sorted(graph)
    index = {name: i for i, name in enumerate(names)}
    pairs = [(index[a], index[b]) for a in names for b in graph[a]]
    rows, cols = (list(x) for x in zip(*pairs, strict=True)) if pairs else ([], [])
    adjacency = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(names), len(names)))
    count, labels = connected_components(adjacency, directed=True, connection="strong")
    components = [[names[i] for i in np.flatnonzero(labels == k)] for k in range(count)]
    return [c for c in components if len(c) > 1]


def _within(name: str, prefixes: tuple[str, ...]) -> bool:
    return any(name == p or name.startswith(p + ".") for p in prefixes)


def layer_violations(graph: dict[str, set[str]]) -> list[str]:
    problems = []
    for module, targets in sorted(graph.items()):
        layer = module.split(".")[0]
        allowed = (layer, *ALLOWED[layer])
        problems += [f"{module} -> {t}" for t in sorted(targets) if not _within(t, allowed)]
    return problems


def test_no_import_cycle_between_modules():
    assert cycles(import_graph()) == []


def test_imports_point_down_the_layers():
    assert layer_violations(import_graph()) == []


def test_no_module_is_over_600_lines():
    long = {str(p.relative_to(ROOT)): n for p in project_modules().values()
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert long == {}


def test_the_checks_see_a_lazy_loop_and_a_layer_breach():
    """The checker itself: a loop through a function-level import, and perception reaching up."""
    graph = {"maps.a": {"maps.b"}, "maps.b": {"maps.a"}, "perception.x": {"behaviours.y"}, "behaviours.y": set()}
    assert cycles(graph) == [["maps.a", "maps.b"]]
    assert layer_violations(graph) == ["perception.x -> behaviours.y"]
