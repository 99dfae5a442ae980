"""The one-row steering-ramp sum: the joint loop's floats, whatever the ramps' overlaps."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.planning.hybrid.ramp_sum import ramp_sum, ramp_sum_full, ramp_sum_one


def _case(lengths: np.ndarray, angles: np.ndarray, factors: np.ndarray, rate: float):
    total = lengths.sum(keepdims=True)
    t = np.linspace(0.0, 1.0, max(2, int(total[0] / 0.01)) + 1)
    s = total[:, None] * t[None, :]
    joints = np.cumsum(lengths)[None, :-1]
    jumps = np.diff(angles)[None, :]
    widths = np.maximum(np.abs(jumps) * factors[None, :] / rate, 1e-9)
    return s, t, total, joints, jumps, widths


def _same(s, t, total, joints, jumps, widths) -> None:
    one = ramp_sum(s, t, total, joints, jumps, widths)
    # Two equal rows take the joint loop (B > 1), with the same floats in each row.
    two = ramp_sum(
        np.vstack([s, s]), t, np.concatenate([total, total]),
        np.vstack([joints, joints]), np.vstack([jumps, jumps]), np.vstack([widths, widths]),
    )  # fmt: skip
    assert one.tobytes() == two[:1].tobytes()
    assert np.array_equal(one, ramp_sum_full(s, joints, jumps, widths))
    flat = ramp_sum_one(s[0], t, total[0], joints[0], jumps[0], widths[0])
    assert flat.tobytes() == one[0].tobytes()


@settings(max_examples=80, deadline=None)
@given(st.integers(2, 30), st.integers(0, 2**32 - 1), st.floats(0.02, 1.0))
def test_one_row_is_the_loop(pieces: int, seed: int, rate: float) -> None:
    """Short pieces and wide ramps: overlapping ramps, and ramps ending out of order."""
    rng = np.random.default_rng(seed)
    lengths = rng.uniform(0.0, 3.0, pieces)
    angles = rng.choice([-0.6, -0.3, 0.0, 0.3, 0.6], pieces) + rng.uniform(-0.01, 0.01, pieces)
    _same(*_case(lengths, angles, rng.uniform(1.0, 3.0, pieces - 1), rate))


def test_a_ramp_that_ends_inside_an_earlier_one() -> None:
    """A wide ramp, then a narrow one that starts and ends within it."""
    lengths = np.array([20.0, 0.5, 20.0])
    angles = np.array([-0.6, 0.6, 0.62])
    _same(*_case(lengths, angles, np.ones(2), 0.15))


def test_equal_angles_and_signed_zeros() -> None:
    """Zero jumps (``-0.0`` among them) and ramps of zero width."""
    lengths = np.array([5.0, 5.0, 5.0, 5.0, 5.0])
    angles = np.array([-0.0, 0.0, -0.0, 0.3, 0.3])
    _same(*_case(lengths, angles, np.ones(4), 0.15))


def test_one_row_not_finite_is_the_full_sum() -> None:
    """NaN or inf in the jumps: the 1-D sum is the full sum's, NaN where it is."""
    s, t, total, joints, jumps, widths = _case(
        np.array([5.0, 5.0, 5.0]), np.array([0.0, np.nan, 0.3]), np.ones(2), 0.15
    )
    flat = ramp_sum_one(s[0], t, total[0], joints[0], jumps[0], widths[0])
    assert np.array_equal(flat, ramp_sum_full(s, joints, jumps, widths)[0], equal_nan=True)
    assert np.isnan(flat).any()
