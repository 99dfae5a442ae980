"""The ramp fit's in-place arithmetic gives what the code it replaced gave, bit for bit.

The references are :mod:`rrtdrive.planning.hybrid.ramps` as it was at 3f87098 (the
Jacobian, the bounded step, the one-vector profile, the end pose and its poses), before
their temporaries were made in place, the bounds test moved to Python floats and the
returned poses computed for the kept rows alone (experiments/bench_trivial.py times
them). Every comparison here is of the bytes.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.planning.hybrid import ramps as r
from rrtdrive.planning.hybrid.primitives import arc_poses

WHEELBASE = 2.51
RADIUS = 5.9
_KS = 1 / RADIUS / 1.02
_LEVELS = st.sampled_from([-_KS, -_KS / 2, 0.0, _KS / 2, _KS])


def _reference_profile(lengths, angles, factors, rate: float, t):
    """ramps._profile as it was (3f87098)."""
    total = lengths.sum()
    s = total * t
    joints = lengths.cumsum()[:-1]
    jumps = angles[1:] - angles[:-1]
    widths = np.maximum(np.abs(jumps) * factors / rate, 1e-9)
    T = len(t)
    J = len(jumps)
    if J * T > r._FULL_SUM_MAX:
        ramp = r._ramp_sum(s[None], t, total[None], joints[None], jumps[None], widths[None])[0]
    elif J:
        u = s[None, :] - joints[:, None]
        u /= widths[:, None]
        u += 0.5
        np.maximum(u, 0.0, out=u)
        np.minimum(u, 1.0, out=u)
        u *= jumps[:, None]
        ramp = u.sum(axis=0)
    else:
        ramp = np.zeros(T)
    return ramp + angles[0], float(total / (T - 1)), (s, joints, jumps, widths)


def _reference_jacobian(n, grid, gear, wheelbase, kappa, dyaw, sums, h, t):
    """ramps._jacobian as it was (3f87098)."""
    s, joints, jumps, widths = grid
    T = len(t)
    lever = np.zeros((2, T))
    np.subtract(sums[:, -1:], sums[:, :-1], out=lever[:, 1:-1])
    lever[:, 0] = sums[:, -1]
    pair = lever[:, :-1] + lever[:, 1:]
    r_ = np.empty((3, T - 1))
    np.multiply(-0.5 * gear, pair[1], out=r_[0])
    np.multiply(0.5 * gear, pair[0], out=r_[1])
    r_[2] = 1.0
    g = 0.5 * gear * h
    v = np.zeros((3, T))
    v[:, :-1] = r_
    v[:, 1:] += r_
    v *= g * (1.0 + (wheelbase * kappa) ** 2) / wheelbase
    d_h = np.array([gear * sums[0, -1], gear * sums[1, -1], 0.0]) / h + (r_ @ dyaw) / h
    back = np.empty((6, T))
    back[:3] = v[:, ::-1]
    np.multiply(back[:3], t[::-1], out=back[3:])
    suffix = np.zeros((6, T + 1))
    np.cumsum(back, axis=1, out=suffix[:, 1:])
    a = s.searchsorted(joints - 0.5 * widths, side="right")
    b = s.searchsorted(joints + 0.5 * widths, side="left")
    slope = jumps / widths
    at_a, at_b = suffix[:, T - a], suffix[:, T - b]
    on = at_a[:3] - at_b[:3]
    share = 0.5 * on + at_b[:3]
    jac = np.zeros((3, 2 * n))
    jac[:, n] = suffix[:3, T]
    jac[:, n:-1] -= share
    jac[:, n + 1 :] += share
    stretch = (at_a[3:] - at_b[3:]) @ slope
    later = np.zeros((3, n))
    later[:, :-1] = (slope * on)[:, ::-1].cumsum(axis=1)[:, ::-1]
    jac[:, :n] = (stretch + d_h / (T - 1))[:, None] - later
    return jac


def _reference_end_and_poses(p, factors, rate, t, start, gear, wheelbase):
    """ramps._end_and_jacobian as it was (3f87098): end, profile, poses, the Jacobian's inputs."""
    n = len(p) // 2
    delta, h, grid = _reference_profile(p[:n], p[n:], factors, rate, t)
    T = len(t)
    kappa = np.tan(delta) / wheelbase
    dyaw = gear * 0.5 * (kappa[1:] + kappa[:-1]) * h
    yaw = np.empty(T)
    yaw[0] = start[2] + 0.0
    yaw[1:] = start[2] + dyaw.cumsum()
    mid = 0.5 * (yaw[1:] + yaw[:-1])
    sums = np.empty((2, T - 1))
    np.cos(mid, out=sums[0])
    np.sin(mid, out=sums[1])
    sums *= h
    sums = sums.cumsum(axis=1)
    px, py = sums[0], sums[1]
    end = np.array([start[0] + gear * px[-1], start[1] + gear * py[-1], yaw[-1]])
    zero = np.zeros(1)
    x = start[0] + gear * np.concatenate([zero, px])
    y = start[1] + gear * np.concatenate([zero, py])
    poses = np.stack([x, y, yaw], axis=-1)
    return end, delta, poses, (n, grid, gear, wheelbase, kappa, dyaw, sums, h, t)


def _reference_bounded_step(jac, err, p, weight, lower, upper):
    """ramps._bounded_step as it was (3f87098): the bounds test on arrays."""
    free = weight.copy()
    for _ in range(len(p) + 1):
        jw = jac * free[None, :]
        try:
            lam = np.linalg.solve(jw @ jac.T + r._RIDGE, -err)
        except np.linalg.LinAlgError:
            return None
        step = free * (jac.T @ lam)
        out = ((p + step < lower) & (step < 0)) | ((p + step > upper) & (step > 0))
        out &= free > 0
        if not out.any():
            return step
        free[out] = 0.0
    return None


def _chain(pieces, gear: int, yaw0: float) -> np.ndarray:
    """Rows of arcs ``(kappa, length)`` driven one after another, about 0.25 m apart."""
    rows = [np.array([[3.0, -2.0, yaw0]])]
    for kappa, length in pieces:
        k = max(1, math.ceil(length / 0.25))
        rows.append(arc_poses(*rows[-1][-1], kappa, gear, np.linspace(0.0, length, k + 1))[1:])
    return np.vstack(rows)


def _same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.tobytes() == b.tobytes()


@settings(max_examples=80, deadline=None)
@given(
    st.lists(st.tuples(_LEVELS, st.floats(0.3, 12.0)), min_size=1, max_size=8),
    st.sampled_from([1, -1]),
    st.floats(0.05, 0.3),
    st.sampled_from([0.0, 0.7, -2.0, math.pi / 2]),
    st.floats(-0.05, 0.05),
)
def test_fit_pieces_are_the_old_arithmetic(pieces, gear: int, rate: float, yaw0, nudge) -> None:
    """Profile, end pose, poses (all and every 4th), Jacobian and step: the old bytes."""
    rows = _chain(pieces, gear, yaw0)
    ds, kappa = r._intervals(rows, gear)
    lengths, angles = r._pieces(ds, kappa, WHEELBASE)
    n = len(lengths)
    t = r._nodes(math.ceil(lengths.sum() / 0.2) * r._SUBSTEPS + 1)
    factors = r._widening(lengths, angles, rate)
    # A parameter vector off the arcs' own (the fit's later iterations), lengths >= 0.
    p = np.concatenate([lengths * (1.0 + nudge), angles + nudge])
    start = rows[0].copy()
    got_profile = r._profile(p[:n], p[n:], factors, rate, t)
    want_profile = _reference_profile(p[:n], p[n:], factors, rate, t)
    assert _same(got_profile[0], want_profile[0]) and got_profile[1] == want_profile[1]
    for g, w in zip(got_profile[2], want_profile[2], strict=True):
        assert _same(g, w)
    end, jacobian, delta, poses = r._end_and_jacobian(p, factors, rate, t, start, gear, WHEELBASE)
    want_end, want_delta, want_poses, inputs = _reference_end_and_poses(
        p, factors, rate, t, start, gear, WHEELBASE
    )
    assert _same(end, want_end)
    assert _same(delta, want_delta)
    assert _same(poses(), want_poses)
    assert _same(poses(r._SUBSTEPS), want_poses[:: r._SUBSTEPS])
    if n < 2:
        return
    jac = jacobian()
    assert _same(jac, _reference_jacobian(*inputs))
    goal = rows[-1, :3]
    err = end - goal
    weight, lower, upper = r._fit_bounds(n, 0.1, math.atan(WHEELBASE / RADIUS))
    got = r._bounded_step(jac, err, p, weight, lower, upper)
    want = _reference_bounded_step(jac, err, p, weight, lower, upper)
    assert (got is None) == (want is None)
    if got is not None:
        assert _same(got, want)


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 6), st.integers(0, 2**32 - 1), st.floats(0.0, 1.0))
def test_bounded_step_holds_the_same_parameters(n: int, seed: int, spread: float) -> None:
    """The bounds test on Python floats holds the parameters the array test held."""
    rng = np.random.default_rng(seed)
    delta_max = math.atan(WHEELBASE / RADIUS)
    weight, lower, upper = r._fit_bounds(n, 0.1, delta_max)
    # Parameters on, near and off their bounds, and large errors: steps that cross them.
    p = np.concatenate([rng.uniform(0.0, 3.0, n), rng.uniform(-delta_max, delta_max, n)])
    at_bound = rng.random(2 * n) < 0.3
    p[at_bound] = np.concatenate([lower[:n], upper[n:]])[at_bound]
    jac = rng.normal(size=(3, 2 * n))
    err = rng.normal(scale=1.0 + 10.0 * spread, size=3)
    got = r._bounded_step(jac, err, p, weight, lower, upper)
    want = _reference_bounded_step(jac, err, p, weight, lower, upper)
    assert (got is None) == (want is None)
    if got is not None:
        assert _same(got, want)


def test_fit_bounds_are_the_concatenations_and_read_only() -> None:
    weight, lower, upper = r._fit_bounds(3, 0.1, 0.4)
    assert _same(weight, np.concatenate([np.ones(3), np.full(3, 0.1**2)]))
    assert _same(lower, np.concatenate([np.zeros(3), np.full(3, -0.4)]))
    assert _same(upper, np.concatenate([np.full(3, np.inf), np.full(3, 0.4)]))
    assert not (weight.flags.writeable or lower.flags.writeable or upper.flags.writeable)
    assert r._fit_bounds(3, 0.1, 0.4)[0] is weight
