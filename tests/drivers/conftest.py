"""Fixtures for the hardware driver tests: emulators and drivers that are always shut down.

Every emulator and driver made through these fixtures is closed at teardown (threads joined, ptys and
sockets closed), and a crash inside an emulator's thread fails the test that caused it. Timings are
shortened (SIPs every 20 ms, a 0.2 s SIP timeout...) so the fault tests take fractions of a second.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any, TypeVar

import pytest

from drivers.pioneer import PioneerBase, open_base
from drivers.ptu_d46 import PtuD46, open_ptu
from tests.drivers.arcos_emulator import ArcosEmulator
from tests.drivers.ptu_emulator import PtuEmulator

E = TypeVar("E", ArcosEmulator, PtuEmulator)

FAST_EMULATOR = {"sip_period": 0.02}
FAST_BASE = {"sip_timeout": 0.2, "resend_period": 0.05, "reply_timeout": 0.1, "connect_timeout": 8.0,
             "command_timeout": 5.0}
FAST_PTU = {"reply_timeout": 0.2, "poll_period": 0.03, "init_settle": 0.04}


@pytest.fixture
def arcos() -> Iterator[Callable[..., ArcosEmulator]]:
    """``arcos(**options)`` starts an ARCOS emulator (pty unless ``transport="tcp"``)."""
    yield from _started("ARCOS", lambda **options: ArcosEmulator(**{**FAST_EMULATOR, **options}).start())


@pytest.fixture
def ptu_emulator() -> Iterator[Callable[..., PtuEmulator]]:
    """``ptu_emulator(**options)`` starts a PTU-D46 emulator."""
    yield from _started("PTU", lambda **options: PtuEmulator(**options).start())


def _started(name: str, start: Callable[..., E]) -> Iterator[Callable[..., E]]:
    """A fixture's factory that remembers what ``start`` made; at teardown each is closed, then a
    crash inside any of them fails the test."""
    made: list[E] = []

    def make(**options: Any) -> E:
        emulator = start(**options)
        made.append(emulator)
        return emulator

    yield make
    for emulator in made:
        emulator.close()
    for emulator in made:
        assert emulator.crashed is None, f"the {name} emulator crashed: {emulator.crashed!r}"


@pytest.fixture
def devices() -> Iterator[Callable[[Any], Any]]:
    """``devices(x)`` returns ``x`` and closes it at teardown (drivers, robots)."""
    opened: list[Any] = []

    def keep(device: Any) -> Any:
        opened.append(device)
        return device

    yield keep
    for device in reversed(opened):
        device.close()


@pytest.fixture
def base(arcos, devices) -> Callable[..., tuple[PioneerBase, ArcosEmulator]]:
    """``base(emulator options..., settings=...)``: an emulator and a Pioneer driver connected to it."""

    def make(settings: dict[str, Any] | None = None, **options: Any) -> tuple[PioneerBase, ArcosEmulator]:
        emulator = arcos(**options)
        fields = {"port": emulator.port, **FAST_BASE, **(settings or {})}
        return devices(open_base(**fields)), emulator

    return make


@pytest.fixture
def ptu(ptu_emulator, devices) -> Callable[..., tuple[PtuD46, PtuEmulator]]:
    def make(settings: dict[str, Any] | None = None, **options: Any) -> tuple[PtuD46, PtuEmulator]:
        emulator = ptu_emulator(**options)
        return devices(open_ptu(port=emulator.port, **{**FAST_PTU, **(settings or {})})), emulator

    return make
