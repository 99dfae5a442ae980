"""The checker's distance field against scipy's transform: the same values, bit for bit."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from rrtdrive.collision import distance
from rrtdrive.collision.distance import distance_field


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(1, 700), st.integers(1, 120),
       st.floats(0.0, 0.6))
def test_equals_scipys_transform(seed, rows, cols, occupied_share):
    # Up to 700 rows: several of distance_field's blocks of BLOCK_ROWS rows.
    rng = np.random.default_rng(seed)
    free = rng.random((rows, cols)) >= occupied_share
    expected = ndimage.distance_transform_edt(free)
    got = distance_field(free)
    assert got.dtype == expected.dtype == np.float64 and got.shape == expected.shape
    assert np.array_equal(got, expected)


def test_blocks_edges_and_extremes(monkeypatch):
    monkeypatch.setattr(distance, "BLOCK_ROWS", 7)  # many blocks, a last short one
    free = np.ones((50, 3000), dtype=bool)
    free[0, 0] = free[49, 2999] = False  # distances up to ~3000 cells across
    assert np.array_equal(distance_field(free), ndimage.distance_transform_edt(free))
    for grid in (np.ones((5, 5), bool), np.zeros((5, 5), bool), np.ones((1, 1), bool)):
        assert np.array_equal(distance_field(grid), ndimage.distance_transform_edt(grid))
