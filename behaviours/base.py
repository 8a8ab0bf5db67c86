"""The base class of bearings leaf behaviours: declared ports, blackboard access and the clock.

A behaviour declares its ports once (``PORTS``, see :mod:`behaviours.ports`); the mission loader
checks a mission against them before anything ticks, and the behaviour's blackboard client is
granted exactly the keys its ports resolve to: read access for referenced inputs, write access
for outputs (remapped or not). Inside ``update()`` a behaviour calls :meth:`get_input` and
:meth:`set_output` (py_trees' own ports use the same names), never a key.
"""

from __future__ import annotations

from typing import Any, ClassVar, TypeVar, overload

import py_trees
from py_trees.common import Access

from behaviours.clock import Clock
from behaviours.ports import (
    REQUIRED,
    InputPort,
    Key,
    OutputPort,
    Port,
    Ref,
    check_literal,
    key_problem,
    matches_type,
    parse_ref,
    type_name,
)
from behaviours.registry import Declared, Kind

_UNSET: Any = object()
T = TypeVar("T")
D = TypeVar("D")


class NotSetUp(RuntimeError):
    """A behaviour ticked before ``setup(clock=...)``: the tree was not set up by a runner."""


class PortedNode(Declared, py_trees.behaviour.Behaviour):
    """Declared ports, blackboard access and the clock, for any kind of node (mixed in first).

    :class:`BearingsBehaviour` (leaves) and :class:`BearingsDecorator` (decorators that also read
    and write the blackboard, like ``LearnRoute``) are this plus a py_trees base class (a
    ``Behaviour``, so this is one too); a subclass calls :meth:`_bind` with its ports after the
    py_trees constructor.
    """

    def _bind(self, ports: dict[str, Any]) -> None:
        """Check ``ports`` against the declaration and grant the blackboard access they need."""
        self.inputs, self.outputs = bind_ports(type(self).__name__, self.PORTS, ports)
        self.bb = self.attach_blackboard_client(name=self.name)
        for key in read_keys(self.PORTS, self.inputs):
            if not self.bb.is_registered(key=key):
                self.bb.register_key(key=key, access=Access.READ)
        for key in self.outputs.values():
            self.bb.register_key(key=key, access=Access.WRITE)
        self._clock: Clock | None = None
        self._output_types = {p.name: p.type for p in self.PORTS if isinstance(p, OutputPort)}

    # -- set-up ----------------------------------------------------------------------------
    def setup(self, **kwargs: Any) -> None:
        """Receive the clock (and anything else the runner hands the tree)."""
        self._clock = kwargs.get("clock", self._clock)

    @property
    def clock(self) -> Clock:
        if self._clock is None:
            raise NotSetUp(f"{self.name}: no clock; set the tree up with "
                           "setup(clock=...)")
        return self._clock

    def now(self) -> float:
        return self.clock.now()

    # -- ports -----------------------------------------------------------------------------
    @overload
    def get_input(self, port: InputPort[T]) -> T: ...
    @overload
    def get_input(self, port: InputPort[T], default: D) -> T | D: ...
    @overload
    def get_input(self, port: str, default: Any = ...) -> Any: ...

    def get_input(self, port: InputPort[Any] | str, default: Any = _UNSET) -> Any:
        """An input's value now: the literal, or the referenced blackboard value.

        Pass the port object (``self.get_input(SPEED)``): its declared type is the value's type for
        mypy. A port's name (``"speed"``) also works, untyped, for plugins written that way. A
        reference nobody has written yet gives ``default`` (``KeyError`` without one).
        """
        name = port if isinstance(port, str) else port.name
        value = self.inputs[name]
        if not isinstance(value, Ref):
            return value
        try:
            return self.bb.get(value.key)
        except KeyError:
            if default is _UNSET:
                raise KeyError(f"{self.bb.name}: input {name!r} reads {value}, which is not set yet") from None
            return default

    @overload
    def set_output(self, port: OutputPort[T], value: T) -> None: ...
    @overload
    def set_output(self, port: str, value: Any) -> None: ...

    def set_output(self, port: OutputPort[Any] | str, value: Any) -> None:
        """Write an output port's key; a value of the wrong type is a bug in the behaviour."""
        name = port if isinstance(port, str) else port.name
        expected = self._output_types[name]
        if not matches_type(value, expected):
            raise TypeError(f"{self.bb.name}: output {name!r} is declared {type_name(expected)}, "
                            f"got {type(value).__name__}")
        self.bb.set(self.outputs[name], value, overwrite=True)

    def output_key(self, port: OutputPort[Any] | str) -> str:
        """The blackboard key an output port writes (after remapping)."""
        return self.outputs[port if isinstance(port, str) else port.name]


class BearingsBehaviour(PortedNode, py_trees.behaviour.Behaviour):
    """A leaf behaviour with typed ports; subclasses implement ``initialise``/``update``.

    Construct with the node's name and its ports as keyword arguments, exactly as a mission
    writes them: literals, ``"{/ns/key}"`` references for inputs, keys for outputs::

        Perceive(name="front eyes", camera="front", observation="{/perception/front}")
    """

    KIND: ClassVar[Kind] = "action"

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name or type(self).__name__)
        self._bind(ports)


class BearingsDecorator(PortedNode, py_trees.decorators.Decorator):
    """A decorator with typed ports: around one child, it reads and writes the blackboard like a leaf.

    Built as the loader builds decorators: ``cls(name=..., child=..., **ports)``.
    """

    KIND: ClassVar[Kind] = "decorator"
    CHILDREN: ClassVar[tuple[int, int | None]] = (1, 1)

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, **ports: Any) -> None:
        super().__init__(name=name, child=child)
        self._bind(ports)


def read_keys(declared: tuple[Port, ...], inputs: dict[str, Any]) -> list[str]:
    """The blackboard entries bound inputs read: references, and literal ``Key`` inputs (a key to watch)."""
    keys = []
    for port in declared:
        value = inputs.get(port.name)
        if isinstance(value, Ref):
            keys.append(value.base)
        elif isinstance(port, InputPort) and port.type is Key and isinstance(value, str):
            keys.append(value.split(".", 1)[0])
    return list(dict.fromkeys(keys))


def bind_ports(owner: str, declared: tuple[Port, ...], given: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str]]:
    """Check ports given in code against the declaration; (inputs, output keys) with defaults filled.

    Raises TypeError/ValueError naming the port; the mission loader reports the same problems
    with file positions before it ever constructs a node.
    """
    by_name = {p.name: p for p in declared}
    unknown = sorted(set(given) - set(by_name))
    if unknown:
        raise TypeError(f"{owner}: unknown port(s) {', '.join(unknown)} (it has: {', '.join(by_name) or 'none'})")
    inputs: dict[str, Any] = {}
    outputs: dict[str, str] = {}
    for port in declared:
        value = given.get(port.name, _UNSET)
        if isinstance(port, OutputPort):
            outputs[port.name] = _output_key(owner, port, value)
        else:
            inputs[port.name] = _input_value(owner, port, value)
    return inputs, outputs


def _output_key(owner: str, port: OutputPort, value: Any) -> str:
    if value is _UNSET:
        return port.key
    ref = parse_ref(value) or (Ref(value) if isinstance(value, str) else None)
    problem = key_problem(ref.key, attributes=False) if ref else "expects a blackboard key"
    if problem or ref is None:
        raise ValueError(f"{owner}.{port.name}: {problem}")
    return ref.key


def _input_value(owner: str, port: InputPort, value: Any) -> Any:
    if value is _UNSET:
        if port.default is REQUIRED:
            raise TypeError(f"{owner}: missing required input {port.name!r}")
        value = port.default
    if value is None and port.default is None:
        return None  # an optional input left unset
    ref = parse_ref(value)
    if ref is not None:
        if port.literal_only:
            raise ValueError(f"{owner}.{port.name} takes a literal value, not a blackboard reference")
        return ref
    value, problem = check_literal(port, value)
    if problem:
        raise ValueError(f"{owner}.{port.name} {problem}")
    return value
