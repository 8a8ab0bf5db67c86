"""The life cycle the protocol emulators share: a daemon thread running ``_loop`` while started,
joined on close, usable as a context manager."""

from __future__ import annotations

import threading
from typing import Self


class EmulatorThread:
    """Base of an emulator that serves its link from a thread. Subclasses implement ``_loop``
    (return when ``running`` is cleared) and ``_release`` (close the link and whatever else)."""

    THREAD_NAME = "emulator"

    def __init__(self) -> None:
        self._running = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> Self:
        self._running.set()
        self._thread = threading.Thread(target=self._loop, name=self.THREAD_NAME, daemon=True)
        self._thread.start()
        return self

    def close(self) -> None:
        self._running.clear()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        self._release()

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _loop(self) -> None:
        raise NotImplementedError

    def _release(self) -> None:
        raise NotImplementedError
