"""Property: any world file gives located diagnostics, or a world the simulator can build, step and
render, never another exception."""

from __future__ import annotations

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from drivers.sim.simulation import Simulation
from drivers.sim.world import World, load_world, shipped_worlds
from tests.fuzzing import examples, load_or_diagnose

SHIPPED = sorted(p.read_text(encoding="utf-8") for p in shipped_worlds().values())
KEYS = ["name", "start", "poses", "walls", "boxes", "pillars", "landmarks", "cameras", "ptu", "lighting", "points",
        "height", "texture", "center", "size", "radius", "position", "id", "kind", "mount", "model", "x", "y",
        "theta_deg", "closed", "seed", "format", "ceiling", "people", "path", "speed", "wait_s", "loop", "sonar",
        "robot", "bumpers"]
SETTINGS = settings(max_examples=examples(150), deadline=None, suppress_health_check=[HealthCheck.too_slow])


def load_text(data: bytes) -> None:
    world = load_or_diagnose(data, load_world, name="world.yaml")
    if world is None:
        return
    assert isinstance(world, World)
    sim = Simulation(world, seed=0)
    sim.robot.base.drive(0.3, 0.2)
    sim.step(0.1)
    for camera in sim.robot.cameras.values():
        camera.grab()


@st.composite
def mutated_worlds(draw) -> bytes:
    text = bytearray(draw(st.sampled_from(SHIPPED)).encode())
    for _ in range(draw(st.integers(1, 6))):
        pos = draw(st.integers(0, max(0, len(text) - 1)))
        op = draw(st.sampled_from(["delete", "insert", "digit"]))
        if op == "delete":
            del text[pos:pos + draw(st.integers(1, 12))]
        elif op == "insert":
            text[pos:pos] = draw(st.sampled_from([b":", b"-", b"[", b"]", b"{", b"}", b"\n", b" ", b"-1", b"0",
                                                  b"1e9", b"nan", b"null", b"'", b"\xff"]))
        elif text:
            text[pos] = ord(draw(st.sampled_from("0123456789-.")))
    return bytes(text)


scalars = st.one_of(st.none(), st.booleans(), st.integers(-3, 3), st.floats(allow_nan=True, allow_infinity=True),
                    st.sampled_from(KEYS), st.text(max_size=5))
structures = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.sampled_from(KEYS), inner, max_size=4)), max_leaves=20)


@SETTINGS
@given(mutated_worlds())
def test_mutated_shipped_worlds_never_raise_unexpectedly(data):
    load_text(data)


@SETTINGS
@given(st.dictionaries(st.sampled_from(KEYS), structures, max_size=6))
def test_random_world_structures_never_raise_unexpectedly(document):
    load_text(yaml.safe_dump(document).encode())
