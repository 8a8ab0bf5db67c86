"""Drive the robot from the keyboard of the terminal the mission runs in (teaching on a robot).

``KeyboardTeleop`` reads a non-blocking key source (:class:`drivers.keyboard.KeySource`) every
tick, never waiting for a key: up/``w`` forward, down/``s`` backward, left/``a`` and right/``d``
turn on the spot, space stops, ``q`` or Enter ends the drive (SUCCESS, so a teach mission saves
its route). A key holds its motion for ``key_timeout`` seconds of tree time: the terminal's
auto-repeat keeps a held key alive, and the robot stops when keys stop arriving.

The key source is handed in at setup (``setup(keys=...)``; tests pass
:class:`drivers.fake.FakeKeys`); without one, the node opens the terminal on standard input
when it first runs, and gives it back when it ends.
"""

from __future__ import annotations

import math
from typing import Any

from py_trees.common import Status

from behaviours.base import BearingsBehaviour
from behaviours.motion import COMMAND
from behaviours.ports import InputPort
from behaviours.registry import register
from drivers.interfaces import STOP, VelocityCommand

MOTIONS = {"up": (1, 0), "w": (1, 0), "down": (-1, 0), "s": (-1, 0),
           "left": (0, 1), "a": (0, 1), "right": (0, -1), "d": (0, -1), "space": (0, 0)}
FINISH = ("q", "enter")


@register
class KeyboardTeleop(BearingsBehaviour):
    """Drive with arrow keys or WASD, space to stop; q or Enter ends (SUCCESS).

    RUNNING while the operator drives; the command falls to zero when no key arrived for
    ``key_timeout``. FAILURE when there is no keyboard (standard input is not a terminal).
    """

    PORTS = (
        InputPort("speed", float, 0.2, unit="m/s", minimum=0.01, maximum=1.2, doc="forward/backward speed"),
        InputPort("turn_rate", float, 30.0, unit="deg/s", minimum=1.0, maximum=300.0, doc="turn rate"),
        InputPort("key_timeout", float, 0.5, unit="s", minimum=0.05, doc="stop when no key came for this long"),
        COMMAND,
    )

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self.keys: Any = None  # a drivers.keyboard.KeySource
        self._opened = False
        self._motion = (0, 0)
        self._last_key = -math.inf

    def setup(self, **kwargs: Any) -> None:
        super().setup(**kwargs)
        self.keys = kwargs.get("keys", self.keys)

    def initialise(self) -> None:
        self._motion, self._last_key = (0, 0), -math.inf

    def _source(self) -> Any:
        if self.keys is None:
            from drivers.keyboard import TerminalKeys  # the terminal is opened only when a mission drives by keys

            self.keys, self._opened = TerminalKeys(), True
        return self.keys

    def update(self) -> Status:
        try:
            source = self._source()
        except OSError as exc:
            self.feedback_message = str(exc)
            self.set_output("command", STOP)
            return Status.FAILURE
        now = self.now()
        for key in source.read():
            if key in FINISH:
                self.feedback_message = "the operator ended the drive"
                self.set_output("command", STOP)
                return Status.SUCCESS
            if key in MOTIONS:
                self._motion, self._last_key = MOTIONS[key], now
        if now - self._last_key > float(self.get_input("key_timeout")):
            self._motion = (0, 0)
        forward, turn = self._motion
        command = VelocityCommand(forward * float(self.get_input("speed")),
                                  turn * math.radians(float(self.get_input("turn_rate"))))
        self.set_output("command", command)
        self.feedback_message = "arrows/WASD drive, space stops, q or Enter ends"
        return Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        if self._opened and new_status != Status.RUNNING and self.keys is not None:
            self.keys.close()
            self.keys, self._opened = None, False
