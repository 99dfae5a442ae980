"""The per-query fast paths of Hybrid A* give what the code they replace gave, bit for bit.

A query answered by the root's first shot pays for the set-up, the shot and the
ramped path alone; these tests pin the shortcuts taken there (experiments/bench_trivial.py
times them) to the arithmetic they stand for.
"""

from __future__ import annotations

import array

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.maps import builtin_map
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.hybrid import ramps
from rrtdrive.planning.hybrid.heuristic import HolonomicField
from rrtdrive.planning.hybrid.resolution import free_cell_graph
from rrtdrive.types import Pose


def test_flat_field_is_the_fields_bytes_and_is_shared() -> None:
    m = builtin_map("parking_lot")
    grid = free_cell_graph(PlanningProblem.from_map(m), 0.5)
    field = HolonomicField.towards(grid, m.goal)
    want = array.array("d")
    want.frombytes(np.ascontiguousarray(field.dist, dtype=np.float64).tobytes())
    assert field.cells == want
    again = HolonomicField.towards(grid, Pose(m.goal.x, m.goal.y, 2.0))
    assert again.cells is field.cells  # the same goal cell: one copy for every query
    outside = HolonomicField.towards(grid, Pose(-500.0, -500.0, 0.0))
    assert set(outside.cells) == {np.inf}


def _probe_widening(lengths: np.ndarray, angles: np.ndarray, rate: float) -> np.ndarray:
    """ramps._widening without its shortcut: every round on the probe points."""
    jumps = angles[1:] - angles[:-1]
    factors = np.ones(len(jumps))
    if not len(jumps):
        return factors
    joints = lengths.cumsum()[:-1]
    probe = np.linspace(0.0, float(lengths.sum()), 4001)
    for _ in range(40):
        widths = np.maximum(np.abs(jumps) * factors / rate, 1e-9)
        inside = (probe[None, :] >= (joints - widths / 2)[:, None]) & (
            probe[None, :] <= (joints + widths / 2)[:, None]
        )
        slope = (inside * (jumps / widths)[:, None]).sum(axis=0)
        worst = np.where(inside, np.abs(slope)[None, :], 0.0).max(axis=1)
        over = worst > rate * (1.0 + 1e-9)
        if not over.any():
            break
        factors = np.where(over, factors * worst / rate * 1.001, factors)
    return factors


@settings(max_examples=300, deadline=None)
@given(st.integers(2, 9), st.integers(0, 2**32 - 1), st.floats(0.05, 2.0), st.booleans())
def test_widening_shortcut_is_the_probe_rounds(
    pieces: int, seed: int, rate: float, touching: bool
) -> None:
    """Ramps apart (the shortcut: factors 1) or not, the factors are the probes' own."""
    rng = np.random.default_rng(seed)
    lengths = rng.uniform(0.05, 6.0, pieces)
    angles = rng.uniform(-0.4, 0.4, pieces)
    if touching:
        # Ramps that end exactly where the next starts (a probe may lie on both).
        angles = np.round(angles * 8) / 8
        lengths = np.abs(angles[1:] - angles[:-1]) / rate
        lengths = np.concatenate([[1.0], np.maximum(lengths, 1e-3)])
    got = ramps._widening(lengths, angles, rate)
    assert np.array_equal(got, _probe_widening(lengths, angles, rate))
    if ramps._apart_and_within(lengths.cumsum()[:-1], angles[1:] - angles[:-1], rate):
        assert np.array_equal(got, np.ones(pieces - 1))


def test_widening_shortcut_is_taken_and_refused() -> None:
    lengths = np.array([4.0, 4.0, 4.0])
    apart = np.array([0.0, 0.2, -0.1])
    assert ramps._apart_and_within(lengths.cumsum()[:-1], np.diff(apart), 0.2)
    assert not ramps._apart_and_within(lengths.cumsum()[:-1], np.diff(apart), 0.02)  # overlap


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 6), st.integers(0, 2**32 - 1), st.integers(3, 700))
def test_one_dimensional_profile_is_the_batch_profile(pieces: int, seed: int, nodes: int) -> None:
    """_profile is _profiles of a batch of one, bit for bit (both ways of summing the ramps)."""
    rng = np.random.default_rng(seed)
    lengths = rng.uniform(0.05, 8.0, pieces)
    angles = rng.uniform(-0.4, 0.4, pieces)
    rate = 0.18
    factors = ramps._widening(lengths, angles, rate)
    t = ramps._nodes(nodes)
    delta, h, _ = ramps._profile(lengths, angles, factors, rate, t)
    want, want_h = ramps._profiles(lengths[None], angles[None], factors, rate, t)
    assert np.array_equal(delta, want[0])
    assert h == float(want_h[0])
    assert np.array_equal(t, np.linspace(0.0, 1.0, nodes))


def _reference_densify(p: np.ndarray, spacing: float, angle_column, rel_slack, abs_slack):
    """geometry.densify as it was (fe62cbf): gathered rows ``a + frac (b - a)``, stacked."""
    from rrtdrive.geometry import wrap_angle

    seg = np.hypot(*np.diff(p[:, :2], axis=0).T)
    pieces = np.maximum(1, np.ceil(seg / spacing * (1 + rel_slack) - abs_slack).astype(np.int64))
    owner = np.repeat(np.arange(len(seg)), pieces)
    first = np.repeat(np.cumsum(pieces) - pieces, pieces)
    frac = (np.arange(len(owner)) - first) / np.repeat(pieces, pieces)
    a, b = p[owner], p[owner + 1]
    out = a + frac[:, None] * (b - a)
    if angle_column is not None:
        k = angle_column
        out[:, k] = a[:, k] + frac * wrap_angle(b[:, k] - a[:, k])
    return np.vstack([out, p[-1:]]), pieces


@settings(max_examples=200, deadline=None)
@given(
    st.integers(2, 40),
    st.integers(2, 5),
    st.integers(0, 2**32 - 1),
    st.sampled_from([0.05, 0.1, 0.25, 1.0]),
    st.sampled_from([0.0, 1e-5]),
    st.sampled_from([0.0, 1e-9]),
    st.booleans(),
)
def test_densify_is_the_reference(
    n: int, dims: int, seed: int, spacing: float, rel: float, ab: float, angles: bool
) -> None:
    """The in-place densify: the same rows (and signs of zero) and piece counts."""
    from rrtdrive.geometry import densify

    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, dims)) * rng.choice([0.01, 1.0, 10.0])
    p[rng.integers(0, n)] = p[0]  # a repeated row: a segment of length 0
    column = 2 if angles and dims > 2 else None
    got = densify(p, spacing, angle_column=column, rel_slack=rel, abs_slack=ab)
    want, pieces = _reference_densify(p, spacing, column, rel, ab)
    assert np.array_equal(got.points, want)
    assert np.array_equal(np.signbit(got.points), np.signbit(want))
    assert np.array_equal(got.pieces, pieces)


def test_body_tests_are_kept_per_map_and_clearance() -> None:
    from rrtdrive.planning.base import cached_checker
    from rrtdrive.planning.hybrid import resolution
    from rrtdrive.planning.hybrid.body import BodyTest

    checker = cached_checker(builtin_map("parking_lot"))
    a = resolution.body_test(checker, 0.1)
    assert resolution.body_test(checker, 0.1) is a
    fresh = BodyTest(checker, 0.1)
    assert vars(a).keys() == vars(fresh).keys()
    for key, value in vars(fresh).items():
        assert np.array_equal(getattr(a, key), value) if key != "checker" else a.checker is value
    for k in range(resolution.BODY_TESTS + 2):
        assert resolution.body_test(checker, 0.2 + 0.01 * k).clearance == 0.2 + 0.01 * k
    tests = checker.grid.derived(("hybrid-body-tests",), dict)
    assert len(tests) == resolution.BODY_TESTS  # the oldest dropped
