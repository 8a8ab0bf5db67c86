"""A grid of cells as text, for reports: the explored cells of the final exploration map, which an
evaluation unpacks to compare with what was really seen (base64 of the row-major packed bits)."""

from __future__ import annotations

import base64

import numpy as np


def pack_cells(mask: np.ndarray) -> str:
    """A boolean grid as base64 of its packed bits (row-major), for reports."""
    return base64.b64encode(np.packbits(mask.astype(bool).ravel()).tobytes()).decode("ascii")


def unpack_cells(text: str, rows: int, cols: int) -> np.ndarray:
    """The inverse of :func:`pack_cells`."""
    bits = np.unpackbits(np.frombuffer(base64.b64decode(text), dtype=np.uint8))
    return bits[: rows * cols].reshape(rows, cols).astype(bool)
