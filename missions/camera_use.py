"""Which cameras a mission reads, from its data flow: a mission without ``cameras:`` grabs those.

Grabbing a camera costs a frame's transfer on a robot and a rendering in the simulator, every
tick; the square mission of the README grabbed the simulator's five cameras it never looked at
(``bearings bench run``: ``cameras_wall_ratio``). Frames reach nodes through the keys the
data-gathering branch writes (``/perception/frames``, ``/perception/frame``), so:

- no node reads those keys: the mission grabs no camera;
- every node that reads them names its camera in a port declared ``camera=True``
  (``Perceive.camera``): the mission grabs the cameras named, in the order the nodes name them;
- a node reads them without naming a camera that way (a plugin, ``Perceive`` with the empty
  name "the first camera"): the mission grabs every camera, as before.

A mission's own ``cameras:`` list always wins (it may list more, for the recording).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from behaviours.ports import Key, Ref
from behaviours.registry import NodeType
from behaviours.sense import GrabFrames
from missions.language import MissionSpec, NodeSpec

FRAME_KEYS = frozenset(port.key for port in NodeType.of(GrabFrames).outputs)
"""The keys the data-gathering branch writes frames to."""

EVERY_CAMERA = None
"""What :func:`cameras_read` returns when the cameras read cannot be told: grab them all."""


def cameras_read(mission: MissionSpec) -> tuple[str, ...] | None:
    """The cameras the mission's nodes read frames of, in order; ``None``: every camera."""
    names: list[str] = []
    for spec in _nodes(mission):
        node_type = mission.registry.lookup(spec.type)
        if node_type is None or not any(_reads_frames(port.type, spec.inputs.get(port.name))
                                        for port in node_type.inputs):
            continue
        named = [spec.inputs.get(port.name) for port in node_type.inputs if port.camera]
        if not named or not all(isinstance(name, str) and name for name in named):
            return EVERY_CAMERA
        names.extend(str(name) for name in named)
    return tuple(dict.fromkeys(names))


def _nodes(mission: MissionSpec) -> Iterator[NodeSpec]:
    for root in (*mission.sense, mission.tree):
        yield from root.walk()


def _reads_frames(port_type: Any, value: Any) -> bool:
    if isinstance(value, Ref):
        return value.base in FRAME_KEYS
    return port_type is Key and isinstance(value, str) and Ref(value).base in FRAME_KEYS
