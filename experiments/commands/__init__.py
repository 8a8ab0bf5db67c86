"""The ``bearings`` sub-commands of the experiments: ``sweep``, ``eval`` and ``bench``.

Each module exposes ``register(subparsers)`` like the built-in commands of
:mod:`missions.commands`; ``missions.cli`` finds them through their entry points (group
``bearings.commands`` in ``pyproject.toml``), never by name.
"""
