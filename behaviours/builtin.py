"""Registration of the control-flow node types every mission can use.

Composites and decorators map onto py_trees' own classes wherever py_trees has the semantics;
``Timeout`` and ``RateController`` use the tree's clock, ``RecoveryNode`` follows Nav2. The
``btcpp`` names are what ``bearings show --format xml`` writes for Groot2.
"""

from __future__ import annotations

import py_trees
from py_trees.common import OneShotPolicy, ParallelPolicy

from behaviours import conditions, motion, perceive, sense, wait  # noqa: F401  (register leaf behaviours)
from behaviours.composites import RecoveryNode
from behaviours.decorators import RateController, Timeout, make_guard
from behaviours.ports import COMPARISONS, Param
from behaviours.registry import NodeType, register_type

MEMORY_DOC = (
    "true: resume at the running child on the next tick (BehaviorTree.CPP Sequence/Fallback); "
    "false: re-tick from the first child every tick (ReactiveSequence/ReactiveFallback)"
)


def _sequence(name: str, children: list, memory: bool) -> py_trees.behaviour.Behaviour:
    return py_trees.composites.Sequence(name=name, memory=memory, children=children)


def _selector(name: str, children: list, memory: bool) -> py_trees.behaviour.Behaviour:
    return py_trees.composites.Selector(name=name, memory=memory, children=children)


def _parallel(name: str, children: list, policy: str, synchronise: bool) -> py_trees.behaviour.Behaviour:
    chosen = ParallelPolicy.SuccessOnAll(synchronise=synchronise) if policy == "all" else (
        ParallelPolicy.SuccessOnOne()
    )
    return py_trees.composites.Parallel(name=name, policy=chosen, children=children)


def _recovery(name: str, children: list, number_of_retries: int) -> py_trees.behaviour.Behaviour:
    return RecoveryNode(name=name, children=children, number_of_retries=number_of_retries)


def _decorator(cls, **renames: str):  # noqa: ANN001, ANN202 - small adapter
    def build(name: str, child: py_trees.behaviour.Behaviour, **params: object) -> py_trees.behaviour.Behaviour:
        return cls(name=name, child=child, **{renames.get(k, k): v for k, v in params.items()})

    return build


def _one_shot(name: str, child: py_trees.behaviour.Behaviour, policy: str) -> py_trees.behaviour.Behaviour:
    chosen = OneShotPolicy.ON_COMPLETION if policy == "on_completion" else (
        OneShotPolicy.ON_SUCCESSFUL_COMPLETION
    )
    return py_trees.decorators.OneShot(name=name, child=child, policy=chosen)


MEMORY = Param("memory", "bool", True, doc=MEMORY_DOC, refs=False)
_KEY = Param("key", "key", doc="blackboard key (absolute), optionally with an attribute: /robot/odometry.x",
             refs=False)
_OP = Param("op", "str", "==", doc="comparison", choices=COMPARISONS, refs=False)
_VALUE = Param("value", "any", doc="the value to compare with", refs=False)

_M = "behaviours.builtin"
for _node in (
    NodeType("Sequence", "composite", _sequence, (MEMORY,), btcpp="Sequence", min_children=1, module=_M,
             doc="Tick children in order; FAILURE at the first failure, SUCCESS when all succeed."),
    NodeType("Selector", "composite", _selector, (MEMORY,), btcpp="Fallback", min_children=1, module=_M,
             doc="Tick children in order until one does not fail (a fallback)."),
    NodeType(
        "Parallel", "composite", _parallel,
        (Param("policy", "str", "all", doc="all: SUCCESS when every child succeeded; one: when any did",
               choices=("all", "one"), refs=False),
         Param("synchronise", "bool", True, doc="with policy all: do not re-tick children that succeeded",
               refs=False)),
        btcpp="Parallel", min_children=1, module=_M,
        doc="Tick every child each tick; FAILURE as soon as one fails.",
    ),
    NodeType(
        "RecoveryNode", "composite", _recovery,
        (Param("number_of_retries", "int", 1, doc="recoveries to try", minimum=0, refs=False),),
        btcpp="RecoveryNode", min_children=2, max_children=2, module=_M,
        doc="Nav2 recovery: tick the task; on failure tick the recovery and retry the task.",
    ),
    NodeType("Timeout", "decorator", _decorator(Timeout),
             (Param("duration", "float", unit="s", doc="time limit in tree time", minimum=0.0, refs=False),),
             btcpp="Timeout", min_children=1, max_children=1, module=_M,
             doc="FAILURE, halting the child, when it runs longer than duration (tree clock)."),
    NodeType("Retry", "decorator", _decorator(py_trees.decorators.Retry, num_attempts="num_failures"),
             (Param("num_attempts", "int", doc="attempts before giving up", minimum=1, refs=False),),
             btcpp="RetryUntilSuccessful", min_children=1, max_children=1, module=_M,
             doc="Restart the child after a failure, up to num_attempts attempts."),
    NodeType("Repeat", "decorator", _decorator(py_trees.decorators.Repeat, num_cycles="num_success"),
             (Param("num_cycles", "int", doc="successes needed; -1 repeats forever", minimum=-1, refs=False),),
             btcpp="Repeat", min_children=1, max_children=1, module=_M,
             doc="Run the child again after each success, num_cycles times; FAILURE on a failure."),
    NodeType("Inverter", "decorator", _decorator(py_trees.decorators.Inverter), (),
             btcpp="Inverter", min_children=1, max_children=1, module=_M,
             doc="Swap SUCCESS and FAILURE."),
    NodeType("ForceSuccess", "decorator", _decorator(py_trees.decorators.FailureIsSuccess), (),
             btcpp="ForceSuccess", min_children=1, max_children=1, module=_M,
             doc="SUCCESS when the child finishes, whatever it returned."),
    NodeType("ForceFailure", "decorator", _decorator(py_trees.decorators.SuccessIsFailure), (),
             btcpp="ForceFailure", min_children=1, max_children=1, module=_M,
             doc="FAILURE when the child finishes, whatever it returned."),
    NodeType("OneShot", "decorator", _one_shot,
             (Param("policy", "str", "on_success", choices=("on_success", "on_completion"), refs=False,
                    doc="latch after the first success, or after the first completion"),),
             btcpp="RunOnce", min_children=1, max_children=1, module=_M,
             doc="Run the child to completion once, then keep returning that result."),
    NodeType("RateController", "decorator", _decorator(RateController),
             (Param("hz", "float", unit="Hz", doc="highest tick rate of the child", minimum=1e-6, refs=False),),
             btcpp="RateController", min_children=1, max_children=1, module=_M,
             doc="Tick the child at most hz times per second (tree clock); RUNNING in between."),
    NodeType("Guard", "decorator", make_guard, (_KEY, _OP, _VALUE),
             btcpp="Precondition", min_children=1, max_children=1, module=_M,
             doc="Tick the child only while the blackboard condition holds; FAILURE otherwise."),
    NodeType("Success", "action", lambda name: py_trees.behaviours.Success(name=name), (),
             btcpp="AlwaysSuccess", module=_M, doc="Always SUCCESS."),
    NodeType("Failure", "action", lambda name: py_trees.behaviours.Failure(name=name), (),
             btcpp="AlwaysFailure", module=_M, doc="Always FAILURE."),
    NodeType("Running", "action", lambda name: py_trees.behaviours.Running(name=name), (),
             btcpp="AlwaysRunning", module=_M, doc="Always RUNNING."),
):
    register_type(_node)
