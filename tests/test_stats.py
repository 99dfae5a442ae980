"""rrtdrive.stats: the one aggregation (scipy.stats intervals)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.stats import Interval, describe, wilson_interval
from rrtdrive.types import InputError


def _hand_wilson(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    p = k / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


@pytest.mark.parametrize(("k", "n"), [(0, 1), (1, 1), (0, 10), (5, 10), (10, 10), (7, 20)])
def test_wilson_matches_the_score_formula(k, n):
    assert wilson_interval(k, n) == pytest.approx(_hand_wilson(k, n), abs=1e-12)


def test_wilson_rejects_fractions():
    with pytest.raises(InputError, match="successes"):
        wilson_interval(2.5, 10)
    assert all(math.isnan(v) for v in wilson_interval(0, 0))


def test_describe_orders_and_kinds():
    s = describe([3.0, 1.0, 2.0, 10.0])
    assert (s.min, s.median, s.max) == (1.0, 2.5, 10.0)
    assert s.interval is Interval.T and not s.rate
    assert describe([1.0, 0.0], rate=True).interval is Interval.WILSON
    b = describe([3.0, 1.0, 2.0, 10.0], nonnegative=True)
    assert b.interval is Interval.BOOTSTRAP and b.mean == s.mean and b.std == s.std
    assert 1.0 <= b.ci_low < b.mean < b.ci_high <= 10.0
    # A fixed seed: the same sample always gets the same interval.
    again = describe([3.0, 1.0, 2.0, 10.0], nonnegative=True)
    assert (again.ci_low, again.ci_high) == (b.ci_low, b.ci_high)
    same = describe([2.0, 2.0, 2.0], nonnegative=True)
    assert (same.ci_low, same.ci_high) == (2.0, 2.0)
    one = describe([7.0], nonnegative=True)
    assert one.mean == 7.0 and math.isnan(one.ci_low) and one.max == 7.0
    empty = describe([])
    assert empty.n == 0 and math.isnan(empty.median)


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.one_of(st.just(0.0), st.floats(0.0, 1e6, allow_nan=False, allow_infinity=False)),
        min_size=2,
        max_size=30,
    )
)
def test_a_nonnegative_sample_never_gets_a_negative_bound(values):
    s = describe(values, nonnegative=True)
    assert s.ci_low >= 0.0
    assert min(values) - 1e-9 <= s.ci_low <= s.ci_high <= max(values) + 1e-9
    # Student's t would go below zero for a skewed sample such as [0, 0, 0, 100].
    assert describe([0.0, 0.0, 0.0, 100.0]).ci_low < 0.0


def test_t_interval_is_scipys():
    from scipy import stats

    x = np.array([1.0, 2.0, 4.0, 8.0])
    s = describe(x)
    half = stats.t.ppf(0.975, 3) * x.std(ddof=1) / 2
    assert (s.ci_low, s.ci_high) == (pytest.approx(x.mean() - half), pytest.approx(x.mean() + half))
