"""py_trees behaviours for bearings missions.

Behaviours read and write the blackboards and never touch hardware: the runner turns
``/robot/command`` and ``/ptu/command`` into driver calls after each tick. Node types are
declared once (:mod:`behaviours.registry`, :mod:`behaviours.ports`) and collected into a
:class:`~behaviours.registry.Registry` per mission load.
"""
