"""The values a validated mission is made of: the specification the builder turns into a tree.

The YAML syntax (see docs/missions.md)::

    mission: square                     # name (default: the file name)
    description: Drive a 1 m square.
    inputs:                             # substituted at load time as ${side}; --set side=2
      side: {type: float, default: 1.0, unit: m, description: length of a side}
    plugins: [my_robot.behaviours]      # modules whose node types the mission may use, explicitly
    rate: 10                            # tick rate in Hz
    tree:                               # one node: TypeName: {parameters}
      Sequence:
        children:
          - Drive: {distance: "${side}"}
          - Rotate: {angle: 90}
          - include: turn_back.yaml     # a subtree from another mission file
            inputs: {speed: 0.2}
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from behaviours.ports import InputPort
from behaviours.registry import Registry
from maps.store import OutputFolders


@dataclass(frozen=True)
class Location:
    """Where something was written: file and 1-based line/column."""

    file: str
    line: int = 0
    col: int = 0

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}" if self.line else self.file


@dataclass(frozen=True)
class NodeSpec:
    """One validated node: its registered type, name, bound ports and children.

    ``inputs`` maps every input port to its literal or :class:`~behaviours.ports.Ref` (defaults
    filled in); ``outputs`` maps every output port to the blackboard key it writes (remapped or
    the port's default); ``locations`` says where each port given in the file was written.
    """

    type: str
    name: str
    inputs: dict[str, Any]
    children: tuple[NodeSpec, ...] = ()
    location: Location = Location("<unknown>")
    included_from: str | None = None  # the include file this node's subtree came from
    outputs: dict[str, str] = field(default_factory=dict)
    locations: dict[str, Location] = field(default_factory=dict, compare=False)

    @property
    def ports(self) -> dict[str, Any]:
        """Inputs and outputs together, as a mission writes them (outputs as keys)."""
        return {**self.inputs, **self.outputs}

    def where(self, port: str) -> Location:
        """Where a port was written (the node itself for a default)."""
        return self.locations.get(port, self.location)

    def walk(self):
        """This node and all nodes below it, depth first."""
        yield self
        for child in self.children:
            yield from child.walk()


@dataclass(frozen=True)
class MissionSpec:
    """A loaded, validated mission, with its inputs already substituted."""

    name: str
    file: str
    tree: NodeSpec
    description: str = ""
    inputs: dict[str, InputPort] = field(default_factory=dict)
    values: dict[str, Any] = field(default_factory=dict)
    sense: tuple[NodeSpec, ...] = ()
    plugins: tuple[str, ...] = ()
    rate_hz: float = 10.0
    max_time_s: float | None = None
    overrun_s: float = 1.0  # how far a tick may overrun its period before the watchdog stops the base
    evaluation: dict[str, Any] = field(default_factory=dict)
    cameras: tuple[str, ...] | None = None  # the cameras this mission grabs; None: every camera
    files: tuple[str, ...] = ()  # this file and every file it includes
    registry: Registry = field(default_factory=Registry.default, compare=False, repr=False)
    # where the mission's files go (missions/outputs.py); None: paths are used as written
    folders: OutputFolders | None = field(default=None, compare=False, repr=False)
