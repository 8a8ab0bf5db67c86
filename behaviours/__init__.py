"""py_trees behaviours for bearings missions.

Behaviours read and write the blackboards and never touch hardware: the runner turns
``/robot/command`` and ``/ptu/command`` into driver calls after each tick. Importing this package
registers every built-in node type with :mod:`behaviours.registry`.
"""

from behaviours import builtin as _builtin  # noqa: F401  (registers the node types)
