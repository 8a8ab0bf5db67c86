"""Shared check of the property tests on input files: a value or located diagnostics, nothing else."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from maps.store import InputError


def examples(count: int) -> int:
    """How many examples a fuzz test draws: ``count`` in the suite, 20x with HYPOTHESIS_PROFILE=fuzz."""
    return count * 20 if os.environ.get("HYPOTHESIS_PROFILE") == "fuzz" else count


def load_or_diagnose(data: bytes, load: Callable[[Path], Any], *, name: str = "input.yaml") -> Any:
    """Write ``data`` to a file and load it; an InputError must carry messages; None then."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / name
        path.write_bytes(data)
        try:
            return load(path)
        except InputError as exc:
            assert exc.diagnostics
            for diagnostic in exc.diagnostics:
                assert isinstance(diagnostic.message, str) and diagnostic.message
                assert diagnostic.line >= 0 and diagnostic.col >= 0
            return None
