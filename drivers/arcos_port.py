"""The byte link to an ARCOS robot: one pyserial port, its packet reader, and the speed it runs at.

:class:`drivers.pioneer.PioneerBase` owns one :class:`ArcosPort`. Writes are serialised by a
re-entrant lock (``stop()`` writes from any thread, also from a signal handler); reads happen on
one thread at a time (the connecting thread, then the I/O thread). The two speed changes of the
protocol live here, as ARIA's ``ArRobot::asyncConnectHandler`` does them (docs/protocols.md):
HOSTBAUD to a faster speed when the robot allows it (:meth:`ArcosPort.switch_speed`), and CLOSE
at every speed for a robot that a client left open at another one
(:meth:`ArcosPort.close_at_every_speed`).
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable
from typing import Any

import serial

from drivers import arcos
from drivers.arcos import Command, PacketReader

log = logging.getLogger(__name__)

READ_TIMEOUT_S = 0.01  # how long one read may wait: bounds the I/O thread's command latency
WRITE_TIMEOUT_S = 0.2
BAUD_SETTLE_S = 0.01  # ARIA: 10 ms after HOSTBAUD, and again after switching its own port
BAUD_PROOF_S = 0.9  # ARIA: no packet at the new speed within this long, back to the old one
PULSE_PERIOD_S = 0.1  # a PULSE every SIP cycle while waiting for that packet
CLOSE_ALL_BAUDS = (9600, 38400, 115200, 19200, 57600)  # ARIA's order
CLOSE_ALL_PAUSE_S = 0.003  # ARIA: 3 ms between them


class ArcosPort:
    """A port that carries ARCOS packets; :meth:`open` it, then send and receive payloads."""

    def __init__(self, url: str, factory: Callable[..., Any]) -> None:
        self.url = url
        self.baud: int | None = None  # the speed in use; None for a URL (MobileSim's TCP, a serial server)
        self.reader = PacketReader()
        self._factory = factory
        self._serial: Any = None
        self._lock = threading.RLock()
        self._pending: list[bytes] = []

    @property
    def is_device(self) -> bool:
        """A serial device (its speed can be set), not a ``socket://``/``rfc2217://`` URL."""
        return "://" not in self.url

    @property
    def is_open(self) -> bool:
        return self._serial is not None

    def open(self, baud: int) -> None:
        """Open at ``baud``; ``ConnectionError`` naming the port when it cannot be opened."""
        try:
            self._serial = self._factory(self.url, baudrate=baud, timeout=READ_TIMEOUT_S,
                                         write_timeout=WRITE_TIMEOUT_S)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise ConnectionError(f"cannot open the Pioneer port {self.url}: {exc}") from None
        self.reader = PacketReader()
        self._pending = []
        self.baud = baud if self.is_device else None

    def fileno(self) -> int | None:
        """The open port's file descriptor (for the link guard), None when it has none."""
        try:
            return int(self._serial.fileno())
        except (AttributeError, OSError, ValueError, TypeError, serial.SerialException):
            return None

    def send(self, data: bytes) -> None:
        with self._lock:
            if self._serial is None:
                raise serial.SerialException("port closed")
            self._serial.write(data)

    def flush(self) -> None:
        """Wait until what was written is on the wire."""
        with self._lock:
            if self._serial is not None:
                self._serial.flush()

    def read(self) -> list[bytes]:
        """The payloads completed by what arrived (waits up to ``READ_TIMEOUT_S`` for a first byte)."""
        port = self._serial
        if port is None:
            raise serial.SerialException("port closed")
        data = port.read(port.in_waiting or 1)
        return self.reader.feed(data) if data else []

    def next_packet(self, until: float) -> bytes | None:
        """The next valid payload before ``until``, else None (used while connecting)."""
        while not self._pending:
            if time.monotonic() >= until:
                return None
            self._pending = self.read()
        return self._pending.pop(0)

    def forget_input(self) -> None:
        """Drop what was received and not yet used."""
        with contextlib.suppress(serial.SerialException, OSError, AttributeError):
            self._serial.reset_input_buffer()
        self.reader.clear()
        self._pending = []

    def close_at_every_speed(self) -> None:
        """CLOSE at every speed, then back to ours: a robot still open at another speed hears one of
        them and goes back to its start speed (ARIA, after two unanswered SYNC0)."""
        if not self.is_device or self._serial is None:
            return
        log.info("no answer on %s; sending CLOSE at every speed", self.url)
        start = self._serial.baudrate
        for baud in CLOSE_ALL_BAUDS:
            self._serial.baudrate = baud
            self.send(arcos.encode_command(Command.CLOSE))
            self.flush()
            time.sleep(CLOSE_ALL_PAUSE_S)
        self._serial.baudrate = start
        self.forget_input()

    def switch_speed(self, target: int) -> bool:
        """HOSTBAUD to ``target``, switch our side, PULSE until a packet arrives at the new speed; True
        then (the packet is kept for the caller), else back to the old speed after 0.9 s."""
        start = self.baud
        if start is None or self._serial is None or target == start:
            return False
        self.forget_input()
        self.send(arcos.encode_command(Command.HOSTBAUD, arcos.BAUD_CODES[target]))
        self.flush()
        time.sleep(BAUD_SETTLE_S)
        self._serial.baudrate = target
        time.sleep(BAUD_SETTLE_S)
        self.forget_input()  # a packet that arrived at the old speed proves nothing (ARIA takes it)
        end = time.monotonic() + BAUD_PROOF_S
        while time.monotonic() < end:
            self.send(arcos.encode_command(Command.PULSE))
            payload = self.next_packet(min(end, time.monotonic() + PULSE_PERIOD_S))
            if payload is not None:
                self._pending.insert(0, payload)
                self.baud = target
                return True
        self._serial.baudrate = start
        self.forget_input()
        return False

    def release(self) -> None:
        """Close the port (never raises); later sends raise ``SerialException``."""
        with self._lock:
            port, self._serial = self._serial, None
        if port is not None:
            with contextlib.suppress(Exception):
                port.close()
        self._pending = []
