"""``bearings import``: BehaviorTree.CPP v4 files as Groot2 saves them (subtrees, remapping, a
TreeNodesModel) become missions that validate; everything with no bearings equivalent is
reported at its line, and nothing is written then."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from maps.store import InputError
from missions.cli import main
from missions.importer import import_btcpp
from missions.loader import LIBRARY, load_mission
from tests.fuzzing import examples, load_or_diagnose

GROOT2_FILE = """\
<?xml version="1.0" encoding="UTF-8"?>
<root BTCPP_format="4" main_tree_to_execute="Patrol">
  <BehaviorTree ID="Patrol">
    <Sequence>
      <SubTree ID="GoTo" name="first corner" gx="2.0" gy="0.5" cmd="{@robot__command}"/>
      <SubTree ID="GoTo" gx="0.0" cmd="{@robot__command}" _uid="7"/>
      <ReactiveFallback name="unless stalled">
        <ScriptCondition code="false == @robot__stalled"/>
        <RetryUntilSuccessful num_attempts="2">
          <Action ID="Drive" distance="-0.3" speed="0.2"/>
        </RetryUntilSuccessful>
      </ReactiveFallback>
      <SubTree ID="Pause" _autoremap="true"/>
      <Parallel success_count="-1" failure_count="1">
        <KeepRunningUntilFailure><IsStalled stalled="{robot__stalled}"/></KeepRunningUntilFailure>
        <RunOnce then_skip="false"><AlwaysSuccess/></RunOnce>
      </Parallel>
      <Stop/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="GoTo">
    <Precondition if="@robot__odometry___x &lt; 10" else="FAILURE">
      <DriveTo x="{gx}" y="{gy}" command="{cmd}"/>
    </Precondition>
  </BehaviorTree>
  <BehaviorTree ID="Pause">
    <Timeout msec="2500">
      <Sleep msec="500"/>
    </Timeout>
  </BehaviorTree>
  <TreeNodesModel>
    <SubTree ID="GoTo">
      <input_port name="gx"/>
      <input_port name="gy" default="0.0"/>
      <output_port name="cmd" default="{@robot__command}"/>
    </SubTree>
    <Action ID="Drive">
      <input_port name="distance" type="double"/>
    </Action>
    <Action ID="PickUp"/>
  </TreeNodesModel>
</root>
"""

EXPECTED = """
    tree:
      Sequence:
        children:
          - Guard:
              name: first corner
              key: /robot/odometry.x
              op: "<"
              value: 10
              child: {DriveTo: {x: 2.0, y: 0.5}}
          - Guard:
              key: /robot/odometry.x
              op: "<"
              value: 10
              child: {DriveTo: {x: 0.0, y: 0.0}}
          - Selector:
              name: unless stalled
              memory: false
              children:
                - CheckBlackboard: {key: /robot/stalled, op: "==", value: false}
                - Retry: {num_attempts: 2, child: {Drive: {distance: -0.3, speed: 0.2}}}
          - Timeout: {duration: 2.5, child: {Wait: {duration: 0.5}}}
          - Parallel:
              children:
                - Repeat: {num_cycles: -1, child: IsStalled}
                - OneShot: {policy: on_completion, child: Success}
          - Stop
"""


def _shape(node):
    return (node.type, node.name, node.inputs, node.outputs, [_shape(c) for c in node.children])


def _write(tmp_path: Path, xml: str, name: str = "tree.xml") -> Path:
    path = tmp_path / name
    path.write_text(xml, encoding="utf-8")
    return path


def _tree(body: str, *, models: str = "", extra: str = "") -> str:
    """A file whose main tree is ``body`` (starting on line 4)."""
    return (f'<?xml version="1.0"?>\n<root BTCPP_format="4" main_tree_to_execute="T">\n  <BehaviorTree ID="T">\n'
            f"{textwrap.indent(textwrap.dedent(body).strip(), '    ')}\n  </BehaviorTree>\n{extra}"
            f"  <TreeNodesModel>{models}</TreeNodesModel>\n</root>\n")


def problems(tmp_path: Path, xml: str) -> list[str]:
    """The import's diagnostics as 'line:col: message' (the file is tree.xml)."""
    path = _write(tmp_path, xml)
    with pytest.raises(InputError) as caught:
        import_btcpp(path)
    prefix = f"{path}:"
    assert all(str(d).startswith(prefix) for d in caught.value.diagnostics), caught.value
    return [str(d).removeprefix(prefix).strip() for d in caught.value.diagnostics]


def test_a_groot2_file_with_subtrees_becomes_the_same_tree_as_the_mission_written_by_hand(tmp_path, write_mission):
    imported = tmp_path / "patrol.yaml"
    imported.write_text(import_btcpp(_write(tmp_path, GROOT2_FILE)), encoding="utf-8")
    mission = load_mission(imported)
    assert mission.name == "Patrol"
    assert _shape(mission.tree) == _shape(load_mission(write_mission(EXPECTED)).tree)


def test_bearings_import_exits_2_with_located_problems_and_writes_nothing(tmp_path, capsys):
    path = _write(tmp_path, _tree('<Sequence>\n  <Dance/>\n  <Drive distanse="1"/>\n</Sequence>'))
    output = tmp_path / "mission.yaml"
    assert main(["import", str(path), "-o", str(output)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[0] == f"{path}:5:7: unknown node type 'Dance'"
    assert err[1].startswith(f"{path}:6:7: Drive has no port 'distanse'; did you mean 'distance'?")
    assert err[-1] == "2 problems found" and not output.exists()
    assert main(["import", str(tmp_path / "missing.xml")]) == 2
    assert main(["import", str(path), "-o", str(tmp_path / "no" / "such" / "folder.yaml")]) == 2
    good = _write(tmp_path, _tree("<Stop/>"), name="good.xml")
    capsys.readouterr()
    assert main(["import", str(good), "-o", str(tmp_path / "no" / "such" / "folder.yaml")]) == 2
    assert "cannot write" in capsys.readouterr().err


@pytest.mark.parametrize(("body", "expected"), [
    ("<IfThenElse><AlwaysSuccess/><AlwaysSuccess/></IfThenElse>",
     "4:5: BehaviorTree.CPP's IfThenElse has no bearings equivalent: bearings has no conditional control node"),
    ("<Action ID='PickUp'/>", "4:5: node type 'PickUp' is declared in the file's TreeNodesModel but bearings"),
    ("<RunOnce><AlwaysSuccess/></RunOnce>", '4:5: RunOnce with then_skip="true" (its default) has no equivalent'),
    ("<Precondition if='@robot__stalled == true' else='SUCCESS'><AlwaysSuccess/></Precondition>",
     "4:5: Precondition else='SUCCESS' has no equivalent: a Guard fails when its condition does not hold"),
    ("<ScriptCondition code='@robot__stalled == true &amp;&amp; @map__x &gt; 1'/>",
     "4:5: ScriptCondition.code: the script '@robot__stalled == true && @map__x > 1' has no bearings equivalent"),
    ("<ScriptCondition code='@robot__stalled == @map__x'/>", "4:5: ScriptCondition.code: the script"),
    ("<Drive distance='{goal_distance}'/>", "4:5: Drive.distance: {goal_distance} is not a bearings blackboard key"),
    ("<Drive distance='1' _skipIf='@robot__stalled'/>", "4:5: _skipIf: scripted pre- and post-conditions have no"),
    ("<Parallel success_count='2'><Stop/><Stop/><Stop/></Parallel>",
     "4:5: Parallel success_count 2 has no equivalent: bearings' Parallel succeeds when all"),
    ("<Parallel failure_count='2'><Stop/><Stop/></Parallel>", "4:5: Parallel failure_count 2 has no equivalent"),
    ("<Timeout msec='{@map__t}'><Stop/></Timeout>", "4:5: Timeout.msec read from the blackboard has no equivalent"),
    ("<Timeout duration='1'><Stop/></Timeout>", "4:5: BehaviorTree.CPP's Timeout has no port 'duration'"),
    ("<Stop><Stop/></Stop>", "4:5: <Stop> (Stop) takes no children (it is a leaf), found 1"),
    ("<Inverter><Stop/><Stop/></Inverter>", "4:5: <Inverter> (Inverter) takes exactly 1 child, found 2"),
    ("<Stop command='robot__command'/>", "4:5: Stop.command is an output: write the blackboard entry it writes, "
     "like {@robot__command}"),
    ("<SubTree ID='Nowhere'/>", "4:5: <SubTree> names tree 'Nowhere', which the file does not hold"),
])  # fmt: skip
def test_what_bearings_has_no_equivalent_for_is_reported_at_its_line(tmp_path, body, expected):
    found = problems(tmp_path, _tree(body, models="<Action ID='PickUp'/>"))
    assert found[0].startswith(expected), found


def test_problems_the_mission_loader_finds_are_reported_at_the_xml_node(tmp_path):
    found = problems(tmp_path, _tree("""
        <Sequence>
          <Drive distance="abc"/>
          <Rotate angle="90" speed="1000"/>
          <Drive distance="{@map__nowhere}"/>
        </Sequence>"""))
    assert found[0] == "5:7: Drive.distance expects a number in m, got 'abc'"
    assert found[1].startswith("6:7: Rotate.speed must be <= 300 in deg/s")
    assert len(found) == 2  # the data flow is checked once the nodes are valid
    found = problems(tmp_path, _tree('<RetryUntilSuccessful num_attempts="-1"><Stop/></RetryUntilSuccessful>'))
    assert found == ["4:5: <RetryUntilSuccessful> as Retry: Retry.num_attempts must be >= 1, got -1"]
    found = problems(tmp_path, _tree('<Drive distance="{@map__nowhere}"/>'))
    assert len(found) == 1 and found[0].startswith("4:5: Drive.distance reads /map/nowhere, which nothing writes")


def test_subtree_entries_must_reach_the_one_bearings_blackboard(tmp_path):
    sub = '  <BehaviorTree ID="S">\n    <Drive distance="{d}" odometry="{odo}"/>\n  </BehaviorTree>\n'
    found = problems(tmp_path, _tree('<SubTree ID="S" d="1.5"/>', extra=sub))
    assert found == ["7:5: Drive.odometry: blackboard entry 'odo' is local to subtree S (bearings has one "
                     "blackboard: remap it in the <SubTree>, e.g. odo=\"{@map__odo}\", or set _autoremap=\"true\")"]
    path = tmp_path / "ok.yaml"
    path.write_text(import_btcpp(_write(tmp_path, _tree('<SubTree ID="S" d="1.5" odo="{@robot__odometry}"/>',
                                                        extra=sub))))
    assert load_mission(path).tree.inputs["distance"] == 1.5
    cycle = '  <BehaviorTree ID="S">\n    <SubTree ID="T"/>\n  </BehaviorTree>\n'
    assert problems(tmp_path, _tree('<SubTree ID="S"/>', extra=cycle)) == ["7:5: subtree cycle: T -> S -> T"]


def test_a_subtree_bomb_stops_at_the_node_budget(tmp_path):
    levels = ""
    for level in range(5):
        calls = f"<SubTree ID='L{level + 1}'/>" * 10
        levels += f'  <BehaviorTree ID="L{level}">\n    <Sequence>{calls}</Sequence>\n  </BehaviorTree>\n'
    levels += '  <BehaviorTree ID="L5">\n    <Stop/>\n  </BehaviorTree>\n'
    found = problems(tmp_path, _tree('<SubTree ID="L0"/>', extra=levels))
    assert len(found) == 1 and "expands to more than 10000 nodes" in found[0]


@pytest.mark.parametrize(("xml", "expected"), [
    ('<root BTCPP_format="4">\n  <BehaviorTree ID="T">\n    <Stop>\n  </BehaviorTree>\n</root>\n',
     "4:5: malformed XML: mismatched tag"),
    ('<?xml version="1.0"?>\n<!DOCTYPE root [<!ENTITY a "aaaa">]>\n<root/>\n',
     "2:1: a DOCTYPE is not allowed in a BehaviorTree.CPP file (no entities are read)"),
    ('<!DOCTYPE root SYSTEM "file:///etc/passwd">\n<root>&xxe;</root>\n', "1:1: a DOCTYPE is not allowed"),
    ('<root BTCPP_format="3">\n  <BehaviorTree ID="T"><Stop/></BehaviorTree>\n</root>\n',
     "1:1: BTCPP_format '3': bearings reads BehaviorTree.CPP v4 files"),
    ("<tree/>", "1:1: a BehaviorTree.CPP file starts with <root>, not <tree>"),
    ('<root>\n  <BehaviorTree ID="A"><Stop/></BehaviorTree>\n  <BehaviorTree ID="B"><Stop/></BehaviorTree>\n</root>',
     "1:1: say which tree is the mission with main_tree_to_execute (candidates: A, B)"),
    ('<root>\n  <include path="other.xml"/>\n  <BehaviorTree><Stop/></BehaviorTree>\n</root>',
     "2:3: <include> has no equivalent"),
    ("", "1:1: malformed XML: no element found"),
])  # fmt: skip
def test_files_that_are_not_btcpp_v4_trees_are_reported_at_their_line(tmp_path, xml, expected):
    found = problems(tmp_path, xml)
    assert found[0].startswith(expected), found


def test_a_single_unnamed_tree_is_the_main_tree(tmp_path):
    path = _write(tmp_path, '<root>\n  <BehaviorTree>\n    <Stop name="halt"/>\n  </BehaviorTree>\n</root>\n')
    text = import_btcpp(path)
    assert "mission: MainTree" in text and "Stop: {name: halt}" in text


def test_the_file_size_is_bounded(tmp_path, monkeypatch):
    monkeypatch.setattr("missions.importer.MAX_FILE_BYTES", 100)
    found = problems(tmp_path, _tree("<Stop/>" * 20))
    assert len(found) == 1 and found[0].startswith("larger than") and "not a BehaviorTree.CPP XML file" in found[0]


def test_the_subtree_example_of_the_documentation_imports_as_it_says(tmp_path, write_mission):
    page = (Path(__file__).resolve().parents[2] / "docs" / "missions.md").read_text()
    section = page[page.index("### Subtrees"):]
    xml = re.search(r"```xml\n(.*?)```", section, re.S).group(1)
    imported = tmp_path / "patrol.yaml"
    imported.write_text(import_btcpp(_write(tmp_path, xml)), encoding="utf-8")
    expected = write_mission("""
        tree:
          Sequence:
            children:
              - Guard: {name: first corner, key: /robot/stalled, value: false, child: {DriveTo: {x: 2.0, y: 0.5}}}
              - Guard: {name: home, key: /robot/stalled, value: false, child: {DriveTo: {x: 0.0, y: 0.0}}}
              - Stop
    """)
    assert _shape(load_mission(imported).tree) == _shape(load_mission(expected).tree)


def _export(path: Path) -> bytes:
    from missions.export import btcpp_xml

    return btcpp_xml(load_mission(path)).encode()


SEEDS = [GROOT2_FILE.encode(), *(_export(p) for p in sorted(LIBRARY.glob("*.yaml")))]
PIECES = [b"<", b">", b"/>", b'"', b"{", b"}", b"@", b"&lt;", b"&amp;", b"<SubTree ID='GoTo'/>", b"\xff",
          b"<Sequence>", b"</Sequence>", b" _autoremap='true'", b" _skipIf='x'", b"{=}", b"<!DOCTYPE x>", b"\n"]


@st.composite
def mutated_files(draw) -> bytes:
    data = bytearray(draw(st.sampled_from(SEEDS)))
    for _ in range(draw(st.integers(1, 5))):
        pos = draw(st.integers(0, len(data)))
        op = draw(st.sampled_from(["delete", "insert", "replace"]))
        if op == "delete":
            del data[pos:pos + draw(st.integers(1, 30))]
        elif op == "insert":
            data[pos:pos] = draw(st.sampled_from(PIECES))
        elif data:
            data[min(pos, len(data) - 1)] = draw(st.integers(0, 255))
    return bytes(data)


TAGS = ["Sequence", "ReactiveSequence", "Fallback", "Parallel", "SubTree", "Timeout", "RunOnce", "Precondition",
        "ScriptCondition", "Sleep", "Drive", "Stop", "Guard", "Action", "BehaviorTree", "TreeNodesModel",
        "input_port", "RecoveryNode", "RateController", "OneShot", "IfThenElse", "KeepRunningUntilFailure", "root"]
ATTRIBUTES = ["ID", "name", "msec", "if", "else", "code", "success_count", "failure_count", "then_skip", "gx",
              "distance", "command", "_autoremap", "_skipIf", "main_tree_to_execute", "BTCPP_format", "default",
              "num_attempts", "policy", "key", "value", "hz"]
VALUES = ["1", "-1", "0.5", "abc", "true", "false", "{@robot__command}", "{=}", "{gx}", "{@_zz}", "{/robot/stalled}",
          "@robot__stalled == true", "@robot__odometry___x &lt; 1 &amp;&amp; x", "GoTo", "Patrol", "Pause", "",
          "SUCCESS", "{@perception__observation___count}", "3000000000", "1e999"]


@st.composite
def rearranged_files(draw) -> bytes:
    """Well-formed XML whose elements and attributes are shuffled among BT.CPP's vocabulary."""
    import xml.etree.ElementTree as ET

    root = ET.fromstring(draw(st.sampled_from(SEEDS)))
    for _ in range(draw(st.integers(1, 6))):
        elements = list(root.iter())
        element = draw(st.sampled_from(elements))
        op = draw(st.sampled_from(["tag", "attribute", "drop_attribute", "remove", "duplicate", "move"]))
        if op == "tag":
            element.tag = draw(st.sampled_from(TAGS))
        elif op == "attribute":
            element.set(draw(st.sampled_from(ATTRIBUTES)), draw(st.sampled_from(VALUES)))
        elif op == "drop_attribute" and element.attrib:
            del element.attrib[draw(st.sampled_from(sorted(element.attrib)))]
        elif len(element):
            child = draw(st.sampled_from(list(element)))
            if op == "remove":
                element.remove(child)
            elif op == "duplicate":
                element.append(ET.fromstring(ET.tostring(child)))
            else:
                element.remove(child)
                inside = set(map(id, child.iter()))
                draw(st.sampled_from([e for e in elements if id(e) not in inside])).append(child)
    return ET.tostring(root)


@settings(max_examples=examples(150), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(mutated_files(), rearranged_files(), st.binary(max_size=100)))
def test_whatever_the_file_holds_import_gives_a_mission_or_located_problems(data):
    result = load_or_diagnose(data, import_btcpp, name="tree.xml")
    assert result is None or result.startswith("# Imported from tree.xml")
    event("imported" if result else "reported")


def test_text_that_yaml_1_2_reads_as_a_number_stays_text(tmp_path):
    path = _write(tmp_path, _tree('<Perceive camera="1e5" name="2E-3"/>'))
    mission = tmp_path / "m.yaml"
    mission.write_text(import_btcpp(path), encoding="utf-8")
    node = load_mission(mission).tree
    assert (node.inputs["camera"], node.name) == ("1e5", "2E-3")
