"""Keys from the terminal a mission runs in, read without ever blocking (the teleop driver).

:class:`TerminalKeys` puts the terminal in cbreak mode (keys arrive one by one, unechoed; Ctrl-C
still sends SIGINT, so the runner's safety stop works as ever), and :meth:`TerminalKeys.read`
returns the keys typed since the last call, polling with a zero timeout. Arrow keys arrive as
escape sequences and come out as ``up``, ``down``, ``left``, ``right``; space is ``space``,
Enter is ``enter``, other keys their lower-case character. The terminal's settings are restored
by :meth:`close` (and at exit, should nobody call it).

Behaviours never import this module: the runner hands the tree an opener
(:data:`~drivers.interfaces.KeyboardOpener`) at setup, and a node that drives by keys opens the
terminal through it when it first runs.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import select
import sys

ESCAPES = {"\x1b[A": "up", "\x1b[B": "down", "\x1b[C": "right", "\x1b[D": "left",
           "\x1bOA": "up", "\x1bOB": "down", "\x1bOC": "right", "\x1bOD": "left"}
NAMED = {" ": "space", "\n": "enter", "\r": "enter", "\x1b": "escape"}


def parse_keys(text: str) -> list[str]:
    """Key names in ``text``: escape sequences of the arrow keys, named keys, characters."""
    keys: list[str] = []
    i = 0
    while i < len(text):
        sequence = text[i:i + 3]
        if sequence in ESCAPES:
            keys.append(ESCAPES[sequence])
            i += 3
            continue
        char = text[i]
        keys.append(NAMED.get(char, char.lower()))
        i += 1
    return keys


class TerminalKeys:
    """The keys of the controlling terminal on standard input (OSError when it is not a terminal).

    A :class:`~drivers.interfaces.KeySource`; the class itself is the runner's
    :data:`~drivers.interfaces.KeyboardOpener` (constructing it opens the terminal).
    """

    def __init__(self, fd: int | None = None) -> None:
        import termios
        import tty

        try:
            self.fd = sys.stdin.fileno() if fd is None else fd
            terminal = os.isatty(self.fd)
        except (OSError, ValueError, AttributeError):  # a replaced or closed stdin has no descriptor
            terminal = False
        if not terminal:
            raise OSError("standard input is not a terminal: run the mission from a terminal to drive with keys")
        self._termios = termios
        self._saved = termios.tcgetattr(self.fd)
        tty.setcbreak(self.fd)
        self._closed = False
        atexit.register(self.close)

    def read(self) -> list[str]:
        if self._closed:
            return []
        data = b""
        while select.select([self.fd], [], [], 0.0)[0]:  # zero timeout: never blocks
            chunk = os.read(self.fd, 1024)
            if not chunk:
                break
            data += chunk
        return parse_keys(data.decode("utf-8", errors="replace"))

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            with contextlib.suppress(Exception):  # the terminal may be gone already
                self._termios.tcsetattr(self.fd, self._termios.TCSADRAIN, self._saved)
