"""Turn a validated :class:`~missions.language.MissionSpec` into a py_trees tree.

The root is the py_trees_ros idiom: a parallel of the data-gathering branch (driver readings,
then the mission's own ``sense:`` nodes) and the mission's task tree. The root succeeds when the
task succeeds and fails as soon as either branch fails.
"""

from __future__ import annotations

import py_trees
from py_trees.common import ParallelPolicy

from behaviours.registry import Registry
from behaviours.sense import GrabFrames, ReadOdometry, ReadPanTilt, ReadRanges
from maps.store import OutputFolders
from missions.language import MissionSpec, NodeSpec
from missions.outputs import resolved_ports

ROOT_NAME = "bearings"
SENSE_NAME = "sense"


def build_node(spec: NodeSpec, registry: Registry, folders: OutputFolders | None = None
               ) -> py_trees.behaviour.Behaviour:
    """The py_trees behaviour (with its subtree) for one validated node; with ``folders``, the
    ports naming files get absolute paths (:mod:`missions.outputs`)."""
    node_type = registry.lookup(spec.type)
    if node_type is None:  # the loader checked this; a spec built by hand may not have been
        raise ValueError(f"unknown node type {spec.type!r}")
    children = [build_node(child, registry, folders) for child in spec.children]
    return node_type.build(name=spec.name, children=children, ports=resolved_ports(spec, node_type, folders))


def build_sense(mission: MissionSpec) -> py_trees.behaviour.Behaviour:
    """The data-gathering branch: odometry, range sensors, pan-tilt, cameras, then the mission's ``sense:``."""
    readings = [ReadOdometry(), ReadRanges(), ReadPanTilt(), GrabFrames(cameras=mission.cameras)]
    nodes = [*readings, *(build_node(s, mission.registry, mission.folders) for s in mission.sense)]
    return py_trees.composites.Sequence(name=SENSE_NAME, memory=False, children=nodes)


def build_root(mission: MissionSpec) -> tuple[py_trees.behaviour.Behaviour, py_trees.behaviour.Behaviour]:
    """(root, task): the root parallel of sense and task, and the mission's task tree."""
    task = build_node(mission.tree, mission.registry, mission.folders)
    root = py_trees.composites.Parallel(
        name=ROOT_NAME,
        policy=ParallelPolicy.SuccessOnSelected(children=[task], synchronise=False),
        children=[build_sense(mission), task],
    )
    return root, task
