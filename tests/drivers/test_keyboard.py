"""The terminal keyboard (drivers/keyboard.py): key names, and no terminal is a clear OSError."""

from __future__ import annotations

import os

import pytest

from drivers.interfaces import KeySource
from drivers.keyboard import TerminalKeys, parse_keys


def test_without_a_terminal_opening_fails_and_never_blocks():
    read, write = os.pipe()  # not a terminal
    try:
        with pytest.raises(OSError, match="not a terminal"):
            TerminalKeys(read)
    finally:
        os.close(read)
        os.close(write)


def test_parse_keys_names_arrows_and_specials():
    assert parse_keys("\x1b[A\x1b[Dw \nQ\x1bOB") == ["up", "left", "w", "space", "enter", "q", "down"]


def test_terminal_keys_is_a_key_source():
    assert issubclass(TerminalKeys, KeySource)  # the interface behaviours see
