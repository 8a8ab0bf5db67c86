"""Every malformed-input case is reported at load time as file:line:col with a clear message."""

from __future__ import annotations

from pathlib import Path

import pytest

from maps.store import InputError
from missions.loader import load_mission


def problems(path: Path, **kwargs) -> list[tuple[int, str]]:
    with pytest.raises(InputError) as info:
        load_mission(path, **kwargs)
    for d in info.value.diagnostics:
        assert d.file.endswith(".yaml") or d.file == "--set", d
    return [(d.line, d.message) for d in info.value.diagnostics]


def test_unknown_node_type_names_the_line_and_suggests(write_mission):
    path = write_mission("""
        tree:
          Sequence:
            children:
              - Drvie: {distance: 1.0}
    """)
    [(line, message)] = problems(path)
    assert line == 4
    assert "unknown node type 'Drvie'" in message and "did you mean 'Drive'" in message


def test_unknown_parameter(write_mission):
    path = write_mission("""
        tree:
          Drive: {distanse: 1.0}
    """)
    found = problems(path)
    assert (2, "Drive has no port 'distanse'; did you mean 'distance'? (it takes: distance, speed, "
               "tolerance, odometry, stalled, safety, held_timeout, command)") in found
    assert any("needs input 'distance'" in m for _, m in found)


def test_missing_required_parameter(write_mission):
    path = write_mission("""
        tree:
          Wait: {}
    """)
    [(line, message)] = problems(path)
    assert line == 2 and "Wait needs input 'duration'" in message


@pytest.mark.parametrize(
    ("value", "expected"),
    [("fast", "expects a number in m/s, got 'fast'"), ("true", "expects a number in m/s, got True"),
     ("[1, 2]", "expects a number in m/s, got a list of 2"), ("5.0", "must be <= 1.2 in m/s, got 5")],
)
def test_wrong_type_or_range(write_mission, value, expected):
    path = write_mission(f"""
        tree:
          Drive:
            distance: 1.0
            speed: {value}
    """)
    [(line, message)] = problems(path)
    assert line == 4
    assert message == f"Drive.speed {expected}"


def test_bad_blackboard_reference(write_mission):
    path = write_mission("""
        tree:
          Sequence:
            children:
              - Drive: {distance: "{/map/nowhere}"}
              - Wait: {duration: "{/robot/odometry}"}
    """)
    found = problems(path)
    assert found == [
        (4, "Drive.distance reads /map/nowhere, which nothing writes (written keys: /perception/frame, "
            "/perception/frames, /ptu/state, /robot/command, /robot/footprint, /robot/odometry, /robot/ranges, "
            "/robot/safety, /robot/stalled)"),
        (5, "Wait.duration is float, but /robot/odometry holds Pose2D (written by the data-gathering branch)"),
    ]
    outside = write_mission('tree: {Drive: {distance: "{/elsewhere/x}"}}\n', name="outside.yaml")
    assert problems(outside) == [(1, "Drive.distance: '/elsewhere/x' is outside the blackboard namespaces "
                                     "/robot, /ptu, /perception, /map, /mission")]


def test_literal_and_reference_are_distinct(write_mission):
    path = write_mission("""
        inputs: {side: 1.0}
        tree:
          Sequence:
            children:
              - Drive: {distance: "{/mission/side}"}
              - Drive: {distance: {/mission/side}}
    """)
    mission = load_mission(path)
    first, second = mission.tree.children
    assert str(first.inputs["distance"]) == "{/mission/side}"
    assert first.inputs["distance"] == second.inputs["distance"]


def test_unknown_input_in_substitution_and_in_set(write_mission):
    path = write_mission("""
        inputs:
          side: 1.0
        tree:
          Drive: {distance: "${sied}"}
    """)
    found = problems(path, overrides={"speeed": "2"})
    assert (4, "Drive.distance: unknown input ${sied}; did you mean 'side'?") in found
    assert any(line == 0 and "unknown input 'speeed'" in m for line, m in found)


def test_set_value_is_type_checked(write_mission):
    path = write_mission("""
        inputs:
          side: {type: float, default: 1.0}
        tree:
          Drive: {distance: "${side}"}
    """)
    [(_, message)] = problems(path, overrides={"side": "long"})
    assert message == "input 'side' expects a number, got 'long'"
    assert load_mission(path, overrides={"side": "2.5"}).tree.inputs["distance"] == 2.5


def test_include_cycle(write_mission):
    write_mission("tree:\n  include: b.yaml\n", name="a.yaml")
    write_mission("tree:\n  include: a.yaml\n", name="b.yaml")
    path = write_mission("tree:\n  include: a.yaml\n", name="top.yaml")
    found = problems(path)
    assert any("include cycle: a.yaml -> b.yaml -> a.yaml" in m for _, m in found)


def test_self_include_is_a_cycle(write_mission):
    path = write_mission("tree:\n  include: self.yaml\n", name="self.yaml")
    [(line, message)] = problems(path)
    assert line == 2 and message == "include cycle: self.yaml -> self.yaml"


def test_missing_include(write_mission):
    path = write_mission("tree:\n  include: nowhere.yaml\n")
    [(line, message)] = problems(path)
    assert line == 2 and message.startswith("cannot find included mission 'nowhere.yaml'")


def test_malformed_yaml_reports_position(write_mission):
    path = write_mission("tree:\n  Sequence:\n    children: [Stop\n")
    [(line, message)] = problems(path)
    assert line == 4 and message.startswith("malformed YAML")


def test_empty_file(write_mission):
    path = write_mission("   \n# only a comment\n")
    [(line, message)] = problems(path)
    assert (line, message) == (1, "the file is empty")


def test_non_utf8_bytes(tmp_path):
    path = tmp_path / "latin1.yaml"
    path.write_bytes(b"tree:\n  Wait: {duration: 1.0}  # caf\xe9\n")
    [(line, message)] = problems(path)
    assert (line, message) == (2, "the file is not valid UTF-8 text")


def test_missing_file(tmp_path):
    [(_, message)] = problems(tmp_path / "absent.yaml")
    assert message == "no such file"


def test_duplicate_keys(write_mission):
    path = write_mission("""
        tree:
          Drive: {distance: 1.0, distance: 2.0}
    """)
    [(line, message)] = problems(path)
    assert line == 2 and message == "duplicate key 'distance'"


def test_all_errors_of_all_files_in_one_pass(write_mission):
    write_mission("""
        inputs: {speed: 0.2}
        tree:
          Drive: {distance: 1.0, speed: "${speed}", colour: red}
    """, name="sub.yaml")
    path = write_mission("""
        mission: many
        flavour: strawberry
        tree:
          Sequence:
            children:
              - Wiat: {duration: 1}
              - Rotate: {angle: left}
              - include: sub.yaml
                inputs: {speed: 0.5, sped: 1}
    """)
    with pytest.raises(InputError) as info:
        load_mission(path)
    located = {(Path(d.file).name, d.line) for d in info.value.diagnostics}
    assert located == {("mission.yaml", 2), ("mission.yaml", 6), ("mission.yaml", 7), ("mission.yaml", 9),
                       ("sub.yaml", 3)}


def test_node_shape_errors(write_mission):
    path = write_mission("""
        tree:
          Sequence:
            children:
              - Drive: 1.0
              - 42
              - {Drive: {distance: 1}, Rotate: {angle: 2}}
              - Inverter: {children: [Stop]}
              - Stop: {child: Stop}
              - Sequence: {}
    """)
    found = dict(problems(path))
    assert found[4] == "Drive: ports are a mapping 'name: value', found 1.0"
    assert found[5] == "expected a node like 'Drive: {distance: 1.0}', found 42"
    assert found[6].startswith("a node is one 'TypeName: {ports}' entry")
    assert found[7] == "Inverter decorates one node: use 'child:'"
    assert found[8] == "Stop is a leaf and takes no child"
    assert found[9] == "Sequence needs 'children:', a list of nodes"


def test_recovery_node_needs_two_children(write_mission):
    path = write_mission("""
        tree:
          RecoveryNode:
            children: [Stop]
    """)
    [(line, message)] = problems(path)
    assert line == 3 and message == "RecoveryNode takes exactly 2 children, got 1"


def test_sensed_keys_keep_a_single_writer(write_mission):
    path = write_mission("""
        sense:
          - Perceive: {camera: panorama}
        tree:
          Sequence:
            children:
              - Perceive: {camera: front}
              - Stop: {command: "{/robot/odometry}"}
    """)
    found = problems(path)
    assert (6, "Perceive writes /perception/observation, which Perceive writes too: a sensed key has one writer "
               "(remap this output to a key of its own, e.g. {/perception/observation_2})") in found
    assert any(line == 7 and "Stop writes /robot/odometry, which the data-gathering branch writes too" in m
               for line, m in found)
    assert any(line == 7 and "Stop writes VelocityCommand to /robot/odometry, where the data-gathering branch "
               "writes Pose2D" in m for line, m in found)
    ok = write_mission("""
        sense:
          - Perceive: {camera: panorama}
          - Perceive: {camera: front, observation: "{/perception/front}"}
        tree: Stop
    """, name="ok.yaml")
    assert [n.outputs["observation"] for n in load_mission(ok).sense] == ["/perception/observation",
                                                                         "/perception/front"]


def test_unknown_plugin_module_and_file(write_mission):
    path = write_mission("""
        plugins: [no_such_module_xyz, ./missing.py, "os; rm -rf /"]
        tree: Stop
    """)
    found = problems(path)
    assert (1, "plugin 'no_such_module_xyz' cannot be imported: no module named 'no_such_module_xyz'") in found
    assert (1, "plugin file './missing.py' not found next to the mission") in found
    assert (1, "plugin 'os; rm -rf /' is neither a module name (a.b.c) nor a .py file in the mission's "
               "folder") in found


def test_top_level_shape(write_mission):
    assert problems(write_mission("- just\n- a list\n")) == [
        (1, "a mission file is a mapping with at least a 'tree:' entry")]
    assert problems(write_mission("mission: nothing\n", name="no_tree.yaml")) == [
        (1, "the file needs 'tree' (the root node of the task tree)")]


def test_unsafe_yaml_tags_are_rejected(write_mission):
    path = write_mission("""
        tree: !!python/object/apply:os.system ["echo pwned"]
    """)
    [(line, message)] = problems(path)
    assert line == 1 and "malformed YAML" in message and "python/object/apply" in message


def test_alias_bomb_is_stopped(write_mission):
    lines = ['a0: &a0 ["x", "x", "x", "x", "x", "x", "x", "x", "x", "x"]']
    for i in range(1, 9):
        refs = ", ".join([f"*a{i - 1}"] * 10)
        lines.append(f"a{i}: &a{i} [{refs}]")
    path = write_mission("\n".join(lines) + "\ntree: Stop\n")
    [(_, message)] = problems(path)
    assert "more than" in message and "alias" in message
