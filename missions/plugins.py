"""Plugins: the Python modules a mission lists under ``plugins:``, whose node types it may use.

A plugin is either an installed module named explicitly (``my_robot.behaviours``) or a ``.py``
file inside the mission's own folder (``plugins: [beep.py]``); nothing else is imported, and a
plugin's node types go into the registry of that one mission load. A ``.py`` plugin is imported
once per process under a module name unique to its absolute path, so two ``beep.py`` files in
two folders never clash. Importing a plugin runs its code: ``bearings validate`` and ``bearings
show`` do so too, because a plugin's node types are what the mission is checked against.
A plugin that fails or exits while importing is reported as an input error at its line.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import re
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

from behaviours.registry import Registry

MODULE = re.compile(r"^[A-Za-z_]\w*(\.[A-Za-z_]\w*)*$")


class PluginError(Exception):
    """A plugin that cannot be used; the message says why (one line)."""


def load_plugin(spec: str, folder: Path, registry: Registry) -> str:
    """Import one plugin and add its node types to ``registry``; the plugin's canonical name."""
    if spec.endswith(".py"):
        path = _plugin_file(spec, folder)
        module = _import_file(spec, path)
        name = str(path)
    elif MODULE.match(spec):
        module = _import(spec, lambda: importlib.import_module(spec))
        name = spec
    else:
        raise PluginError(f"plugin {spec!r} is neither a module name (a.b.c) nor a .py file in the mission's folder")
    try:
        added = registry.add_module(module)
    except ValueError as exc:
        raise PluginError(f"plugin {spec!r}: {exc}") from None
    if not added:
        raise PluginError(f"plugin {spec!r} defines no node types (mark them with @register from "
                          "behaviours.registry)")
    return name


def _plugin_file(spec: str, folder: Path) -> Path:
    path = (folder / spec).resolve()
    try:
        path.relative_to(folder.resolve())
    except ValueError:
        raise PluginError(f"plugin file {spec!r} is outside the mission's folder; put it next to the mission or "
                          "install it as a module") from None
    if not path.is_file():
        raise PluginError(f"plugin file {spec!r} not found next to the mission")
    return path


def _import_file(spec: str, path: Path) -> ModuleType:
    stem = re.sub(r"\W", "_", path.stem)
    name = f"bearings_plugin_{stem}_{hashlib.sha1(str(path).encode()).hexdigest()[:12]}"
    if name in sys.modules:
        return sys.modules[name]
    module_spec = importlib.util.spec_from_file_location(name, path)
    if module_spec is None or module_spec.loader is None:
        raise PluginError(f"cannot load plugin file {spec!r}")
    module = importlib.util.module_from_spec(module_spec)
    sys.modules[name] = module
    loader = module_spec.loader

    def execute() -> ModuleType:
        try:
            loader.exec_module(module)
        except BaseException:
            del sys.modules[name]
            raise
        return module

    return _import(spec, execute)


def _import(spec: str, run: Callable[[], ModuleType]) -> ModuleType:
    try:
        return run()
    except ModuleNotFoundError as exc:
        raise PluginError(f"plugin {spec!r} cannot be imported: no module named {exc.name!r}") from None
    except SystemExit as exc:
        raise PluginError(f"plugin {spec!r} exited while being imported (exit code {exc.code!r})") from None
    except Exception as exc:  # noqa: BLE001 - a broken plugin is the user's input error
        raise PluginError(f"plugin {spec!r} failed to import: {type(exc).__name__}: {exc}") from None
