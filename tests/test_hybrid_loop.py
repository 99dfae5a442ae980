"""The search loop's lean body tests give what the code they replaced gave (issue 13).

Each reference is the code as it was at 44c06ab (the screen's look-up through
``clearances_xy``, the runs' worst-first exact test through the checker's six-disc
screen for more than six poses); the lean code must agree with it bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.maps import builtin_map
from rrtdrive.planning.base import cached_checker
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.primitives import PrimitiveSet

RADIUS = 5.9


def _checker():
    return cached_checker(builtin_map("parking_lot"))


def _reference_screen(body: BodyTest, poses: np.ndarray):
    """BodyTest.screen as it was (44c06ab)."""
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    off = body.offsets
    c, s = np.cos(p[:, 2])[:, None], np.sin(p[:, 2])[:, None]
    val = body.checker.clearances_xy(c * off + p[:, 0:1], s * off + p[:, 1:2])
    k = body._n_axis
    hit = (val[:, :k] < body.occupied_below).any(axis=1)
    room = val[:, k:].min(axis=1) - body.disc_need
    return hit, room >= 0.0, room


def _reference_exact(body: BodyTest, poses: np.ndarray) -> np.ndarray:
    """BodyTest._exact as it was: six poses or fewer straight to the rectangles."""
    checker = body.checker
    if len(poses) <= 6:
        return checker.rectangles_free(poses, clearance=body.clearance)
    offsets, radius = checker._screens[1]
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    val = checker.clearances_xy(c * offsets + poses[:, 0:1], s * offsets + poses[:, 1:2])
    free = (val >= radius + body.clearance).all(axis=1)
    rest = np.flatnonzero(~free)
    if len(rest):
        free[rest] = checker.rectangles_free(poses[rest], clearance=body.clearance)
    return free


def _reference_runs_free(body: BodyTest, poses: np.ndarray) -> np.ndarray:
    """BodyTest.runs_free as it was (44c06ab)."""
    P, n = poses.shape[0], poses.shape[1]
    flat = poses.reshape(-1, 3)
    hit, clear, room = _reference_screen(body, flat)
    alive = ~hit.reshape(P, n).any(axis=1)
    unsure = (~clear).reshape(P, n) & alive[:, None]
    runs = np.flatnonzero(unsure.any(axis=1))
    if not len(runs):
        return alive
    worst = runs * n + np.where(unsure[runs], room.reshape(P, n)[runs], np.inf).argmin(axis=1)
    alive[runs[~_reference_exact(body, flat[worst])]] = False
    unsure &= alive[:, None]
    unsure.ravel()[worst] = False
    idx = np.flatnonzero(unsure.ravel())
    if len(idx):
        ok = _reference_exact(body, flat[idx])
        bad = np.zeros(P * n, dtype=bool)
        bad[idx[~ok]] = True
        alive &= ~bad.reshape(P, n).any(axis=1)
    return alive


def _poses(seed: int, count: int, lo: float = 0.0, hi: float = 100.0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.column_stack(
        [rng.uniform(lo, hi, count), rng.uniform(lo, hi, count), rng.uniform(-7, 7, count)]
    )


def test_axis_clearances_are_clearances_xy_bit_for_bit() -> None:
    """Inside the grid, beyond it (some points read -inf) and for no poses at all."""
    checker = _checker()
    off = np.array([-1.3, 0.0, 0.005, 0.8, 2.7])
    for lo, hi in ((0.0, 100.0), (-40.0, 140.0)):
        p = _poses(1, 700, lo, hi)
        c, s = np.cos(p[:, 2])[:, None], np.sin(p[:, 2])[:, None]
        want = checker.clearances_xy(c * off + p[:, 0:1], s * off + p[:, 1:2])
        got = checker.axis_clearances(p.T, off)
        assert np.array_equal(got, want.T)
    assert np.isinf(got).any() and np.isfinite(got).any()
    assert checker.axis_clearances(np.zeros((3, 0)), off).shape == (5, 0)


@pytest.mark.parametrize("clearance", [0.0, 0.15])
def test_screen_and_walk_screen_are_the_reference(clearance: float) -> None:
    body = BodyTest(_checker(), clearance)
    for lo, hi in ((0.0, 100.0), (-10.0, 110.0)):
        p = _poses(2, 3000, lo, hi)
        got, want = body.screen(p), _reference_screen(body, p)
        assert all(np.array_equal(a, b) for a, b in zip(got, want, strict=True))
        assert want[0].any() and want[1].any() and not (want[0] | want[1]).all()
        sizes = np.array([0, 7, 1, 40, 0, 2952])
        starts = np.cumsum(sizes) - sizes
        expect = [bool(want[0][a : a + m].any()) for a, m in zip(starts, sizes, strict=True)]
        assert body.any_hits(p, sizes).tolist() == expect


@settings(max_examples=150, deadline=None)
@given(
    st.floats(0.0, 100.0),
    st.floats(0.0, 100.0),
    st.floats(-math.pi, math.pi),
    st.sampled_from([0.0, 0.05, 0.15]),
    st.sampled_from([1.0, 4.0]),
    st.lists(st.booleans(), min_size=10, max_size=10),
)
def test_runs_free_is_the_reference(x, y, yaw, clearance, factor, keep) -> None:
    """The successors' runs from any pose (subsets of the primitives too): bit for bit."""
    body = BodyTest(_checker(), clearance)
    prims = PrimitiveSet.build(1 / RADIUS, 5, 1.0, 0.1, reverse=True)
    if factor != 1.0:
        prims = prims.scaled(factor)
    poses = prims.poses_from(x, y, yaw)
    if any(keep):
        poses = poses[np.flatnonzero(keep)]
    assert np.array_equal(body.runs_free(poses), _reference_runs_free(body, poses))


def test_runs_free_near_parked_cars_is_the_reference() -> None:
    """Poses along the parked rows: many runs unsure, both answers, both exact phases."""
    body = BodyTest(_checker(), 0.15)
    prims = PrimitiveSet.build(1 / RADIUS, 5, 1.0, 0.1, reverse=True)
    seen, phases = set(), 0
    for x, y, yaw in _poses(5, 600):
        poses = prims.poses_from(x, y, yaw)
        got = body.runs_free(poses)
        assert np.array_equal(got, _reference_runs_free(body, poses))
        seen.update(got.tolist())
        hit, clear, _ = _reference_screen(body, poses.reshape(-1, 3))
        phases += bool((~hit & ~clear).any())
    assert seen == {True, False}
    assert phases > 100
