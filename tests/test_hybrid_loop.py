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
    seen, few, many = set(), 0, 0
    for x, y, yaw in _poses(5, 600):
        poses = prims.poses_from(x, y, yaw)
        got = body.runs_free(poses)
        assert np.array_equal(got, _reference_runs_free(body, poses))
        seen.update(got.tolist())
        hit, clear, _ = _reference_screen(body, poses.reshape(-1, 3))
        unsure = int((~hit & ~clear).sum())
        few += 0 < unsure <= 8
        many += unsure > 30
    assert seen == {True, False}
    assert few > 20 and many > 50  # one exact call, and the worst-first two


@settings(max_examples=200, deadline=None)
@given(
    st.floats(-50.0, 150.0),
    st.floats(-50.0, 150.0),
    st.floats(-10.0, 10.0),
    st.sampled_from([1.0, 2.0, 4.0]),
    st.lists(st.booleans(), min_size=10, max_size=10),
)
def test_rows_from_is_poses_from_bit_for_bit(x, y, yaw, factor, keep) -> None:
    prims = PrimitiveSet.build(1 / RADIUS, 5, 1.0, 0.1, reverse=True)
    if factor != 1.0:
        prims = prims.scaled(factor)
    want = prims.poses_from(x, y, yaw)
    assert np.array_equal(prims.rows_from(x, y, yaw), want.reshape(-1, 3).T)
    sub = np.flatnonzero(keep).tolist()
    if sub:
        assert np.array_equal(prims.rows_from(x, y, yaw, sub), want[sub].reshape(-1, 3).T)
    # The loop's end poses (plain floats): poses_from's last rows.
    c, s = math.cos(yaw), math.sin(yaw)
    ends = [[x + c * lx - s * ly, y + s * lx + c * ly, yaw + dy] for lx, ly, dy in
            prims.local[:, -1, :].tolist()]  # fmt: skip
    assert ends == want[:, -1, :].tolist()


#: Searches of the parking lot with reverse (gear 0) and forward (1): start, gear,
#: expansions, shots on, and what they gave at 44c06ab (counts; the node arrays hashed).
_SEARCHES = [
    ((5.0, 6.0, 0.0), 0, 300, False, (300, 1886, 56, 0), "f9ade0e1b1e10f3e"),
    ((89.47158621961735, 42.27169069454373, 0.5623580414487663), 0, 400, True,
     (162, 883, 29, 16), "0a7d57ef7de6aff1"),
    ((10.973466400669674, 20.32415440873966, -1.3583838921738032), 0, 600, True,
     (600, 3464, 63, 0), "0f179bbf69c763f9"),
    ((32.97317164990922, 78.84287034284043, -1.2365633569717065), 1, 400, True,
     (43, 56, 4, 0), "9bc164ae0ec85c7f"),
]  # fmt: skip


@pytest.mark.parametrize(("start", "gear", "budget", "shots", "counts", "digest"), _SEARCHES)
def test_search_loop_builds_the_recorded_tree(start, gear, budget, shots, counts, digest) -> None:
    """The whole loop (keys, costs, long arcs, body tests, shots): every node as at 44c06ab.

    Random starts between the parked cars of ``experiments/random_goals.py`` (seed 1:
    starts 17, 25 and 3), where most expansions test their successors' bodies.
    """
    import hashlib

    from rrtdrive.planning.base import PlanningProblem
    from rrtdrive.planning.hybrid.config import HybridConfig
    from rrtdrive.planning.hybrid.heuristic import Heuristic, HolonomicField
    from rrtdrive.planning.hybrid.primitives import primitive_sets
    from rrtdrive.planning.hybrid.resolution import free_cell_graph
    from rrtdrive.planning.hybrid.search import HybridSearch, analytic_shots
    from rrtdrive.types import Pose

    m = builtin_map("parking_lot")
    cfg = HybridConfig()
    problem = PlanningProblem.from_map(m, reverse=gear == 0)
    grid = free_cell_graph(problem, cfg.xy_resolution)
    h = Heuristic(HolonomicField.towards(grid, m.goal), None, m.goal)
    prims, *long = primitive_sets(
        1 / RADIUS, cfg.curvatures, cfg.step, cfg.check_spacing, gear, cfg.long_steps
    )
    body = BodyTest(problem.checker, 0.15)
    shoot = analytic_shots(m.goal, RADIUS, gear == 0, cfg.check_spacing, body, 3 if shots else 0)
    search = HybridSearch(body, Pose(*start), m.goal, h, prims, shoot, cfg, 1 / RADIUS,
                          m.bounds, long)  # fmt: skip
    _, out = search.run(lambda pieces: None, budget, lambda: False)
    assert (out.expansions, out.nodes, out.shots, out.connections) == counts
    nodes = np.array([search.x, search.y, search.yaw, search.g, search.gear, search.kappa,
                      search.parent, search.step])  # fmt: skip
    assert hashlib.sha256(nodes.tobytes()).hexdigest()[:16] == digest


@pytest.mark.parametrize("resolution", [0.1, 0.6])
def test_screens_without_axis_points_are_the_reference(resolution: float) -> None:
    """A grid too coarse for the sure-collision screen (no axis points): no hit, same answers."""
    from rrtdrive.collision import CheckerConfig, CollisionChecker

    m = builtin_map("parking_lot")
    checker = CollisionChecker.for_map(m, config=CheckerConfig(resolution=resolution))
    body = BodyTest(checker, 0.15)
    assert (body._n_axis == 0) == (resolution == 0.6)
    p = _poses(9, 500)
    got, want = body.screen(p), _reference_screen(body, p)
    assert all(np.array_equal(a, b) for a, b in zip(got, want, strict=True))
    prims = PrimitiveSet.build(1 / RADIUS, 5, 1.0, 0.1, reverse=True)
    for x, y, yaw in p[:60]:
        poses = prims.poses_from(x, y, yaw)
        assert np.array_equal(body.runs_free(poses), _reference_runs_free(body, poses))
