"""The mission language: inputs, references, includes with their own inputs, plugins, schema."""

from __future__ import annotations

import json
import sys
import textwrap

import jsonschema
import pytest

from behaviours import registry
from behaviours.ports import Ref
from maps.store import InputError, load_yaml
from missions.cli import main
from missions.loader import LIBRARY, load_mission
from missions.schema import mission_schema


def test_inputs_substitute_with_their_type_and_into_text(write_mission):
    path = write_mission("""
        inputs:
          side: {type: float, default: 1.5, unit: m}
          label: corner
        tree:
          Sequence:
            name: "square of ${side} m at ${label}"
            children:
              - Drive: {distance: "${side}"}
    """)
    mission = load_mission(path)
    assert mission.tree.children[0].inputs["distance"] == 1.5
    assert mission.values == {"side": 1.5, "label": "corner"}
    assert load_mission(path, overrides={"side": "3"}).tree.children[0].inputs["distance"] == 3.0


def test_references_are_kept_for_tick_time(write_mission):
    path = write_mission("""
        inputs: {goal_x: 1.5}
        tree:
          Sequence:
            children:
              - DriveTo: {x: "{/mission/goal_x}", y: 0.5}
              - CheckBlackboard: {key: /robot/odometry.x, op: ">", value: 0.2}
    """)
    drive_to, check = load_mission(path).tree.children
    assert drive_to.inputs["x"] == Ref("/mission/goal_x")
    assert check.inputs == {"key": "/robot/odometry.x", "op": ">", "value": 0.2}


def test_include_with_its_own_inputs_and_name(write_mission, tmp_path):
    write_mission("""
        inputs:
          distance: {type: float}
          speed: 0.2
        tree:
          Drive: {distance: "${distance}", speed: "${speed}"}
    """, name="leg.yaml")
    path = write_mission("""
        inputs: {side: 2.0}
        tree:
          Sequence:
            children:
              - include: leg.yaml
                name: first leg
                inputs: {distance: "${side}"}
              - include: leg.yaml
                inputs: {distance: 1, speed: 0.5}
    """)
    mission = load_mission(path)
    first, second = mission.tree.children
    assert (first.name, first.inputs["distance"], first.inputs["speed"]) == ("first leg", 2.0, 0.2)
    assert (second.inputs["distance"], second.inputs["speed"]) == (1.0, 0.5)
    assert first.included_from == str((tmp_path / "leg.yaml").resolve())
    assert len(mission.files) == 2


def test_included_required_input_must_be_given(write_mission):
    write_mission("inputs: {d: {type: float}}\ntree: {Drive: {distance: '${d}'}}\n", name="leg.yaml")
    path = write_mission("tree:\n  include: leg.yaml\n")
    with pytest.raises(InputError) as info:
        load_mission(path)
    assert "input 'd' is required (the include's inputs: do not give it)" in str(info.value)


def test_include_search_path_and_environment(write_mission, tmp_path, monkeypatch):
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "park.yaml").write_text("tree: Stop\n")
    path = write_mission("tree:\n  include: park.yaml\n")
    assert load_mission(path, search_path=[lib]).tree.type == "Stop"
    monkeypatch.setenv("BEARINGS_PATH", str(lib))
    assert load_mission(path).tree.type == "Stop"


def test_shipped_library_is_on_the_include_path(write_mission):
    path = write_mission("tree:\n  include: square.yaml\n  inputs: {side: 0.5}\n")
    mission = load_mission(path)
    assert mission.tree.name == "square"


def test_plugin_file_registers_a_behaviour(write_mission, tmp_path):
    (tmp_path / "beep.py").write_text(textwrap.dedent("""
        from py_trees.common import Status
        from behaviours.base import BearingsBehaviour
        from behaviours.ports import InputPort
        from behaviours.registry import register

        @register
        class Beep(BearingsBehaviour):
            '''Make a noise (a test plugin).'''
            PORTS = (InputPort("times", int, 1, doc="how often"),)

            def update(self):
                return Status.SUCCESS
    """))
    path = write_mission("""
        plugins: [./beep.py]
        tree:
          Beep: {times: 3}
    """)
    mission = load_mission(path)
    assert mission.tree.inputs == {"times": 3}
    assert mission.registry.lookup("Beep").doc == "Make a noise (a test plugin)."


def test_a_plugin_stays_with_its_mission(write_mission, tmp_path):
    (tmp_path / "honk.py").write_text(textwrap.dedent("""
        from py_trees.common import Status
        from behaviours.base import BearingsBehaviour
        from behaviours.registry import register

        @register
        class Honk(BearingsBehaviour):
            '''Honk (a test plugin).'''
            def update(self):
                return Status.SUCCESS
    """))
    with_plugin = write_mission("plugins: [honk.py]\ntree: Honk\n", name="a.yaml")
    without = write_mission("tree: Honk\n", name="b.yaml")
    assert load_mission(with_plugin).tree.type == "Honk"
    with pytest.raises(InputError, match="unknown node type 'Honk'"):
        load_mission(without)  # loaded in the same process, after the first: no leak
    assert "Honk" not in registry.Registry.default()


def test_entry_point_group_registers_behaviours(tmp_path, monkeypatch, write_mission):
    package = tmp_path / "site"
    (package / "acme_bt").mkdir(parents=True)
    (package / "acme_bt" / "__init__.py").write_text(textwrap.dedent("""
        from py_trees.common import Status
        from behaviours.base import BearingsBehaviour
        from behaviours.registry import register

        @register
        class AcmeDock(BearingsBehaviour):
            '''Dock at the Acme charger.'''
            def update(self):
                return Status.SUCCESS
    """))
    info = package / "acme_bt-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: acme-bt\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[bearings.behaviours]\nacme = acme_bt\n")
    monkeypatch.syspath_prepend(str(package))
    registry._with_entry_points.cache_clear()
    try:
        mission = load_mission(write_mission("tree: AcmeDock\n"))
        assert mission.tree.type == "AcmeDock"
    finally:
        sys.modules.pop("acme_bt", None)
        registry._with_entry_points.cache_clear()


def test_yaml_12_floats(write_mission):
    path = write_mission("tree:\n  Wait: {duration: 1e-3}\n")
    assert load_mission(path).tree.inputs["duration"] == pytest.approx(0.001)


def test_schema_accepts_every_shipped_mission_and_rejects_typos():
    schema = mission_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)
    shipped = sorted(LIBRARY.glob("*.yaml"))
    assert shipped
    for path in shipped:
        errors = list(validator.iter_errors(_plain(load_yaml(path))))
        assert not errors, (path, errors[0].message)
    assert list(validator.iter_errors({"tree": {"Drive": {"distanse": 1}}}))
    assert not list(validator.iter_errors({"tree": {"Drive": {"distance": "{/mission/d}"}}}))


def test_schema_lists_every_node_type_with_its_ports():
    defs = mission_schema()["$defs"]
    drive = defs["type_Drive"]["properties"]["Drive"]
    assert drive["required"] == ["distance"]
    assert drive["properties"]["speed"]["default"] == 0.3
    assert "[m/s]" in drive["properties"]["speed"]["description"]
    for name in ("Sequence", "Selector", "Parallel", "Timeout", "Retry", "Repeat", "Inverter", "ForceSuccess",
                 "ForceFailure", "OneShot", "RateController", "RecoveryNode", "Guard", "Wait", "Rotate",
                 "DriveTo", "Stop"):
        assert f"type_{name}" in defs


def _plain(value):
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return value


def test_world_and_profile_schemas_come_from_the_declared_models(capsys):
    from drivers.sim.world import shipped_worlds
    from missions.profiles import PROFILES

    assert main(["schema", "--world"]) == 0
    world_schema = json.loads(capsys.readouterr().out)
    jsonschema.Draft202012Validator.check_schema(world_schema)
    validator = jsonschema.Draft202012Validator(world_schema)
    for path in shipped_worlds().values():
        assert not list(validator.iter_errors(_plain(load_yaml(path)))), path
    assert list(validator.iter_errors({"walls": [{"points": [[0, 0], [1, 0]], "height": 500}]}))
    assert world_schema["properties"]["ceiling"]["anyOf"][0]["unit"] == "m"
    assert main(["schema", "--profile"]) == 0
    profile_schema = json.loads(capsys.readouterr().out)
    jsonschema.Draft202012Validator.check_schema(profile_schema)
    validator = jsonschema.Draft202012Validator(profile_schema)
    for path in PROFILES.glob("*.yaml"):
        assert not list(validator.iter_errors(_plain(load_yaml(path)))), path
    assert list(validator.iter_errors({"base": {"driver": "pioneer"}, "wheels": 4}))
