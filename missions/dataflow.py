"""The data-flow check: every key a mission reads is written by something, with a matching type.

Run by the loader on a mission whose nodes are already valid one by one. Writers of a key are:
the output ports of the mission's nodes (as remapped), the data-gathering branch's own nodes
(:data:`behaviours.sense.SENSE_NODES`), and the runner, which publishes every mission input as
``/mission/<input>`` and the collision monitor's state (:data:`behaviours.keys.RUNNER_KEYS`, a
key with one writer, like a sensed one). Readers are input ports given a ``{/ns/key}``
reference (their default included) and literal ``key`` inputs (``Guard``, ``CheckBlackboard``). The runner itself reads
the command keys (:data:`behaviours.keys.COMMAND_KEYS`). Rules:

1. every key read has at least one writer (a did-you-mean names the closest written key);
2. a reference to an attribute (``/robot/odometry.x``) names an attribute the writer's type has;
3. the written type fits the reading port's type (``int`` feeds ``float``; ``Any`` is checked
   when the value arrives);
4. all writers of one key agree on its type;
5. a sensed key (one written in the data-gathering branch) has exactly one writer.

Order of writes within a tick is not checked: a reader may run before its writer has written,
and must cope (as behaviours do with "waiting for odometry").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from behaviours.keys import COMMAND_KEYS, RUNNER_KEYS, input_key
from behaviours.ports import InputPort, Key, Ref, assignable, attribute_type, type_name
from behaviours.registry import NodeType
from behaviours.sense import SENSE_NODES
from maps.located import closest
from maps.store import Diagnostic
from missions.language import Location, MissionSpec, NodeSpec


@dataclass(frozen=True)
class Writer:
    """Something that writes a key: a node's output, the sense branch or the runner."""

    key: str
    type: Any
    who: str
    where: Location
    sensed: bool = False


@dataclass(frozen=True)
class Read:
    """A node input that reads a key (an attribute path included)."""

    node: NodeSpec
    port: InputPort
    key: str
    attributes: tuple[str, ...]


def check_dataflow(mission: MissionSpec) -> list[Diagnostic]:
    """Every data-flow problem of a mission, located at the port that has it."""
    writers = _writers(mission)
    problems = [*_sensed_single_writer(writers), *_writers_agree(writers), *_commands(writers)]
    for read in _reads(mission):
        problems.extend(_check_read(read, writers.get(read.key, [])))
        if read.key not in writers:
            problems.append(_unwritten(read, writers))
    return problems


# -- who writes --------------------------------------------------------------------------------------
def _writers(mission: MissionSpec) -> dict[str, list[Writer]]:
    out: dict[str, list[Writer]] = {}
    here = Location(mission.file)
    for cls in SENSE_NODES:
        for port in NodeType.of(cls).outputs:
            out.setdefault(port.key, []).append(Writer(port.key, port.type, "the data-gathering branch", here, True))
    for name, declared in mission.inputs.items():
        key = input_key(name)
        out.setdefault(key, []).append(Writer(key, declared.type, f"the mission input {name!r}", here))
    for spec in RUNNER_KEYS:
        out.setdefault(spec.path, []).append(Writer(spec.path, spec.type, "the runner", here, True))
    for sensed, roots in ((True, mission.sense), (False, (mission.tree,))):
        for spec in (node for root in roots for node in root.walk()):
            node_type = mission.registry.lookup(spec.type)
            for output in node_type.outputs if node_type else ():
                key = spec.outputs[output.name]
                out.setdefault(key, []).append(Writer(key, output.type, _who(spec), spec.where(output.name), sensed))
    return out


def _who(spec: NodeSpec) -> str:
    return spec.type if spec.name == spec.type else f"{spec.name!r} ({spec.type})"


def _sensed_single_writer(writers: dict[str, list[Writer]]) -> list[Diagnostic]:
    problems = []
    for key, found in writers.items():
        if len(found) > 1 and any(w.sensed for w in found):
            first = next(w for w in found if w.sensed)
            for other in (w for w in found if w is not first):
                problems.append(_at(other.where, f"{other.who} writes {key}, which {first.who} writes too: a sensed "
                                    "key has one writer (remap this output to a key of its own, e.g. "
                                    f"{{{key}_2}})"))
    return problems


def _writers_agree(writers: dict[str, list[Writer]]) -> list[Diagnostic]:
    problems = []
    for key, found in writers.items():
        first = found[0]
        for other in found[1:]:
            if not (assignable(other.type, first.type) or assignable(first.type, other.type)):
                problems.append(_at(other.where, f"{other.who} writes {type_name(other.type)} to {key}, where "
                                    f"{first.who} writes {type_name(first.type)}: one key holds one type"))
    return problems


def _commands(writers: dict[str, list[Writer]]) -> list[Diagnostic]:
    problems = []
    for spec in COMMAND_KEYS:
        for writer in writers.get(spec.path, []):
            if not assignable(writer.type, spec.type):
                problems.append(_at(writer.where, f"{writer.who} writes {type_name(writer.type)} to {spec.path}, "
                                    f"which the runner reads as {type_name(spec.type)}"))
    return problems


# -- who reads ---------------------------------------------------------------------------------------
def _reads(mission: MissionSpec) -> list[Read]:
    reads = []
    for spec in (node for root in (*mission.sense, mission.tree) for node in root.walk()):
        node_type = mission.registry.lookup(spec.type)
        for port in node_type.inputs if node_type else ():
            value = spec.inputs.get(port.name)
            if isinstance(value, Ref):
                reads.append(Read(spec, port, value.base, value.attributes))
            elif port.type is Key and isinstance(value, str):
                ref = Ref(value)
                reads.append(Read(spec, port, ref.base, ref.attributes))
    return reads


def _unwritten(read: Read, writers: dict[str, list[Writer]]) -> Diagnostic:
    namespace, _, leaf = read.key.rpartition("/")
    siblings = {key.rpartition("/")[2]: key for key in writers if key.rpartition("/")[0] == namespace}
    match = closest(leaf, siblings)  # names within the namespace: a shared prefix is no likeness
    hint = f"; did you mean {siblings[match]!r}?" if match else f" (written keys: {', '.join(sorted(writers))})"
    return _at(read.node.where(read.port.name), f"{_who(read.node)}.{read.port.name} reads {read.key}, which "
               f"nothing writes{hint}")


def _check_read(read: Read, found: list[Writer]) -> list[Diagnostic]:
    where = read.node.where(read.port.name)
    owner = f"{_who(read.node)}.{read.port.name}"
    problems = []
    for writer in found:
        try:
            value_type = _through(writer.type, read.attributes)
        except AttributeError as exc:
            problems.append(_at(where, f"{owner}: {read.key} holds {type_name(writer.type)}, and {exc}"))
            continue
        if read.port.type is not Key and not assignable(value_type, read.port.type):
            path = ".".join((read.key, *read.attributes))
            problems.append(_at(where, f"{owner} is {type_name(read.port.type)}, but {path} holds "
                                f"{type_name(value_type)} (written by {writer.who})"))
    return problems[:1]


def _through(tp: Any, attributes: tuple[str, ...]) -> Any:
    for attribute in attributes:
        tp = attribute_type(tp, attribute)
    return tp


def _at(where: Location, message: str) -> Diagnostic:
    return Diagnostic(where.file, where.line, where.col, message)
