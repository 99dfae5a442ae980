"""Paths with gears: rows [x, y, yaw, kappa, gear], cusps and gear segments."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.types import InputError, Path

NOWHERE = np.zeros((0, 2))


def _line(x0: float, x1: float, gear: int, n: int = 6) -> np.ndarray:
    xs = np.linspace(x0, x1, n)
    return np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs, np.full(n, float(gear))])


def test_four_columns_get_forward_gear():
    xs = np.linspace(0.0, 3.0, 4)
    p = Path(np.column_stack([xs, xs, 0 * xs, 0 * xs]), NOWHERE)
    assert p.samples.shape == (4, 5)
    assert p.gears.tolist() == [1, 1, 1, 1]
    assert p.is_forward_only and p.cusps.tolist() == [] and p.segments() == [(0, 4)]
    assert p.length == pytest.approx(3 * np.sqrt(2))


def test_empty_path():
    p = Path.empty()
    assert p.samples.shape == (0, 5) and len(p) == 0
    assert p.segments() == [] and p.is_forward_only and p.length == 0.0
    assert Path(np.zeros((0, 4)), NOWHERE).samples.shape == (0, 5)


def test_cusp_row_repeats_and_adds_no_length():
    p = Path(np.vstack([_line(0, 5, 1), _line(5, 2, -1, 4), _line(2, 4, 1, 3)]), NOWHERE)
    assert p.cusps.tolist() == [6, 10]
    assert p.segments() == [(0, 6), (6, 10), (10, 13)]
    assert p.length == pytest.approx(5 + 3 + 2)
    assert not p.is_forward_only
    for a, b in p.segments():
        assert len(set(p.gears[a:b].tolist())) == 1
    # Consecutive segments share the cusp position.
    for (_, b), (c, _) in zip(p.segments()[:-1], p.segments()[1:], strict=True):
        np.testing.assert_array_equal(p.xy[b - 1], p.xy[c])


@pytest.mark.parametrize("gear", [0.0, 2.0, 0.5, np.nan])
def test_bad_gear_is_one_clear_error(gear):
    s = _line(0, 5, 1)
    s[3, 4] = gear
    with pytest.raises(InputError, match=r"path\.gear: must be \+1 \(forward\) or -1"):
        Path(s, NOWHERE)


@pytest.mark.parametrize("shape", [(5, 3), (5, 6), (20,)])
def test_bad_shape_is_one_clear_error(shape):
    with pytest.raises(InputError, match="path.samples"):
        Path(np.zeros(shape), NOWHERE)


def test_samples_are_read_only_copies():
    s = _line(0, 5, -1)
    p = Path(s, NOWHERE)
    s[0, 4] = 1.0
    assert p.gears[0] == -1
    with pytest.raises(ValueError):
        p.samples[0, 0] = 1.0


@settings(max_examples=60, deadline=None)
@given(st.lists(st.sampled_from([1, -1]), min_size=1, max_size=40))
def test_segments_partition_the_rows(gears):
    n = len(gears)
    s = np.column_stack([np.arange(n, dtype=float), np.zeros((n, 3)), np.array(gears, float)])
    p = Path(s, NOWHERE)
    segs = p.segments()
    assert segs[0][0] == 0 and segs[-1][1] == n
    assert all(a < b for a, b in segs)
    assert all(b == c for (_, b), (c, _) in zip(segs[:-1], segs[1:], strict=True))
    assert [a for a, _ in segs[1:]] == p.cusps.tolist()
    for a, b in segs:
        assert np.all(p.gears[a:b] == p.gears[a])
    for (a, _), (c, _) in zip(segs[:-1], segs[1:], strict=True):
        assert p.gears[a] != p.gears[c]
    assert p.is_forward_only == all(g == 1 for g in gears)


def test_problem_reverse_is_a_validated_bool():
    from rrtdrive.maps import builtin_map
    from rrtdrive.planning import PlanningProblem

    m = builtin_map("parking_lot")
    assert PlanningProblem.from_map(m).reverse is False
    p = PlanningProblem.from_map(m, reverse=True)
    assert p.reverse is True
    with pytest.raises(InputError, match="reverse"):
        PlanningProblem(m, p.checker, m.start, m.goal, m.vehicle, reverse="yes")
    with pytest.raises(InputError, match="reverse"):
        PlanningProblem(m, p.checker, m.start, m.goal, m.vehicle, reverse=1)
