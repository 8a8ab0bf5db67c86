"""The control-flow node types every mission can use, declared like any other node type.

Each is py_trees' own class where py_trees has the semantics, with the bearings declaration
(kind, ports, BehaviorTree.CPP name, child count) on top; the constructors take the mission's
port names. ``Timeout``, ``RateController`` and ``Guard`` (tree clock, blackboard conditions)
live in :mod:`behaviours.decorators`, Nav2's ``RecoveryNode`` in :mod:`behaviours.composites`.
"""

from __future__ import annotations

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import OneShotPolicy, ParallelPolicy

from behaviours.ports import InputPort
from behaviours.registry import Declared, register

MEMORY = InputPort(
    "memory", bool, True, literal_only=True,
    doc="true: resume at the running child on the next tick (BehaviorTree.CPP Sequence/Fallback); "
        "false: re-tick from the first child every tick (ReactiveSequence/ReactiveFallback)",
)  # fmt: skip


@register
class Sequence(Declared, py_trees.composites.Sequence):
    """Tick children in order; FAILURE at the first failure, SUCCESS when all succeed."""

    KIND = "composite"
    PORTS = (MEMORY,)
    CHILDREN = (1, None)

    def __init__(self, name: str, children: list[Behaviour], memory: bool = True) -> None:
        super().__init__(name=name, memory=memory, children=children)


@register
class Selector(Declared, py_trees.composites.Selector):
    """Tick children in order until one does not fail (a fallback)."""

    KIND = "composite"
    PORTS = (MEMORY,)
    BTCPP = "Fallback"
    CHILDREN = (1, None)

    def __init__(self, name: str, children: list[Behaviour], memory: bool = True) -> None:
        super().__init__(name=name, memory=memory, children=children)


@register
class Parallel(Declared, py_trees.composites.Parallel):
    """Tick every child each tick; FAILURE as soon as one fails."""

    KIND = "composite"
    POLICY = InputPort("policy", str, "all", choices=("all", "one"), literal_only=True,
                       doc="all: SUCCESS when every child succeeded; one: when any did")
    SYNCHRONISE = InputPort("synchronise", bool, True, literal_only=True,
                            doc="with policy all: do not re-tick children that succeeded")
    PORTS = (POLICY, SYNCHRONISE)
    CHILDREN = (1, None)

    def __init__(self, name: str, children: list[Behaviour], policy: str = "all", synchronise: bool = True
                 ) -> None:
        chosen = ParallelPolicy.SuccessOnAll(synchronise=synchronise) if policy == "all" else (
            ParallelPolicy.SuccessOnOne())
        super().__init__(name=name, policy=chosen, children=children)
        self.policy_name = policy


@register
class Retry(Declared, py_trees.decorators.Retry):
    """Restart the child after a failure, up to num_attempts attempts."""

    KIND = "decorator"
    NUM_ATTEMPTS = InputPort("num_attempts", int, minimum=1, literal_only=True, doc="attempts before giving up")
    PORTS = (NUM_ATTEMPTS,)
    BTCPP = "RetryUntilSuccessful"
    CHILDREN = (1, 1)

    def __init__(self, name: str, child: Behaviour, num_attempts: int) -> None:
        super().__init__(name=name, child=child, num_failures=num_attempts)


@register
class Repeat(Declared, py_trees.decorators.Repeat):
    """Run the child again after each success, num_cycles times; FAILURE on a failure."""

    KIND = "decorator"
    NUM_CYCLES = InputPort("num_cycles", int, minimum=-1, literal_only=True, doc="successes needed; -1 repeats forever")
    PORTS = (NUM_CYCLES,)
    CHILDREN = (1, 1)

    def __init__(self, name: str, child: Behaviour, num_cycles: int) -> None:
        super().__init__(name=name, child=child, num_success=num_cycles)


@register
class Inverter(Declared, py_trees.decorators.Inverter):
    """Swap SUCCESS and FAILURE."""

    KIND = "decorator"
    CHILDREN = (1, 1)


@register
class ForceSuccess(Declared, py_trees.decorators.FailureIsSuccess):
    """SUCCESS when the child finishes, whatever it returned."""

    KIND = "decorator"
    CHILDREN = (1, 1)


@register
class ForceFailure(Declared, py_trees.decorators.SuccessIsFailure):
    """FAILURE when the child finishes, whatever it returned."""

    KIND = "decorator"
    CHILDREN = (1, 1)


@register
class OneShot(Declared, py_trees.decorators.OneShot):
    """Run the child to completion once, then keep returning that result."""

    KIND = "decorator"
    POLICY = InputPort("policy", str, "on_success", choices=("on_success", "on_completion"), literal_only=True,
                       doc="latch after the first success, or after the first completion")
    PORTS = (POLICY,)
    BTCPP = "RunOnce"
    CHILDREN = (1, 1)

    def __init__(self, name: str, child: Behaviour, policy: str = "on_success") -> None:
        chosen = OneShotPolicy.ON_COMPLETION if policy == "on_completion" else OneShotPolicy.ON_SUCCESSFUL_COMPLETION
        super().__init__(name=name, child=child, policy=chosen)


@register
class Success(Declared, py_trees.behaviours.Success):  # type: ignore[valid-type,misc]
    """Always SUCCESS."""

    BTCPP = "AlwaysSuccess"


@register
class Failure(Declared, py_trees.behaviours.Failure):  # type: ignore[valid-type,misc]
    """Always FAILURE."""

    BTCPP = "AlwaysFailure"


@register
class Running(Declared, py_trees.behaviours.Running):  # type: ignore[valid-type,misc]
    """Always RUNNING."""

    BTCPP = "AlwaysRunning"
