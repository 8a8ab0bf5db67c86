"""One module per ``bearings`` sub-command; each exposes ``register(subparsers)``.

A command module sets ``func`` on its parser: ``func(args) -> int`` returns the exit code.
Add a module here and list it in :data:`COMMANDS` to add a sub-command.
"""

COMMANDS = (
    "missions.commands.run",
    "missions.commands.validate",
    "missions.commands.show",
    "missions.commands.import_",
    "missions.commands.schema",
    "missions.commands.bench",
    "missions.commands.sim",
    "missions.commands.calibrate",
    "missions.commands.doctor",
    "missions.commands.map",
    "missions.commands.sweep",
    "missions.commands.eval",
)
