"""The report's text form of a grid of cells."""

from __future__ import annotations

import numpy as np

from maps.exploration.codec import pack_cells, unpack_cells


def test_packed_cells_round_trip():
    mask = np.random.default_rng(1).random((7, 13)) > 0.5
    assert np.array_equal(unpack_cells(pack_cells(mask), 7, 13), mask)


def test_packed_bits_are_row_major_by_hand():
    mask = np.zeros((2, 4), dtype=bool)
    mask[0, 0] = mask[1, 3] = True  # bits 10000001: one byte, 0x81
    assert pack_cells(mask) == "gQ=="  # base64 of b"\x81"
