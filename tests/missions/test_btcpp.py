"""The BehaviorTree.CPP v4 export loads in BT.CPP itself, and ``bearings import`` reads it back
into the same tree: every shipped mission, a mission using every built-in node type, and
generated trees of built-in node types with random valid ports.

BT.CPP is ``behaviortreepy`` (a dev dependency: if it cannot be imported these tests fail, they
are not skipped). Its factory registers Python nodes without port declarations, so it cannot
itself hold BT.CPP to the rule that every attribute of a registered node is a declared port.
:func:`load_in_btcpp` therefore applies that rule (``createNodeFromXML``'s, port for port) to
every node the TreeNodesModel declares, then hands BT.CPP the file with those nodes registered
from the model and their checked attributes removed; BT.CPP's own nodes (``Precondition`` and
its script, ``Timeout msec``, ``Parallel``, ``RunOnce``, ...) keep every attribute and are checked
by BT.CPP. A control node the model declares (Nav2's ``RecoveryNode``) cannot be registered
through behaviortreepy at all and stands as a ``Sequence`` once its ports and children are
checked.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import behaviortreepy as bt
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from behaviours.ports import InputPort, Key, Ref
from behaviours.registry import NodeType, Registry
from behaviours.sense import SENSE_NODES
from maps.store import InputError
from missions.btcpp import BUILTIN_NAMES, identifier_to_key, key_to_identifier, parse_comparison, script_literal
from missions.cli import main
from missions.export import btcpp_xml
from missions.importer import dump_mission, import_btcpp
from missions.inputs import Unbound
from missions.language import NodeSpec
from missions.loader import LIBRARY, load_mission
from tests.fuzzing import examples

SHIPPED = sorted(LIBRARY.glob("*.yaml"))

EVERY_NODE_TYPE = """
    mission: every_node_type
    cameras: [panorama, stereo, landmarks]
    sense:
      - Perceive: {camera: panorama, max_features: 300, observation: "{/perception/panorama}"}
      - CorrectOdometry
      - LocalisePose: {camera: landmarks}
    tree:
      Sequence:
        name: every node type
        children:
          - Parallel:
              policy: one
              children:
                - RateController: {hz: 2.5, child: IsStalled}
                - Running
          - Selector:
              memory: false
              children:
                - Guard:
                    name: enough landmarks
                    key: /perception/panorama.count
                    op: ">="
                    value: 20
                    child:
                      Timeout:
                        duration: 1.5
                        child: {DriveTo: {x: "{/robot/odometry.x}", y: -0.5, speed: 0.25}}
                - RecoveryNode:
                    number_of_retries: 2
                    children:
                      - Retry: {num_attempts: 3, child: {Drive: {distance: 0.5, command: "{/robot/command}"}}}
                      - Rotate: {angle: -45}
          - Sequence:
              memory: false
              children:
                - OneShot: {policy: on_completion, child: {Wait: {duration: 0.25}}}
                - OneShot: {child: {Inverter: {child: Failure}}}
          - Selector:
              children:
                - Repeat:
                    num_cycles: 2
                    child:
                      ForceSuccess:
                        child: {CheckBlackboard: {key: /robot/odometry.x, op: "<", value: 5.0}}
                - ForceFailure: {child: Success}
          - Sequence:
              name: the LT-map nodes
              children:
                - LearnRoute:
                    budget: 100000
                    observation: "{/perception/panorama}"
                    child:
                      Selector:
                        children:
                          - KeyboardTeleop
                          - Sequence:
                              children:
                                - Equals: {value: waypoints, equals: waypoints}
                                - DriveWaypoints: {waypoints: [0.5, 0.0, 0.5, 0.5]}
                - LoadMap: {path: route.ltmap}
                - PruneMap: {fraction: 0.6}
                - StartRoute: {direction: reverse}
                - RecoveryNode:
                    children:
                      - RecoveryNode:
                          number_of_retries: 4
                          children:
                            - AvoidObstacles:
                                wait: 1.5
                                max_detour: 2.5
                                child:
                                  Parallel:
                                    policy: one
                                    children:
                                      - FollowRoute: {observation: "{/perception/panorama}"}
                                      - ViewframeSwitch
                            - SkipViewframes: {window: 8, observation: "{/perception/panorama}"}
                      - SearchPattern: {observation: "{/perception/panorama}"}
          - Sequence:
              name: the roadmap nodes
              children:
                - LoadTargetImages: {folder: targets}
                - CalibrateTurns
                - RoomEstimationDodecagon: {side: 0.25}
                - Selector:
                    children:
                      - AllTargetsFound
                      - Sequence:
                          children:
                            - CoverageScoring
                            - GoToPose: {goal: "{/map/coverage_goal}"}
                            - ScanForTargets
                            - TargetHoming: {room: "{/map/room}"}
                            - ReturnToReference
                            - RecordTarget
                - BuildGraph: {file: learned.roadmap, odometry: "{/robot/calibrated_odometry}"}
                - LoadRoadmap: {file: learned.roadmap}
                - NavigateToTarget: {target: door}
          - Parallel:
              name: the exploration nodes
              policy: one
              children:
                - MapStereo: {camera: stereo, odometry: "{/robot/pose}"}
                - Sequence:
                    children:
                      - LookAround
                      - Parallel:
                          policy: one
                          children:
                            - SelectGoalPoint: {odometry: "{/robot/pose}"}
                            - FollowPath: {odometry: "{/robot/pose}"}
                            - WatchInterestEdges: {turn_rate: "{/robot/command.w}", odometry: "{/robot/pose}"}
          - Stop
"""

# Nav2's declarations (nav2_behavior_tree: RecoveryNode, RateController providedPorts()):
# a bearings node exported under a Nav2 name must be what Nav2 registers.
NAV2 = {"RecoveryNode": ("Control", {"number_of_retries": "int"}), "RateController": ("Decorator", {"hz": "double"})}


@pytest.fixture
def every_node_type(write_mission) -> Path:
    return write_mission(EVERY_NODE_TYPE, name="every_node_type.yaml")


# -- BT.CPP, through behaviortreepy ----------------------------------------------------------------
def _ok(*_: Any) -> bt.NodeStatus:
    return bt.NodeStatus.SUCCESS


def _model(root: ET.Element) -> dict[str, ET.Element]:
    model = root.find("TreeNodesModel")
    assert model is not None
    return {entry.get("ID"): entry for entry in model}


def _converts(text: str, cpp_type: str | None) -> bool:
    """Would BT.CPP's convertFromString take this literal for a port of this type?"""
    try:
        if cpp_type == "double":
            return math.isfinite(float(text))
        if cpp_type == "int":
            return int(text) == int(text)
    except ValueError:
        return False
    return cpp_type != "bool" or text in ("true", "false", "1", "0", "TRUE", "FALSE", "True", "False")


def _checked_ports(element: ET.Element, entry: ET.Element) -> None:
    """BT.CPP's createNodeFromXML for a registered node: every port-named attribute is a declared
    port, a literal converts to the port's type, a blackboard key uses '@' at most once, first."""
    ports = {p.get("name"): p.get("type") for p in entry}
    for name, value in element.attrib.items():
        if name == "name" or not name[0].isalpha():
            continue
        assert name in ports, f"<{element.tag}> writes {name}, which its TreeNodesModel entry does not declare"
        if len(value) >= 3 and value[0] == "{" and value[-1] == "}":
            key = value[1:-1]
            assert "@" not in key[1:] and identifier_to_key(key) is not None, f"{name}={value}"
        else:
            assert _converts(value, ports[name]), f"<{element.tag} {name}={value!r}> is not a {ports[name]}"


def _standing_in(root: ET.Element, models: dict[str, ET.Element]) -> None:
    """Check and strip the nodes BT.CPP will know only from the model (see the module docstring)."""
    for tree in root.findall("BehaviorTree"):
        for element in tree.iter():
            if element.tag in BUILTIN_NAMES or element.tag == "BehaviorTree":
                continue
            entry = models.get(element.tag)
            assert entry is not None, f"<{element.tag}> is neither a BT.CPP node nor in the TreeNodesModel"
            _checked_ports(element, entry)
            element.attrib = {k: v for k, v in element.attrib.items() if k == "name"}
            if entry.tag == "Control":
                assert len(element) >= 1 and (element.tag != "RecoveryNode" or len(element) == 2)
                element.tag = "Sequence"


def load_in_btcpp(xml: str, blackboard: Any = None) -> dict[str, Any]:
    """Every tree of an exported file, created by BehaviorTree.CPP's factory."""
    root = ET.fromstring(xml.split("\n", 1)[1])
    models = _model(root)
    for name, (kind, ports) in NAV2.items():
        if name in models:
            entry = models[name]
            assert entry.tag == kind and {p.get("name"): p.get("type") for p in entry} == ports
    _standing_in(root, models)
    factory = bt.BehaviorTreeFactory()
    register = {"Action": factory.register_simple_action, "Condition": factory.register_simple_condition,
                "Decorator": factory.register_simple_decorator}
    for node_id, entry in models.items():
        if entry.tag in register:
            register[entry.tag](node_id, _ok)
    factory.register_behavior_tree_from_text(ET.tostring(root, encoding="unicode"))
    return {tree_id: factory.create_tree(tree_id, blackboard or bt.Blackboard.create())
            for tree_id in factory.registered_behavior_trees()}


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_every_shipped_mission_loads_in_behaviortree_cpp(path):
    mission = load_mission(path)
    trees = load_in_btcpp(btcpp_xml(mission))
    expected = {path.stem, f"{path.stem}_sense"} if mission.sense else {path.stem}
    assert set(trees) == expected and all(isinstance(tree, bt.Tree) for tree in trees.values())


def test_the_mission_of_every_node_type_loads_in_behaviortree_cpp(every_node_type):
    mission = load_mission(every_node_type)
    used = {node.type for node in mission.tree.walk()} | {node.type for node in mission.sense}
    assert used == set(Registry.builtin().names()), "the fixture must use every built-in node type"
    xml = btcpp_xml(mission)
    assert set(load_in_btcpp(xml)) == {"every_node_type", "every_node_type_sense"}
    for tag in ("ReactiveSequence", "ReactiveFallback", "Fallback", "Precondition", "ScriptCondition",
                'RunOnce then_skip="false"', "OneShot", 'Timeout msec="1500"', "RetryUntilSuccessful",
                "AlwaysRunning", 'Parallel success_count="1"', "RecoveryNode", "RateController"):
        assert f"<{tag}" in xml


def test_the_guard_script_reads_the_root_blackboard_entry_the_mapping_names():
    """BT.CPP evaluates the showcase's guard on @perception__observation___count: set through the
    mapping, a count of 60 lets the tour run, 10 fails the mission."""
    xml = btcpp_xml(load_mission(LIBRARY / "showcase.yaml"))
    assert 'if="@perception__observation___count &gt;= 50"' in xml
    entry = key_to_identifier("/perception/observation.count")[1:]
    for count, status in ((60.0, bt.NodeStatus.SUCCESS), (10.0, bt.NodeStatus.FAILURE)):
        blackboard = bt.Blackboard.create()
        blackboard.set_double(entry, count)
        assert load_in_btcpp(xml, blackboard)["showcase"].tick_exactly_once() == status


# -- the key mapping -------------------------------------------------------------------------------
def test_the_key_mapping_is_readable_for_ordinary_keys_and_hex_for_the_rest():
    assert key_to_identifier("/perception/observation.count") == "@perception__observation___count"
    assert key_to_identifier("/mission/min_landmarks") == "@mission__min_landmarks"
    assert key_to_identifier("/map/route2/x1.y") == "@map__route2__x1___y"
    assert key_to_identifier("/map/goal_") == "@_" + b"/map/goal_".hex()
    assert key_to_identifier("/map/a__b") != key_to_identifier("/map/a/b")
    for identifier in ("@map__a____b", "@robot", "@nowhere__x", "@_zz", "@_" + b"/map/x".hex(), "@Map__x"):
        assert identifier_to_key(identifier) is None, identifier  # not the canonical name of a key
    assert identifier_to_key("@Map__x".replace("M", "m")) == "/map/x"


segment = st.text(alphabet="abcXY019_é", min_size=0, max_size=6)
keys = st.builds(lambda ns, first, rest, attrs: f"/{ns}/{first}{''.join('/' + s for s in rest)}"
                 f"{''.join('.' + a for a in attrs)}",
                 st.sampled_from(["robot", "ptu", "perception", "map", "mission"]),
                 st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,5}", fullmatch=True), st.lists(segment, max_size=3),
                 st.lists(st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,4}", fullmatch=True), max_size=2))


@settings(max_examples=examples(150), deadline=None)
@given(keys)
def test_every_key_maps_to_one_btcpp_identifier_and_back(key):
    identifier = key_to_identifier(key)
    assert identifier_to_key(identifier) == key
    assert identifier.isascii() and identifier[0] == "@" and (identifier[1:].replace("_", "a").isalnum())
    comparison = parse_comparison(f"{identifier} >= 5")
    assert comparison is not None and comparison.name == identifier


@settings(max_examples=examples(25), deadline=None)
@given(keys, st.one_of(st.integers(-(2**31), 2**31 - 1),  # behaviortreepy's set_int takes a C++ int
                       st.floats(allow_nan=False, allow_infinity=False), st.booleans(),
                       st.text(alphabet="ab '\"x", max_size=4)))
def test_btcpp_scripts_read_the_entry_the_identifier_names(key, value):
    """BehaviorTree.CPP itself parses the script and finds the entry under the mapped name."""
    literal = script_literal(value)
    if literal is None:  # both quotes in one text, or a subnormal number std::stod refuses
        assert (isinstance(value, str) and "'" in value and '"' in value) or 0 < abs(value) < 2.3e-308
        return
    identifier = key_to_identifier(key)
    factory = bt.BehaviorTreeFactory()
    xml = ET.Element("root", {"BTCPP_format": "4", "main_tree_to_execute": "T"})
    ET.SubElement(ET.SubElement(xml, "BehaviorTree", {"ID": "T"}), "ScriptCondition",
                  {"code": f"{identifier} == {literal}"})
    blackboard = bt.Blackboard.create()
    if isinstance(value, bool):
        blackboard.set_bool(identifier[1:], value)
    elif isinstance(value, int):
        blackboard.set_int(identifier[1:], value)
    elif isinstance(value, float):
        blackboard.set_double(identifier[1:], value)
    else:
        blackboard.set_string(identifier[1:], value)
    tree = factory.create_tree_from_text(ET.tostring(xml, encoding="unicode"), blackboard)
    assert tree.tick_exactly_once() == bt.NodeStatus.SUCCESS
    assert parse_comparison(f"{identifier} == {literal}").value == value


# -- the round trip ----------------------------------------------------------------------------------
def _typed(value: Any) -> Any:
    """A port value with its type (so that 1, 1.0 and True differ)."""
    if isinstance(value, list):
        return ("list", tuple(_typed(v) for v in value))
    return (type(value).__name__, value)


def shape(node: NodeSpec) -> tuple[Any, ...]:
    """What makes two trees the same: types, names, inputs, outputs, children."""
    return (node.type, node.name, {k: _typed(v) for k, v in node.inputs.items()}, dict(node.outputs),
            tuple(shape(child) for child in node.children))


def round_trip(path: Path, folder: Path) -> tuple[Any, Any]:
    """(original, imported) shapes of the task tree and the sense nodes; the export also loads in BT.CPP.
    Required inputs get a value, as to run (an export writes the values)."""
    unbound = {name: "x" for name, value in load_mission(path).values.items() if isinstance(value, Unbound)}
    mission = load_mission(path, overrides=unbound)
    xml_path = folder / f"{path.stem}.xml"
    xml = btcpp_xml(mission)
    load_in_btcpp(xml)
    xml_path.write_text(xml, encoding="utf-8")
    imported = folder / f"{path.stem}.imported.yaml"
    imported.write_text(import_btcpp(xml_path), encoding="utf-8")
    again = load_mission(imported)
    assert again.name == mission.name.replace(" ", "_")
    return ((shape(mission.tree), [shape(n) for n in mission.sense]),
            (shape(again.tree), [shape(n) for n in again.sense]))


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_every_shipped_mission_survives_export_and_import(path, tmp_path):
    original, imported = round_trip(path, tmp_path)
    assert imported == original


def test_the_mission_of_every_node_type_survives_export_and_import(every_node_type, tmp_path):
    original, imported = round_trip(every_node_type, tmp_path)
    assert imported == original


def test_bearings_import_writes_a_mission_that_validates(tmp_path, capsys):
    xml, mission = tmp_path / "showcase.xml", tmp_path / "showcase.yaml"
    assert main(["show", "showcase", "--format", "xml", "-o", str(xml)]) == 0
    assert main(["import", str(xml), "-o", str(mission)]) == 0
    assert main(["validate", str(mission)]) == 0
    text = mission.read_text()
    assert text.startswith("# Imported from showcase.xml") and "key: /perception/observation.count" in text
    capsys.readouterr()
    assert main(["import", str(xml)]) == 0 and capsys.readouterr().out == text


# -- generated trees ---------------------------------------------------------------------------------
BUILTIN = Registry.builtin()
FLOAT_REFS = ("/robot/odometry.x", "/robot/odometry.y", "/robot/odometry.theta")
names = st.text(st.characters(blacklist_categories=("Cc", "Cs"), blacklist_characters="$",
                              whitelist_characters="\t\n\x85"), min_size=1, max_size=8).filter(lambda s: s.strip())
texts = st.text(st.characters(blacklist_categories=("Cc", "Cs"), blacklist_characters="${}"), max_size=6)
map_keys = st.lists(st.from_regex(r"[A-Za-z0-9_é]{1,6}", fullmatch=True), min_size=1, max_size=3).map(
    lambda parts: "/map/out/" + "/".join(parts))


def _literal(port: InputPort) -> st.SearchStrategy[Any] | None:
    if port.name == "duration" and port.literal_only:  # Timeout: BT.CPP counts whole milliseconds
        return st.integers(0, 10**7).map(lambda ms: ms / 1000)
    if port.type is float:
        low = port.minimum if port.minimum is not None else -1e300
        return st.floats(low, port.maximum if port.maximum is not None else 1e300, allow_subnormal=False)
    if port.type is int:
        return st.integers(int(port.minimum) if port.minimum is not None else -(2**31),
                           int(port.maximum) if port.maximum is not None else 2**31 - 1)
    if port.type is bool:
        return st.booleans()
    if port.choices:
        return st.sampled_from(port.choices)
    if port.type is str:
        return texts
    if port.type is Key:
        return st.sampled_from([*FLOAT_REFS, "/robot/stalled", "/robot/odometry"])
    if port.type == list[float]:  # waypoints: x, y pairs
        coordinate = st.floats(-10, 10, allow_subnormal=False)  # std::stod refuses subnormals
        pairs = st.lists(st.tuples(coordinate, coordinate), min_size=1, max_size=3)
        return pairs.map(lambda points: [v for point in points for v in point])
    if port.type is not object:
        return None  # a Pose2D, a dict of frames: from the blackboard only
    return st.one_of(st.integers(-(2**63), 2**63 - 1), st.floats(allow_nan=False, allow_infinity=False,
                                                                 allow_subnormal=False),
                     st.booleans(), st.text(alphabet="ab '_-.", max_size=5))  # a Guard's value


def _reference(port: InputPort) -> st.SearchStrategy[str] | None:
    """A reference the data-gathering branch can feed: a sensed key of the port's type (or an
    odometry attribute for a number)."""
    if port.literal_only:
        return None
    refs = [key for key, written in SENSED_TYPES.items() if written is port.type]
    refs += list(FLOAT_REFS) if port.type is float else []
    return st.sampled_from([f"{{{key}}}" for key in refs]) if refs else None


@st.composite
def node_bodies(draw, node_type) -> dict[str, Any]:
    body: dict[str, Any] = {}
    for port in node_type.inputs:
        if not port.required and draw(st.booleans()):
            continue
        literal, reference = _literal(port), _reference(port)
        if node_type.name in ("Guard", "CheckBlackboard") and port.name == "value" and literal is not None:
            literal = literal.filter(lambda v: script_literal(v) is not None)
        use_reference = reference is not None and (literal is None or draw(st.booleans()))
        body[port.name] = draw(reference if use_reference else literal)
    for port in node_type.outputs:
        if draw(st.booleans()):
            key = draw(map_keys) + "/" + port.name  # one type per key: the port name ends it
            body[port.name] = "{" + key + "}"
    if node_type.name == "Parallel":
        body["synchronise"] = True  # synchronise: false has no BT.CPP equivalent (tested below)
    if draw(st.booleans()):
        body["name"] = draw(names)
    return body


SENSED_TYPES = {port.key: port.type for cls in SENSE_NODES for port in NodeType.of(cls).outputs}
SENSED = set(SENSED_TYPES)


def _fed_by_sensing(node_type: NodeType) -> bool:
    """Its default references read sensed keys only (a tree of it alone passes the data-flow check;
    the route nodes also read the map and the observation, written by other nodes)."""
    return all(not isinstance(p.default, Ref) or p.default.base in SENSED for p in node_type.inputs)


LEAVES = [t for t in BUILTIN.all_types() if not t.takes_children and _fed_by_sensing(t)]
DECORATORS = [t for t in BUILTIN.all_types() if t.kind == "decorator" and _fed_by_sensing(t)]
COMPOSITES = [t for t in BUILTIN.all_types() if t.kind == "composite"]


@st.composite
def trees(draw, depth: int = 3) -> Any:
    kinds = ["leaf"] if depth == 0 else ["leaf", "decorator", "composite"]
    kind = draw(st.sampled_from(kinds))
    pool = {"leaf": LEAVES, "decorator": DECORATORS, "composite": COMPOSITES}[kind]
    node_type = draw(st.sampled_from(pool))
    body = draw(node_bodies(node_type))
    if kind == "decorator":
        body["child"] = draw(trees(depth - 1))
    elif kind == "composite":
        high = node_type.max_children or 3
        body["children"] = draw(st.lists(trees(depth - 1), min_size=node_type.min_children, max_size=high))
    return {node_type.name: body}


@settings(max_examples=examples(120), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(trees(), st.lists(st.just({"Perceive": {"camera": "panorama", "observation": "{/perception/sensed}"}}),
                         max_size=1))
def test_generated_trees_load_in_btcpp_and_survive_export_and_import(tmp_path_factory, tree, sense):
    folder = tmp_path_factory.mktemp("generated")
    path = folder / "generated.yaml"
    path.write_text(dump_mission({"mission": "generated", "sense": sense, "tree": tree}), encoding="utf-8")
    original, imported = round_trip(path, folder)
    assert imported == original


# -- what the export refuses --------------------------------------------------------------------------
@pytest.mark.parametrize(("node", "message"), [
    ("Parallel: {synchronise: false, children: [Success]}", "synchronise: false has no BehaviorTree.CPP"),
    ("Timeout: {duration: 0.0015, child: Success}", "not a whole number of milliseconds"),
    ("Guard: {key: /robot/stalled, value: [1, 2], child: Success}", "cannot be written in a BehaviorTree.CPP"),
    ("CheckBlackboard: {key: /robot/stalled, value: null}", "cannot be written in a BehaviorTree.CPP script"),
    ("Perceive: {camera: '{front}'}", "would be a blackboard reference"),
    ("Drive: {distance: 1.0e-310}", "not a number BehaviorTree.CPP reads"),
    ("Repeat: {num_cycles: 3000000000, child: Success}", "outside BehaviorTree.CPP's integer range"),
    ("Timeout: {duration: 5000000.0, child: Success}", "outside BehaviorTree.CPP's integer range 0..4294967295"),
])  # fmt: skip
def test_the_export_reports_what_btcpp_cannot_express_at_the_node(write_mission, capsys, node, message):
    path = write_mission(f"tree:\n  Sequence:\n    children:\n      - {node}\n")
    with pytest.raises(InputError) as caught:
        btcpp_xml(load_mission(path))
    assert [str(d) for d in caught.value.diagnostics] == [f"{path}:4:9: {d.message}" for d in caught.value.diagnostics]
    assert message in caught.value.diagnostics[0].message
    assert main(["show", str(path), "--format", "xml"]) == 2
    assert message in capsys.readouterr().err


def test_a_mission_named_like_a_node_type_gets_a_tree_id_btcpp_accepts(write_mission):
    path = write_mission("mission: Stop\ntree: Stop\n")
    xml = btcpp_xml(load_mission(path))
    assert 'main_tree_to_execute="StopTree"' in xml and set(load_in_btcpp(xml)) == {"StopTree"}


def test_a_float_port_keeps_every_digit(write_mission):
    path = write_mission("tree: {Drive: {distance: 0.123456789012, speed: 1.0e-2}}\n")
    xml = btcpp_xml(load_mission(path))
    assert 'distance="0.123456789012"' in xml and 'speed="0.01"' in xml
