"""The roadmap behaviours (docs/design.md, method 2): learn a roadmap between a few target
images and navigate it. Thin over :mod:`maps.room`, :mod:`maps.coverage`, :mod:`maps.roadmap`,
:mod:`maps.planning`, :mod:`perception.planar` and :mod:`perception.stereo`.

=====================  ==================================================================
module                 node types
=====================  ==================================================================
``targets``            ``LoadTargetImages``, ``LoadRoadmap``, ``RecordTarget``, ``AllTargetsFound``
``room``               ``RoomEstimationDodecagon``
``coverage``           ``CoverageScoring``
``travel``             ``GoToPose``, ``ReturnToReference``
``scan``               ``ScanForTargets``
``homing``             ``TargetHoming`` (and the homing routine the others reuse)
``graph``              ``BuildGraph``
``navigate``           ``NavigateToTarget``
=====================  ==================================================================

``values`` holds the values these nodes hand each other through their ports, ``vision`` the
image side (upright SIFT, matching, planar homing of one image against a target),
``routine`` the base class of the long-running ones (a coroutine advanced once per tick that
drives through the standard motion nodes), ``display`` the report figures and the drawings.
docs/roadmap.md is the overview.
"""
