"""The base class of bearings behaviours: declared ports, blackboard access and the clock.

A behaviour declares ``PARAMS`` (typed parameters), ``READS`` and ``WRITES`` (blackboard keys)
as class attributes; the mission loader checks a mission against them before anything ticks, and
the blackboard client only grants access to the declared keys.
"""

from __future__ import annotations

from typing import Any, ClassVar

import py_trees
from py_trees.common import Access

from behaviours.clock import Clock
from behaviours.ports import REQUIRED, Param, Ref, check_value, parse_ref


class NotSetUp(RuntimeError):
    """A behaviour ticked before ``setup(clock=...)``: the tree was not set up by a runner."""


class BearingsBehaviour(py_trees.behaviour.Behaviour):
    """A leaf behaviour with typed ports; subclasses implement ``initialise``/``update``."""

    PARAMS: ClassVar[tuple[Param, ...]] = ()
    READS: ClassVar[tuple[str, ...]] = ()
    WRITES: ClassVar[tuple[str, ...]] = ()
    KIND: ClassVar[str] = "action"  # or "condition"

    def __init__(self, name: str | None = None, **params: Any) -> None:
        super().__init__(name=name or type(self).__name__)
        self.params = bind_params(type(self).__name__, self.PARAMS, params)
        self.bb = self.attach_blackboard_client(name=self.name)
        refs = [value.key.split(".", 1)[0] for value in self.params.values() if isinstance(value, Ref)]
        for key in dict.fromkeys([*self.READS, *refs]):
            self.bb.register_key(key=key, access=Access.READ)
        for key in self.WRITES:
            self.bb.register_key(key=key, access=Access.WRITE)
        self._clock: Clock | None = None

    # -- set-up ----------------------------------------------------------------------------
    def setup(self, **kwargs: Any) -> None:
        """Receive the clock (and anything else the runner hands the tree)."""
        self._clock = kwargs.get("clock", self._clock)

    @property
    def clock(self) -> Clock:
        if self._clock is None:
            raise NotSetUp(f"{self.name}: no clock; set the tree up with setup(clock=...)")
        return self._clock

    def now(self) -> float:
        return self.clock.now()

    # -- ports -----------------------------------------------------------------------------
    def param(self, name: str) -> Any:
        """A parameter's value now: the literal, or the referenced blackboard value."""
        value = self.params[name]
        if isinstance(value, Ref):
            return self.bb.get(value.key)
        return value

    def read(self, key: str, default: Any = None) -> Any:
        """A declared key's value, or ``default`` when nobody has written it yet."""
        try:
            return self.bb.get(key)
        except KeyError:
            return default

    def write(self, key: str, value: Any) -> None:
        self.bb.set(key, value, overwrite=True)


def bind_params(owner: str, declared: tuple[Param, ...], given: dict[str, Any]) -> dict[str, Any]:
    """Check given parameters against the declaration and fill in defaults (programmatic use).

    Raises TypeError/ValueError with the offending parameter named; the mission loader reports the
    same problems with file positions before it ever constructs a node.
    """
    by_name = {p.name: p for p in declared}
    unknown = sorted(set(given) - set(by_name))
    if unknown:
        raise TypeError(f"{owner}: unknown parameter(s) {', '.join(unknown)}")
    bound: dict[str, Any] = {}
    for param in declared:
        if param.name not in given:
            if param.default is REQUIRED:
                raise TypeError(f"{owner}: missing required parameter {param.name!r}")
            bound[param.name] = param.default
            continue
        value = given[param.name]
        ref = value if isinstance(value, Ref) else parse_ref(value)
        if ref is not None:
            bound[param.name] = ref
            continue
        value, error = check_value(param, value)
        if error:
            raise ValueError(f"{owner}.{param.name} {error}")
        bound[param.name] = value
    return bound
