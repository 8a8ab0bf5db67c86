"""One module per ``bearings`` sub-command; each exposes ``register(subparsers)``.

A command module sets ``func`` on its parser: ``func(args) -> int`` returns the exit code.
Add a module here and list it in :data:`COMMANDS` to add a built-in sub-command. Commands from
outside ``missions`` (``experiments``: sweep, eval, bench; a plugin package) are entry points of
the group :data:`ENTRY_POINT_GROUP` naming such a module, declared in their ``pyproject.toml``::

    [project.entry-points."bearings.commands"]
    sweep = "experiments.commands.sweep"
"""

COMMANDS = (
    "missions.commands.run",
    "missions.commands.validate",
    "missions.commands.show",
    "missions.commands.import_",
    "missions.commands.schema",
    "missions.commands.sim",
    "missions.commands.calibrate",
    "missions.commands.doctor",
    "missions.commands.map",
    "missions.commands.plot",
    "missions.commands.missions_list",
    "missions.commands.log",
)

ENTRY_POINT_GROUP = "bearings.commands"
