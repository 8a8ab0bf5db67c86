"""The roadmap node types are built-ins, declared fully, and cheap to load."""

from __future__ import annotations

import subprocess
import sys

from behaviours.ports import InputPort
from behaviours.registry import Registry

ROADMAP = {"LoadTargetImages", "LoadRoadmap", "RecordTarget", "AllTargetsFound", "CalibrateTurns", "CorrectOdometry",
           "RoomEstimationDodecagon", "CoverageScoring", "GoToPose", "ReturnToReference", "ScanForTargets",
           "TargetHoming", "BuildGraph", "NavigateToTarget"}


def test_every_roadmap_node_type_is_a_builtin_with_documented_ports():
    types = {t.name: t for t in Registry.builtin().all_types() if t.module.startswith("behaviours.roadmap.")}
    assert set(types) == ROADMAP
    for node_type in types.values():
        assert node_type.doc, node_type.name
        for port in (*node_type.inputs, *node_type.outputs):
            assert port.doc, f"{node_type.name}.{port.name}"
            if isinstance(port, InputPort) and port.type in (float, list[float]) and port.name not in ("turn_scale",):
                assert port.unit or port.name in ("fragment_cost",), f"{node_type.name}.{port.name} has no unit"


def test_loading_the_registry_does_not_import_scipy_signal():
    """Every mission load builds the registry: the coverage scoring's FFT convolution is imported when used."""
    code = "import sys, behaviours.registry as r; r.Registry.builtin(); print('scipy.signal' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
