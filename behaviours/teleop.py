"""Drive the robot from the keyboard of the terminal the mission runs in (teaching on a robot).

``KeyboardTeleop`` reads a non-blocking key source (:class:`drivers.interfaces.KeySource`) every
tick, never waiting for a key: up/``w`` forward, down/``s`` backward, left/``a`` and right/``d``
turn on the spot, space stops, ``q`` or Enter ends the drive (SUCCESS, so a teach mission saves
its route). A key holds its motion for ``key_timeout`` seconds of tree time: the terminal's
auto-repeat keeps a held key alive, and the robot stops when keys stop arriving.

The keyboard reaches the node like the other drivers, at setup: the runner hands the tree an
opener (``setup(keyboard=...)``, :data:`drivers.interfaces.KeyboardOpener`; the terminal on
standard input by default, tests hand one returning :class:`drivers.fake.FakeKeys`). The node
opens the keyboard when it first runs, so a mission that never drives by keys never takes the
terminal, and gives it back when it ends.
"""

from __future__ import annotations

import math
from typing import Any

from py_trees.common import Status

from behaviours.base import BearingsBehaviour, NotSetUp
from behaviours.motion import COMMAND
from behaviours.ports import InputPort
from behaviours.registry import register
from drivers.interfaces import STOP, KeyboardOpener, KeySource, VelocityCommand

MOTIONS = {"up": (1, 0), "w": (1, 0), "down": (-1, 0), "s": (-1, 0),
           "left": (0, 1), "a": (0, 1), "right": (0, -1), "d": (0, -1), "space": (0, 0)}
FINISH = ("q", "enter")


@register
class KeyboardTeleop(BearingsBehaviour):
    """Drive with arrow keys or WASD, space to stop; q or Enter ends (SUCCESS).

    RUNNING while the operator drives; the command falls to zero when no key arrived for
    ``key_timeout``. FAILURE when there is no keyboard (standard input is not a terminal).
    """

    SPEED = InputPort("speed", float, 0.2, unit="m/s", minimum=0.01, maximum=1.2, doc="forward/backward speed")
    TURN_RATE = InputPort("turn_rate", float, 30.0, unit="deg/s", minimum=1.0, maximum=300.0, doc="turn rate")
    KEY_TIMEOUT = InputPort("key_timeout", float, 0.5, unit="s", minimum=0.05,
                            doc="stop when no key came for this long")
    PORTS = (SPEED, TURN_RATE, KEY_TIMEOUT, COMMAND)

    def __init__(self, name: str | None = None, **ports: Any) -> None:
        super().__init__(name=name, **ports)
        self._open_keyboard: KeyboardOpener | None = None
        self.keys: KeySource | None = None  # open while the node drives
        self._motion = (0, 0)
        self._last_key = -math.inf

    def setup(self, **kwargs: Any) -> None:
        super().setup(**kwargs)
        self._open_keyboard = kwargs.get("keyboard", self._open_keyboard)

    def initialise(self) -> None:
        self._motion, self._last_key = (0, 0), -math.inf

    def _source(self) -> KeySource:
        if self.keys is None:
            if self._open_keyboard is None:
                raise NotSetUp(f"{self.name}: no keyboard; set the tree up with setup(keyboard=...)")
            self.keys = self._open_keyboard()
        return self.keys

    def update(self) -> Status:
        try:
            source = self._source()
        except OSError as exc:
            self.feedback_message = str(exc)
            self.set_output(COMMAND, STOP)
            return Status.FAILURE
        now = self.now()
        for key in source.read():
            if key in FINISH:
                self.feedback_message = "the operator ended the drive"
                self.set_output(COMMAND, STOP)
                return Status.SUCCESS
            if key in MOTIONS:
                self._motion, self._last_key = MOTIONS[key], now
        if now - self._last_key > self.get_input(self.KEY_TIMEOUT):
            self._motion = (0, 0)
        forward, turn = self._motion
        command = VelocityCommand(forward * self.get_input(self.SPEED),
                                  turn * math.radians(self.get_input(self.TURN_RATE)))
        self.set_output(COMMAND, command)
        self.feedback_message = "arrows/WASD drive, space stops, q or Enter ends"
        return Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        if new_status != Status.RUNNING and self.keys is not None:
            self.keys.close()
            self.keys = None
