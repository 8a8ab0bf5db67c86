"""Property: whatever bytes a mission file holds, loading it gives a mission or located
diagnostics, never another exception (so the CLI never shows a traceback)."""

from __future__ import annotations

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from missions.language import MissionSpec
from missions.loader import LIBRARY, load_mission
from tests.fuzzing import examples, load_or_diagnose

SHIPPED = sorted(p.read_text(encoding="utf-8") for p in LIBRARY.glob("*.yaml"))
NAMES = ["Sequence", "Selector", "Parallel", "Drive", "Rotate", "Wait", "Timeout", "Retry", "Repeat",
         "RecoveryNode", "Guard", "CheckBlackboard", "include", "children", "child", "tree", "inputs",
         "distance", "duration", "memory", "name", "key", "value", "${side}", "{/robot/odometry}", "sense"]
SETTINGS = settings(max_examples=examples(300), deadline=None, suppress_health_check=[HealthCheck.too_slow])


def load_text(data: bytes) -> None:
    result = load_or_diagnose(data, load_mission, name="fuzz.yaml")
    assert result is None or isinstance(result, MissionSpec)


@st.composite
def mutated_missions(draw) -> bytes:
    text = bytearray(draw(st.sampled_from(SHIPPED)).encode())
    for _ in range(draw(st.integers(1, 6))):
        op = draw(st.sampled_from(["delete", "insert", "replace", "dup_line"]))
        pos = draw(st.integers(0, max(0, len(text) - 1)))
        if op == "delete" and text:
            del text[pos:pos + draw(st.integers(1, 20))]
        elif op == "insert":
            text[pos:pos] = draw(st.sampled_from([b":", b"-", b" ", b"\n", b"{", b"[", b"&a", b"*a", b"\t", b"#",
                                                  b"'", b'"', b"\xff", b"${x}", b"{/map/goal}", b"!!int"]))
        elif op == "replace" and text:
            text[pos] = draw(st.integers(0, 255))
        else:
            lines = bytes(text).split(b"\n")
            i = draw(st.integers(0, len(lines) - 1))
            lines.insert(i, lines[i])
            text = bytearray(b"\n".join(lines))
    return bytes(text)


scalars = st.one_of(st.none(), st.booleans(), st.integers(-5, 5), st.floats(allow_nan=True),
                    st.sampled_from(NAMES), st.text(max_size=8))
structures = st.recursive(
    scalars,
    lambda inner: st.one_of(st.lists(inner, max_size=4),
                            st.dictionaries(st.sampled_from(NAMES), inner, max_size=4)),
    max_leaves=25,
)


@SETTINGS
@given(mutated_missions())
def test_mutated_shipped_missions_never_raise_unexpectedly(data):
    load_text(data)


@SETTINGS
@given(st.dictionaries(st.sampled_from(["tree", "inputs", "mission", "sense", "plugins", "rate",
                                        "evaluation", "max_time"]), structures, max_size=5))
def test_random_structures_never_raise_unexpectedly(document):
    load_text(yaml.safe_dump(document).encode())


@SETTINGS
@given(st.binary(max_size=200))
def test_random_bytes_never_raise_unexpectedly(data):
    load_text(data)
