"""Hybrid A*'s fast paths give exactly what the slow references they replace gave (issue 13).

Each reference here is the code as it was before the speed-up (pose by pose,
candidate by candidate, one Dijkstra per call); the fast code must agree with it
bit for bit or, where the arithmetic was reordered, to 1e-9.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.sparse.csgraph import dijkstra

from rrtdrive.maps import builtin_map
from rrtdrive.planning.base import PlanningProblem, cached_checker
from rrtdrive.planning.dubins import dubins_paths
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.heuristic import HolonomicField
from rrtdrive.planning.hybrid.resolution import free_cell_graph
from rrtdrive.planning.hybrid.search import walk_hits, walk_poses, walks_hit
from rrtdrive.planning.reeds_shepp import reeds_shepp_paths
from rrtdrive.types import Pose

RADIUS = 5.9
_TURN = {"L": 1, "S": 0, "R": -1}


def _checker():
    return cached_checker(builtin_map("parking_lot"))


def _reference_walk(start: Pose, word: str, lengths, radius: float, spacing: float):
    """The walk one pose at a time (the code before the speed-up): every pose, in order."""
    x, y, yaw = start.x, start.y, start.yaw
    out = []
    for letter, seg in zip(word, lengths, strict=True):
        turn = _TURN[letter]
        n = max(1, math.ceil(abs(seg) / spacing))
        c0, s0 = math.cos(yaw), math.sin(yaw)
        for k in range(1, n + 1):
            u = seg * k / n
            if turn == 0:
                px, py, pyaw = x + u * c0, y + u * s0, yaw
            else:
                pyaw = yaw + turn * u / radius
                px = x + turn * radius * (math.sin(pyaw) - s0)
                py = y - turn * radius * (math.cos(pyaw) - c0)
            out.append((px, py, pyaw))
        x, y, yaw = px, py, pyaw
    return out


def _reference_hits(start: Pose, word: str, lengths, radius: float, spacing: float, body):
    return any(body.hit_at(*p) for p in _reference_walk(start, word, lengths, radius, spacing))


poses = st.tuples(st.floats(0.0, 100.0), st.floats(0.0, 100.0), st.floats(-math.pi, math.pi)).map(
    lambda p: Pose(*p)
)


@settings(max_examples=60, deadline=None)
@given(poses, poses, st.sampled_from([0.1, 0.5]), st.booleans())
def test_vectorised_walk_is_the_pose_by_pose_walk(a: Pose, b: Pose, spacing: float, rs: bool):
    body = BodyTest(_checker(), 0.15)
    words = reeds_shepp_paths(a, b, RADIUS) if rs else dubins_paths(a, b, RADIUS)
    words = [(w.word, w.lengths) for w in words[:4]]
    got, sizes = walk_poses(a, words, RADIUS, spacing)
    want = [p for w, lengths in words for p in _reference_walk(a, w, lengths, RADIUS, spacing)]
    assert sizes.sum() == len(want)
    assert np.array_equal(got, np.array(want).reshape(-1, 3))  # bit for bit
    hits = walks_hit(a, words, RADIUS, spacing, body)
    assert hits == [_reference_hits(a, w, s, RADIUS, spacing, body) for w, s in words]
    assert [walk_hits(a, w, s, RADIUS, spacing, body) for w, s in words] == hits


def test_walks_hit_finds_hits_and_clear_words() -> None:
    """Not vacuous: over random pairs both answers occur, and agree with the reference."""
    body = BodyTest(_checker(), 0.15)
    rng = np.random.default_rng(5)
    seen = set()
    for _ in range(40):
        a = Pose(*rng.uniform(0, 100, 2), rng.uniform(-math.pi, math.pi))
        b = Pose(*rng.uniform(0, 100, 2), rng.uniform(-math.pi, math.pi))
        words = [(w.word, w.lengths) for w in reeds_shepp_paths(a, b, RADIUS)[:3]]
        got = walks_hit(a, words, RADIUS, 0.5, body)
        assert got == [_reference_hits(a, w, s, RADIUS, 0.5, body) for w, s in words]
        seen.update(got)
    assert seen == {True, False}


@settings(max_examples=200, deadline=None)
@given(poses, poses, st.sampled_from([0.5, 5.9, 12.0]), st.integers(1, 6))
def test_limited_reeds_shepp_paths_are_the_first_of_all(a: Pose, b: Pose, r: float, limit: int):
    full = reeds_shepp_paths(a, b, r)[:limit]
    got = reeds_shepp_paths(a, b, r, limit=limit)[:limit]
    assert [(p.word, p.lengths) for p in got] == [(p.word, p.lengths) for p in full]


def test_holonomic_field_is_one_dijkstra_and_is_shared() -> None:
    m = builtin_map("parking_lot")
    grid = free_cell_graph(PlanningProblem.from_map(m), 0.5)
    field = HolonomicField.towards(grid, m.goal)
    node = int(grid.index[grid.cell(m.goal.x, m.goal.y)])
    want = np.full(grid.index.shape, np.inf)
    want[grid.index >= 0] = dijkstra(grid.graph, directed=False, indices=node)
    want = np.maximum(want - grid.resolution * math.sqrt(2.0), 0.0)
    assert np.array_equal(field.dist, want)
    again = HolonomicField.towards(grid, Pose(m.goal.x, m.goal.y, 1.0))
    assert again.dist is field.dist  # the same goal cell: the cached field
    assert not field.dist.flags.writeable
    outside = HolonomicField.towards(grid, Pose(-500.0, -500.0, 0.0))
    assert outside.value(m.goal.x, m.goal.y) == math.inf


@pytest.mark.parametrize("clearance", [0.0, 0.15])
def test_exact_test_of_unsure_poses_is_the_checkers(clearance: float) -> None:
    checker = _checker()
    body = BodyTest(checker, clearance)
    rng = np.random.default_rng(11)
    p = np.column_stack(
        [rng.uniform(0, 100, 3000), rng.uniform(0, 100, 3000), rng.uniform(-np.pi, np.pi, 3000)]
    )
    hit, clear, _ = body.screen(p)
    unsure = p[~hit & ~clear]
    assert len(unsure) > 50
    want = checker.poses_free(unsure, clearance=clearance)
    assert want.any() and not want.all()
    assert np.array_equal(body._exact(unsure), want)


def test_lean_lookups_are_the_checkers_bit_for_bit() -> None:
    """clearances_xy and the exact test's corners: the same floats as the general code."""
    from rrtdrive.vehicle import footprint_corners

    checker = _checker()
    rng = np.random.default_rng(2)
    inside = rng.uniform(0.0, 100.0, (500, 2))
    outside = rng.uniform(-30.0, 130.0, (500, 2))  # some beyond the grid
    for pts in (inside, outside):
        got = checker.clearances_xy(pts[:, 0], pts[:, 1])
        assert np.array_equal(got, checker.clearances(pts))
    assert np.isinf(checker.clearances_xy(outside[:, 0], outside[:, 1])).any()
    poses = np.column_stack([inside, rng.uniform(-np.pi, np.pi, 500)])
    assert np.array_equal(checker._corners(poses), footprint_corners(poses, checker.vehicle))


@pytest.mark.parametrize("reverse", [False, True])
def test_scalar_heuristic_is_at(reverse: bool) -> None:
    from rrtdrive.planning.hybrid.config import HybridConfig
    from rrtdrive.planning.hybrid.heuristic import Heuristic
    from rrtdrive.planning.hybrid.resolution import dubins_table

    m = builtin_map("parking_lot")
    grid = free_cell_graph(PlanningProblem.from_map(m), 0.5)
    field = HolonomicField.towards(grid, m.goal)
    if reverse:
        h = Heuristic(field, None, m.goal)
    else:
        table = dubins_table(RADIUS, HybridConfig())
        h = Heuristic(field, table.to(m.goal), m.goal, table.scalar_to(m.goal))
    fast = h.scalar()
    rng = np.random.default_rng(4)
    pts = np.column_stack(
        [rng.uniform(-10, 110, 2000), rng.uniform(-10, 110, 2000), rng.uniform(-4, 4, 2000)]
    ).tolist()
    got = [fast(*p) for p in pts]
    assert got == [h.at(*p) for p in pts]  # bit for bit, inf included
    assert math.inf in got and any(v < math.inf for v in got)


@settings(max_examples=80, deadline=None)
@given(
    st.integers(1, 5),
    st.integers(2, 9),
    st.integers(0, 2**32 - 1),
    st.floats(0.02, 1.0),
)
def test_banded_ramp_sum_is_the_full_sum(rows: int, pieces: int, seed: int, rate: float):
    """The ramps' steering sum joint by joint: bit for bit the (B, J, T) array's sum."""
    from rrtdrive.planning.hybrid.ramps import _SUBSTEPS, _ramp_sum, _ramp_sum_full

    rng = np.random.default_rng(seed)
    lengths = rng.uniform(0.05, 8.0, (rows, pieces))
    angles = rng.uniform(-0.6, 0.6, (rows, pieces))
    total = lengths.sum(axis=1)
    t = np.linspace(0.0, 1.0, max(2, int(total.max() / 0.2)) * _SUBSTEPS + 1)
    s = total[:, None] * t[None, :]
    joints = np.cumsum(lengths, axis=1)[:, :-1]
    jumps = np.diff(angles, axis=1)
    factors = rng.uniform(1.0, 3.0, pieces - 1)
    widths = np.maximum(np.abs(jumps) * factors[None, :] / rate, 1e-9)
    got = _ramp_sum(s, t, total, joints, jumps, widths)
    assert np.array_equal(got, _ramp_sum_full(s, joints, jumps, widths))


def test_ramped_segment_unchanged_on_a_chain_of_arcs() -> None:
    """A many-joint segment (overlapping ramps widened): the same rows as the full sum gives."""
    from rrtdrive.planning.hybrid import ramps
    from rrtdrive.planning.hybrid.primitives import arc_poses

    rows = [np.array([[0.0, 0.0, 0.0]])]
    for k in [0.0, 1 / 6, -1 / 6, 1 / 6, 0.0, -1 / 8, 0.0]:
        rows.append(arc_poses(*rows[-1][-1], k, 1, np.linspace(0, 2.5, 11))[1:])
    seg = np.vstack(rows)
    args = (seg, 1, 0.17, 2.51, math.atan(2.51 / 5.9))
    fast = ramps.ramped_segment(*args)
    full, one = ramps._ramp_sum, ramps._ramp_sum_one
    try:
        ramps._ramp_sum = lambda s, t, total, j, d, w: ramps._ramp_sum_full(s, j, d, w)
        ramps._ramp_sum_one = lambda s, t, total, j, d, w: ramps._ramp_sum_full(
            s[None], j[None], d[None], w[None]
        )[0]
        slow = ramps.ramped_segment(*args)
    finally:
        ramps._ramp_sum, ramps._ramp_sum_one = full, one
    assert fast is not None and slow is not None
    assert np.array_equal(fast, slow)


def _reference_chain(search, i: int):
    """HybridSearch.chain as it was: one arc_poses call per primitive, pieces grown by vstack."""
    from rrtdrive.planning.hybrid.primitives import arc_poses
    from rrtdrive.planning.hybrid.search import Piece

    nodes = []
    while i >= 0:
        nodes.append(i)
        i = search.parent[i]
    nodes.reverse()
    pieces = []
    n = max(1, math.ceil(search.prims.length / search.cfg.sample_spacing - 1e-9))
    s = search.prims.length * np.arange(n + 1) / n
    for a, b in zip(nodes[:-1], nodes[1:], strict=True):
        poses = arc_poses(search.x[a], search.y[a], search.yaw[a], search.kappa[b],
                          search.gear[b], s)  # fmt: skip
        rows = np.column_stack([poses, np.full(len(poses), search.kappa[b])])
        rows[-1, :3] = (search.x[b], search.y[b], search.yaw[b])
        if pieces and pieces[-1].gear == search.gear[b]:
            pieces[-1] = Piece(search.gear[b], np.vstack([pieces[-1].rows, rows[1:]]))
        else:
            pieces.append(Piece(search.gear[b], rows))
    return pieces


def test_vectorised_chain_is_the_reference() -> None:
    """Chains of a real reversing search (many gears and curvatures): bit for bit."""
    from rrtdrive.planning.hybrid.config import HybridConfig
    from rrtdrive.planning.hybrid.heuristic import Heuristic
    from rrtdrive.planning.hybrid.primitives import PrimitiveSet
    from rrtdrive.planning.hybrid.search import HybridSearch, analytic_shots

    m = builtin_map("parking_lot")
    problem = PlanningProblem.from_map(m, reverse=True)
    cfg = HybridConfig()
    grid = free_cell_graph(problem, cfg.xy_resolution)
    h = Heuristic(HolonomicField.towards(grid, m.goal), None, m.goal)
    prims = PrimitiveSet.build(1 / RADIUS, cfg.curvatures, cfg.step, cfg.check_spacing, True)
    body = BodyTest(problem.checker, 0.15)
    shots = analytic_shots(m.goal, RADIUS, True, cfg.check_spacing, None, max_candidates=0)
    search = HybridSearch(body, m.start, m.goal, h, prims, shots, cfg, 1 / RADIUS, m.bounds)
    search.run(lambda pieces: None, 300, lambda: False)
    gears = set()
    for i in range(0, len(search.x), 7):
        got, want = search.chain(i), _reference_chain(search, i)
        assert [p.gear for p in got] == [p.gear for p in want]
        assert all(np.array_equal(a.rows, b.rows) for a, b in zip(got, want, strict=True))
        gears.update(p.gear for p in got)
    assert gears == {1, -1}


@settings(max_examples=300, deadline=None)
@given(
    x=st.floats(0.0, 100.0),
    y=st.floats(0.0, 100.0),
    yaw=st.floats(-math.pi, math.pi),
    clearance=st.sampled_from([0.0, 0.05, 0.15, 0.25]),
    factor=st.sampled_from([1.0, 2.0, 4.0]),
)
def test_free_within_proves_every_successor_free(x, y, yaw, clearance, factor):
    """A node with the discs' room for the primitives' reach: every successor pose is free.

    The skip of the search's body test must never call free what the exact test
    rejects, and the primitives it skips are all of them, in both gears, for the
    step arcs and the long ones (``HybridConfig.long_steps``) alike.
    """
    from rrtdrive.planning.hybrid.primitives import PrimitiveSet

    body = BodyTest(_checker(), clearance)
    prims = PrimitiveSet.build(1 / RADIUS, 5, 1.0, 0.1, reverse=True)
    if factor != 1.0:
        prims = prims.scaled(factor)
        assert prims.local.shape[1] == round(10 * factor)  # still 0.1 m apart
    reach = body.reach(prims.length, 1 / RADIUS)
    if not body.free_within(x, y, yaw, reach):
        return
    poses = prims.poses_from(x, y, yaw).reshape(-1, 3)
    assert body.free(poses).all()
    assert not body.hits(poses).any()


def test_free_within_is_not_vacuous():
    """On the parking lot's aisles the skip applies, and next to a parked car it does not."""
    body = BodyTest(_checker(), 0.15)
    reach = body.reach(1.0, 1 / RADIUS)
    rng = np.random.default_rng(3)
    pts = rng.uniform(0, 100, size=(2000, 3))
    pts[:, 2] = rng.uniform(-math.pi, math.pi, 2000)
    skipped = [body.free_within(*p, reach) for p in pts]
    assert 0.05 < np.mean(skipped) < 0.95
    # A pose whose body is not free is never skipped.
    for p, s in zip(pts, skipped, strict=True):
        if not body.free(p[None])[0]:
            assert not s


def _reference_ends(start, gear: int, delta, h, wheelbase: float):
    """ramps._ends as it was (d4ad454): the end poses of the rows of ``delta``."""
    kappa = np.tan(delta) / wheelbase
    hb = h[:, None]
    dyaw = gear * 0.5 * (kappa[:, 1:] + kappa[:, :-1]) * hb
    yaw = np.empty(delta.shape)
    yaw[:, 0] = start[2] + 0.0
    yaw[:, 1:] = start[2] + np.cumsum(dyaw, axis=1)
    mid = 0.5 * (yaw[:, 1:] + yaw[:, :-1])
    out = np.empty((len(delta), 3))
    out[:, 0] = start[0] + gear * np.cumsum(hb * np.cos(mid), axis=1)[:, -1]
    out[:, 1] = start[1] + gear * np.cumsum(hb * np.sin(mid), axis=1)[:, -1]
    out[:, 2] = yaw[:, -1]
    return out


def _reference_widening(lengths, angles, rate: float):
    """ramps._widening as it was, one ramp's maximum at a time (d4ad454)."""
    jumps = np.diff(angles)
    factors = np.ones(len(jumps))
    if not len(jumps):
        return factors
    joints = np.cumsum(lengths)[:-1]
    probe = np.linspace(0.0, float(lengths.sum()), 4001)
    for _ in range(40):
        widths = np.maximum(np.abs(jumps) * factors / rate, 1e-9)
        inside = (probe[None, :] >= (joints - widths / 2)[:, None]) & (
            probe[None, :] <= (joints + widths / 2)[:, None]
        )
        slope = (inside * (jumps / widths)[:, None]).sum(axis=0)
        worst = np.array([np.abs(slope[m]).max() if m.any() else 0.0 for m in inside])
        over = worst > rate * (1.0 + 1e-9)
        if not over.any():
            break
        factors = np.where(over, factors * worst / rate * 1.001, factors)
    return factors


def _reference_fit(rows, gear, rate, wheelbase, delta_max, spacing, angle_weight, pinned=(0, 0)):
    """ramps._ramped_once as it was (d4ad454): every Newton iteration one (2n+1)-row batch.

    The end pose and its forward-difference Jacobian from the batch ``[p, p + eps I]``,
    the converged iteration included.
    """
    from rrtdrive.geometry import wrap_angle
    from rrtdrive.planning.hybrid import ramps as r

    rows = np.asarray(rows, dtype=float)
    ds, kappa = r._intervals(rows, gear)
    if not len(ds):
        return None
    lengths, angles = r._pieces(ds, kappa, wheelbase)
    angles = np.clip(angles, -delta_max, delta_max)
    n = len(lengths)
    start, goal = rows[0, :3].copy(), rows[-1, :3]
    m = max(1, math.ceil(float(lengths.sum()) / spacing - 1e-9))
    t = np.linspace(0.0, 1.0, m * r._SUBSTEPS + 1)
    if n == 1:
        delta, h = r._profiles(lengths[None], angles[None], np.ones(0), rate, t)
        poses = r._integrate(start, gear, delta, h, wheelbase)[0]
        out = np.column_stack([poses, np.tan(delta[0]) / wheelbase])[:: r._SUBSTEPS]
        out[0, :3], out[-1, :3] = start, goal
        return out
    p = np.concatenate([lengths, angles])
    weight = np.concatenate([np.ones(n), np.full(n, angle_weight**2)])
    lower = np.concatenate([np.zeros(n), np.full(n, -delta_max)])
    upper = np.concatenate([np.full(n, np.inf), np.full(n, delta_max)])
    factors = _reference_widening(lengths, angles, rate)
    eps = 1e-6
    for _ in range(r._NEWTON_ITERATIONS):
        batch = np.vstack([p, p + eps * np.eye(2 * n)])
        delta, h = r._profiles(batch[:, :n], batch[:, n:], factors, rate, t)
        ends = _reference_ends(start, gear, delta, h, wheelbase)
        err = ends[0] - goal
        err[2] = wrap_angle(err[2])
        pose = (delta[0], h[0])
        if float(np.abs(err).max()) < r._NEWTON_TOL:
            break
        jac = ((ends[1:] - ends[0]) / eps).T
        step = r._bounded_step(jac, err, p, weight, lower, upper)
        if step is None:
            return None
        p = np.clip(p + step, lower, upper)
    else:
        return None
    delta, h = pose
    poses = r._integrate(start, gear, delta[None], np.array([h]), wheelbase)[0]
    out = np.column_stack([poses, np.tan(delta) / wheelbase])[:: r._SUBSTEPS]
    out[0, :3], out[-1, :3] = start, goal
    return out


_KS = 1 / RADIUS / 1.02
_LEVELS = st.sampled_from([-_KS, -_KS / 2, 0.0, _KS / 2, _KS])


def _chain(pieces, gear: int) -> np.ndarray:
    """Rows of arcs ``(kappa, length)`` driven one after another, about 0.25 m apart."""
    from rrtdrive.planning.hybrid.primitives import arc_poses

    rows = [np.array([[3.0, -2.0, 0.7]])]
    for kappa, length in pieces:
        k = max(1, math.ceil(length / 0.25))
        rows.append(arc_poses(*rows[-1][-1], kappa, gear, np.linspace(0.0, length, k + 1))[1:])
    return np.vstack(rows)


def _central_jacobian(p, factors, rate, t, start, gear: int, wheelbase: float, eps: float):
    """Central differences of the end pose (the reference's arithmetic) in every parameter."""
    from rrtdrive.planning.hybrid import ramps as r

    n = len(p) // 2

    def end(q):
        delta, h = r._profiles(q[None, :n], q[None, n:], factors, rate, t)
        return _reference_ends(start, gear, delta, h, wheelbase)[0]

    return np.column_stack(
        [(end(p + eps * e) - end(p - eps * e)) / (2 * eps) for e in np.eye(2 * n)]
    )


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.tuples(_LEVELS, st.floats(0.5, 8.0)), min_size=2, max_size=7),
    st.sampled_from([1, -1]),
    st.floats(0.05, 0.3),
)
def test_exact_jacobian_is_the_difference_quotient(pieces, gear: int, rate: float) -> None:
    """The fit's Jacobian of the end pose: the central difference quotient, to its rounding.

    The end pose is the reference's bit for bit; the Jacobian agrees to 1e-5 of its
    largest entry (the quotient's own error: 1e-7 steps, rounding of 1e-9 relative,
    and a kink where a ramp's end crosses a node).
    """
    from rrtdrive.planning.hybrid import ramps as r

    rows = _chain(pieces, gear)
    ds, kappa = r._intervals(rows, gear)
    lengths, angles = r._pieces(ds, kappa, 2.51)
    n = len(lengths)
    if n < 2:
        return
    t = np.linspace(0.0, 1.0, math.ceil(lengths.sum() / 0.2) * r._SUBSTEPS + 1)
    factors = r._widening(lengths, angles, rate)
    p = np.concatenate([lengths, angles])
    start = rows[0].copy()
    end, jacobian, delta, poses = r._end_and_jacobian(p, factors, rate, t, start, gear, 2.51)
    jac = jacobian()
    want_delta, want_h = r._profiles(p[None, :n], p[None, n:], factors, rate, t)
    assert np.array_equal(end, _reference_ends(start, gear, want_delta, want_h, 2.51)[0])
    assert np.array_equal(delta, want_delta[0])
    # The poses from the fit's own sums are _integrate's, bit for bit.
    assert np.array_equal(poses(), r._integrate(start, gear, want_delta, want_h, 2.51)[0])
    quotient = _central_jacobian(p, factors, rate, t, start, gear, 2.51, 1e-7)
    assert np.abs(jac - quotient).max() <= 1e-5 * np.abs(quotient).max()


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.tuples(_LEVELS, st.floats(0.5, 8.0)), min_size=1, max_size=7),
    st.sampled_from([1, -1]),
)
@example([(-_KS, 3.0), (_KS, 3.0)], 1)
def test_exact_fit_is_near_the_difference_quotient_fit(pieces, gear: int) -> None:
    """The fit with the exact Jacobian against the old one (forward differences).

    Both end exactly on the end pose, but the lengths and angles that do are a
    (2n - 3)-dimensional set, and the least-change steps of two Jacobians that
    differ by the quotient's O(1e-6) error stop at different points of it: the rows
    agree to a millimetre (bench_hybrid.py's 150 plans: 2.7e-4 m at most), not bit for bit.
    """
    from unittest import mock

    from rrtdrive.planning.hybrid import ramps

    rows = _chain(pieces, gear)
    args = (rows, gear, 0.17, 2.51, math.atan(2.51 / RADIUS))
    fast = ramps.ramped_segment(*args)
    with mock.patch.object(ramps, "_ramped_once", _reference_fit):
        slow = ramps.ramped_segment(*args)
    if fast is None or slow is None:
        return
    assert fast.shape == slow.shape
    assert np.abs(fast - slow).max() <= 1e-3


@settings(max_examples=100, deadline=None)
@given(st.integers(2, 12), st.integers(0, 2**32 - 1), st.floats(0.02, 0.5))
def test_vectorised_widening_is_the_reference(pieces: int, seed: int, rate: float) -> None:
    from rrtdrive.planning.hybrid.ramps import _widening

    rng = np.random.default_rng(seed)
    lengths = rng.uniform(0.1, 6.0, pieces)
    angles = rng.uniform(-0.4, 0.4, pieces)
    assert np.array_equal(
        _widening(lengths, angles, rate), _reference_widening(lengths, angles, rate)
    )


@settings(max_examples=200, deadline=None)
@given(
    x=st.floats(0.0, 100.0),
    y=st.floats(0.0, 100.0),
    yaw=st.floats(-math.pi, math.pi),
)
def test_field_clearance_is_a_lower_bound_of_the_exact_clearance(x, y, yaw):
    """The query's clearance cap skips the exact distances only where the field's bound decides."""
    from rrtdrive.planning.hybrid.resolution import field_clearance

    checker = _checker()
    exact = checker.body_clearance((x, y, yaw))
    assert field_clearance(checker, Pose(x, y, yaw)) <= exact + 1e-12


def test_end_clearance_caps_as_the_exact_value_does():
    """EndClearance.cap gives min(wanted, 0.999 exact) whichever way it decides."""
    import dataclasses

    from rrtdrive.planning.hybrid.resolution import EndClearance

    base = builtin_map("parking_lot")
    rng = np.random.default_rng(4)
    checker = _checker()
    done = 0
    while done < 40:
        pose = Pose(rng.uniform(0, 100), rng.uniform(0, 100), rng.uniform(-math.pi, math.pi))
        if not checker.pose_free(pose.as_tuple()):
            continue
        problem = PlanningProblem.from_map(dataclasses.replace(base, start=pose))
        exact = min(checker.body_clearance(pose.as_tuple()),
                    checker.body_clearance(problem.goal.as_tuple()))  # fmt: skip
        for wanted in (0.0, 0.05, 0.15, 0.25, 0.6, 2.0):
            want = max(0.0, min(wanted, exact * 0.999)) if wanted > 0 else 0.0
            assert EndClearance(problem).cap(wanted) == want
        done += 1
