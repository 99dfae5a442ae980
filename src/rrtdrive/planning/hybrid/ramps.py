"""Continuous curvature for a gear segment of exact arcs: steering ramps, exact end poses.

A Hybrid A* segment is a chain of arcs and lines, so its steering angle
``delta = atan(L kappa)`` jumps where two of them meet. :func:`ramped_segment`
replaces every jump of ``d`` by a linear ramp of ``delta`` of length
``|d| / rate`` centred on the joint (a clothoid-like transition: the steering turns
at a constant rate per metre), so that ``|d delta / ds| <= rate`` along the whole
segment; where ramps of one sign overlap they are widened until the sum keeps the
rate. The segment is then integrated from its exact start pose, and the arcs'
lengths and steering angles are fitted (least-change Gauss-Newton on a
forward-difference Jacobian, every ramp keeping its rate) so that it ends exactly
on the original end pose. The angles stay within ``[-delta_max, delta_max]`` (one
that a step would push past its bound is held there).

The ramps cut each corner by a few centimetres (at most about ``d w^2 / 48`` for a
ramp of width ``w``), so the result is checked again by the caller (body with the
clearance, ``|kappa|``, sharpness); a segment that cannot be closed returns ``None``.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np

from rrtdrive.geometry import wrap_angle
from rrtdrive.planning.hybrid.bounded_step import RIDGE as _RIDGE  # noqa: F401 (tests read it)
from rrtdrive.planning.hybrid.bounded_step import bounded_step as _bounded_step
from rrtdrive.planning.hybrid.pieces import intervals as _intervals
from rrtdrive.planning.hybrid.pieces import runs as _pieces
from rrtdrive.planning.hybrid.pieces import without_slivers as _without_slivers
from rrtdrive.planning.hybrid.ramp_sum import FULL_SUM_MAX as _FULL_SUM_MAX
from rrtdrive.planning.hybrid.ramp_sum import ramp_sum as _ramp_sum
from rrtdrive.planning.hybrid.ramp_sum import ramp_sum_full as _ramp_sum_full  # noqa: F401
from rrtdrive.planning.hybrid.ramp_sum import ramp_sum_one as _ramp_sum_one

__all__ = ["ramped_segment"]

#: The ufuncs that ``ndarray.cumsum`` / ``.sum`` call (the same floats), without their wrappers.
_accumulate, _add_reduce = np.add.accumulate, np.add.reduce
#: The lever pairs' factors in :func:`_jacobian`: ``-g/2`` (y) and ``g/2`` (x), times the gear.
_HALF_SIGNS = np.array([[-0.5], [0.5]])

#: Sub-steps of the integration per returned row (rows at most ``spacing`` apart).
_SUBSTEPS = 4
#: Newton iterations of the end-pose fit and its tolerance (metres / radians).
_NEWTON_ITERATIONS = 12
_NEWTON_TOL = 1e-10
#: A fit is stuck when its pose error, still over ``_STUCK_FROM``, has not fallen under
#: ``_STUCK_SHARE`` of the one before in ``_STUCK_AFTER`` iterations running: angles held
#: at the steering limit leave too few free lengths to close the gap, and Gauss-Newton
#: repeats the same tiny step to the end (in the 7 m lane-to-lane turn, 242 of the 245
#: fits that fail now end after 3-5 iterations instead of 12; of the fits that converge
#: in bench_hybrid's queries and the street turns, none would have ended so). Two since
#: session 19 (was 3): the failing fits end an iteration sooner (lane to lane at 7 m:
#: 345 -> 307 ms CPU), and no answer changed in bench_hybrid's 150 queries,
#: bench_default's 400, the behaviour snapshot's 80 and 68 tight-map plans.
_STUCK_SHARE = 0.9
_STUCK_AFTER = 2
_STUCK_FROM = 1e-6
#: Slack of the row-spacing test, metres (float rounding of rows exactly ``spacing`` apart).
_GAP_SLACK = 1e-9


def _profiles(
    lengths: np.ndarray, angles: np.ndarray, factors: np.ndarray, rate: float, t: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Steering at the nodes ``t * total`` of each row of ``lengths``/``angles``; and ``h``.

    ``lengths`` and ``angles`` are ``(B, n)``; each jump's ramp is ``factors`` times
    as long as the rate needs (``>= 1``: the widening for overlaps).
    """
    total = lengths.sum(axis=1)
    s = total[:, None] * t[None, :]
    # ndarray methods and slices, not np.cumsum / np.diff: the same arithmetic without
    # their Python wrappers (microseconds a call in the fit's inner loop).
    joints = lengths.cumsum(axis=1)[:, :-1]
    jumps = angles[:, 1:] - angles[:, :-1]
    widths = np.maximum(np.abs(jumps) * factors[None, :] / rate, 1e-9)
    return _ramp_sum(s, t, total, joints, jumps, widths) + angles[:, :1], total / (len(t) - 1)


def _integrate(
    start: np.ndarray, gear: int, delta: np.ndarray, h: np.ndarray, wheelbase: float
) -> np.ndarray:
    """Poses ``(B, n, 3)`` driven from ``start`` with steering ``delta`` ``(B, n)``, steps ``h``."""
    kappa = np.tan(delta) / wheelbase
    hb = h[:, None]
    dyaw = gear * 0.5 * (kappa[:, 1:] + kappa[:, :-1]) * hb
    zero = np.zeros((len(delta), 1))
    yaw = start[2] + np.concatenate([zero, dyaw.cumsum(axis=1)], axis=1)
    mid = 0.5 * (yaw[:, 1:] + yaw[:, :-1])
    x = start[0] + gear * np.concatenate([zero, (hb * np.cos(mid)).cumsum(axis=1)], axis=1)
    y = start[1] + gear * np.concatenate([zero, (hb * np.sin(mid)).cumsum(axis=1)], axis=1)
    return np.stack([x, y, yaw], axis=-1)


def _end_and_jacobian(
    p: np.ndarray,
    factors: np.ndarray,
    rate: float,
    t: np.ndarray,
    start: np.ndarray,
    gear: int,
    wheelbase: float,
) -> tuple[np.ndarray, Callable[[], np.ndarray], np.ndarray, Callable[[int], np.ndarray]]:
    """End pose of ``p = [lengths, angles]``, its exact Jacobian ``(3, 2n)``, the profile.

    The Jacobian is returned as a function that computes it on demand: the Newton
    step that converges needs none.

    The derivative of the discrete integration (:func:`_integrate`'s end), one
    integration instead of the ``2n + 1`` a difference quotient needs. A change
    of the yaw at node ``c`` turns the rest of the path about it: the end moves by
    the lever arm ``(-(y_end - y_c), x_end - x_c)`` (here the trapezoid's half-step
    sums) and turns by the same angle. A change of the steering at node ``c``
    changes the yaw of every later node by ``g h sec^2(delta_c) / L`` (half of it
    at the first). The steering moves with an angle by the ramps' share of it (1/2
    on a ramp, whose width grows with its jump; 1 after it), with a length by the
    slope of the ramps it shifts (every joint after that piece) and through the
    grid ``s = total t`` and step ``h = total / (T - 1)`` it stretches.

    Returns
    -------
    tuple
        The end pose ``(3,)``, a function giving the Jacobian ``(3, 2n)``, the
        steering profile ``(T,)`` and a function giving every pose ``(T, 3)`` (as
        :func:`_integrate` would; ``poses(k)``: every ``k``-th of them).
    """
    n = len(p) // 2
    delta, h, grid = _profile(p[:n], p[n:], factors, rate, t)
    T = len(t)
    # In place where the expression made temporaries: a * b and b * a, a + b and b + a
    # round alike, so ``gear * 0.5 * (k1 + k0) * h`` is ``((k1 + k0) * (gear * 0.5)) * h``.
    kappa = np.tan(delta)
    kappa /= wheelbase
    dyaw = kappa[1:] + kappa[:-1]
    dyaw *= gear * 0.5
    dyaw *= h
    yaw = np.empty(T)
    yaw[0] = start[2] + 0.0
    _accumulate(dyaw, out=yaw[1:])  # dyaw.cumsum(), then start[2] + it
    yaw[1:] += start[2]
    mid = yaw[1:] + yaw[:-1]
    mid *= 0.5
    # The x and y sums as the rows of one array: each row's products and running sums are
    # those of the 1-D arrays, in half the numpy calls.
    sums = np.empty((2, T - 1))
    np.cos(mid, out=sums[0])
    np.sin(mid, out=sums[1])
    sums *= h
    sums = _accumulate(sums, axis=1)
    px, py = sums[0], sums[1]
    end = np.array([start[0] + gear * px[-1], start[1] + gear * py[-1], yaw[-1]])

    def jacobian() -> np.ndarray:
        return _jacobian(n, grid, gear, wheelbase, kappa, dyaw, sums, h, t)

    def poses(every: int = 1) -> np.ndarray:
        # _integrate's rows from this integration's sums: the same operations, the same
        # floats; every ``every``-th row only (elementwise: those rows of the whole).
        out = np.empty((len(range(0, T, every)), 3))
        out[0, 0] = start[0] + gear * 0.0
        out[0, 1] = start[1] + gear * 0.0
        # Row i >= 1 is start + gear * sums[:, i - 1] (g * a is a * g).
        np.multiply(sums[:, every - 1 :: every], gear, out=out[1:, :2].T)
        out[1:, :2] += start[:2]
        out[:, 2] = yaw[::every]
        return out

    return end, jacobian, delta, poses


def _profile(
    lengths: np.ndarray, angles: np.ndarray, factors: np.ndarray, rate: float, t: np.ndarray
) -> tuple[np.ndarray, float, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """:func:`_profiles` of one parameter vector: the steering ``(T,)``, ``h`` and the grid.

    The same floats as ``_profiles(lengths[None], angles[None], ...)`` (the same
    operations on 1-D arrays; the ramps are summed one after the other, as numpy
    sums the ``(B, J, T)`` array along ``J``), without its 2-D and 3-D wrappers.
    The grid ``(s, joints, jumps, widths)`` is what :func:`_jacobian` reads.
    """
    # The ufuncs that ndarray.sum / cumsum call (the same floats), and the widths
    # max(|jumps| * factors / rate, 1e-9) in place: this runs at every step of the fit.
    total = _add_reduce(lengths)
    s = total * t
    joints = _accumulate(lengths)[:-1]
    jumps = angles[1:] - angles[:-1]
    widths = np.abs(jumps)
    widths *= factors
    widths /= rate
    np.maximum(widths, 1e-9, out=widths)
    T = len(t)
    J = len(jumps)
    if J * T > _FULL_SUM_MAX:
        ramp = _ramp_sum_one(s, t, total, joints, jumps, widths)
    elif J:
        u = s[None, :] - joints[:, None]
        u /= widths[:, None]
        u += 0.5
        np.maximum(u, 0.0, out=u)
        np.minimum(u, 1.0, out=u)
        u *= jumps[:, None]
        ramp = _add_reduce(u, axis=0)
    else:
        ramp = np.zeros(T)
    ramp += angles[0]  # a fresh array: ramp + angles[0] in place
    return ramp, float(total / (T - 1)), (s, joints, jumps, widths)


def _jacobian(
    n: int,
    grid: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    gear: int,
    wheelbase: float,
    kappa: np.ndarray,
    dyaw: np.ndarray,
    sums: np.ndarray,
    h: float,
    t: np.ndarray,
) -> np.ndarray:
    """The Jacobian of :func:`_end_and_jacobian`, from its integration's arrays.

    ``grid``: :func:`_profile`'s ``(s, joints, jumps, widths)``; ``sums``: the
    ``(2, T - 1)`` running sums of the x and y steps.
    """
    s, joints, jumps, widths = grid
    T = len(t)
    # lever[:, c]: the sums over the steps from node c to the end (0 at the last node).
    lever = np.zeros((2, T))
    np.subtract(sums[:, -1:], sums[:, :-1], out=lever[:, 1:-1])
    lever[:, 0] = sums[:, -1]
    # r[:, i]: d end / d dyaw_i, the turn of every node after i: rows 0 and 1 are
    # -g/2 (y lever pair) and g/2 (x lever pair), both in two calls (a * b is b * a).
    r = np.empty((3, T - 1))
    np.add(lever[::-1, :-1], lever[::-1, 1:], out=r[:2])
    r[:2] *= _HALF_SIGNS * gear
    r[2] = 1.0
    g = 0.5 * gear * h
    # v: d end / d delta_c, written reversed (back[:3]: the order the suffix sums run in).
    # v[:, c] = r[:, c] + r[:, c - 1] in the middle; the last column r[:, -1] + 0.0 as
    # ``zeros; v[:, :-1] = r; v[:, 1:] += r`` made it (0.0 + -0.0 is 0.0).
    back = np.empty((6, T))
    v = back[:3, ::-1]
    v[:, 0] = r[:, 0]
    np.add(r[:, 1:], r[:, :-1], out=v[:, 1:-1])
    np.add(r[:, -1], 0.0, out=v[:, -1])
    # g * (1 + (L kappa)^2) / L, in place (x ** 2 is numpy's x * x).
    scale = wheelbase * kappa
    np.multiply(scale, scale, out=scale)
    scale += 1.0
    scale *= g
    scale /= wheelbase
    v *= scale
    d_h = np.array([gear * sums[0, -1], gear * sums[1, -1], 0.0]) / h + (r @ dyaw) / h
    # Suffix sums of v (rows 0-2) and v * t (rows 3-5), summed from the last node on as
    # before, in one running sum of the reversed rows: column T - c holds the sums from
    # node c on (column 0, "from T on", is zero).
    np.multiply(back[:3], t[::-1], out=back[3:])
    suffix = np.empty((6, T + 1))
    suffix[:, 0] = 0.0
    _accumulate(back, axis=1, out=suffix[:, 1:])
    a = s.searchsorted(joints - 0.5 * widths, side="right")  # first node on a ramp
    b = s.searchsorted(joints + 0.5 * widths, side="left")  # first node after it
    slope = jumps / widths
    at_a, at_b = suffix[:, T - a], suffix[:, T - b]  # (fancy: their layout sets the @ below)
    on = at_a[:3] - at_b[:3]  # (3, J): v summed over each ramp
    share = 0.5 * on + at_b[:3]  # d end / d jump_j
    jac = np.zeros((3, 2 * n))
    jac[:, n] = suffix[:3, T]
    jac[:, n:-1] -= share
    jac[:, n + 1 :] += share
    stretch = (at_a[3:] - at_b[3:]) @ slope  # the grid's stretch: the same for every length
    later = np.zeros((3, n))
    later[:, :-1] = _accumulate((slope * on)[:, ::-1], axis=1)[:, ::-1]  # joints k .. J-1
    jac[:, :n] = (stretch + d_h / (T - 1))[:, None] - later
    return jac


def _widening(lengths: np.ndarray, angles: np.ndarray, rate: float) -> np.ndarray:
    """Factors (>= 1) by which overlapping ramps of one sign are widened to keep ``rate``."""
    jumps = angles[1:] - angles[:-1]
    factors = np.ones(len(jumps))
    if not len(jumps):
        return factors
    joints = lengths.cumsum()[:-1]
    if _apart_and_within(joints, jumps, rate):
        return factors
    probe = np.linspace(0.0, float(lengths.sum()), 4001)
    for _ in range(40):
        widths = np.maximum(np.abs(jumps) * factors / rate, 1e-9)
        lo, hi = joints - widths / 2, joints + widths / 2
        # Which ramps hold a probe changes only where one starts or ends: the first probe
        # of each run stands for the run (the same columns, ~2 J of 4 001). The running
        # sum adds the ramps in order as the (J, 4001) sum did (not pairwise, as a
        # single column's sum would be).
        p = probe[_runs(probe, lo, hi)]
        inside = (p[None, :] >= lo[:, None]) & (p[None, :] <= hi[:, None])
        slope = _accumulate(inside * (jumps / widths)[:, None], axis=0)[-1]
        # Each ramp's steepest summed slope (0 where a ramp covers no probe point).
        worst = np.where(inside, np.abs(slope)[None, :], 0.0).max(axis=1)
        over = worst > rate * (1.0 + 1e-9)
        if not over.any():
            break
        factors = np.where(over, factors * worst / rate * 1.001, factors)
    return factors


def _runs(probe: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The first probe index of each run of probes inside the same ramps ``[lo, hi]``.

    ``probe`` is sorted; every probe, where a bound is not finite.
    """
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        return np.arange(len(probe))
    edges = np.concatenate([[0], probe.searchsorted(lo), probe.searchsorted(hi, side="right")])
    edges = np.unique(edges)
    return edges[edges < len(probe)]


def _apart_and_within(joints: np.ndarray, jumps: np.ndarray, rate: float) -> bool:
    """Whether :func:`_widening`'s first round finds no ramp over ``rate`` (factors 1).

    True when no probe point can lie on two of the unwidened ramps (for every pair
    one ramp's start, as the probe test computes it, lies past the other's end) and
    each ramp's own slope keeps ``rate``: then every probe's summed slope is one
    ramp's, exactly (the other terms are zeros), and so is each ramp's steepest. The
    common case (ramps apart) without the probes' ``(J, 4001)`` arrays; False decides
    nothing (the probes do).
    """
    widths = np.maximum(np.abs(jumps) / rate, 1e-9)  # the first round's (factors 1: x * 1.0 = x)
    lo = (joints - widths / 2).tolist()
    hi = (joints + widths / 2).tolist()
    for i in range(len(lo)):
        for j in range(i + 1, len(lo)):
            # Two ramps may share a probe only when max(lo) <= min(hi) (NaN: not apart).
            if not (lo[j] > hi[i] or lo[i] > hi[j]):
                return False
    # A ramp that covers no probe point counts 0 in the probe test: also within.
    return bool((np.abs(jumps / widths) <= rate * (1.0 + 1e-9)).all())


def ramped_segment(
    rows: np.ndarray,
    gear: int,
    rate: float,
    wheelbase: float,
    delta_max: float,
    spacing: float = 0.2,
    angle_weight: float = 0.1,
    pinned: tuple[bool, bool] = (False, False),
) -> np.ndarray | None:
    """The segment with continuous steering at most ``rate`` rad/m, or ``None``.

    The arcs' lengths and steering angles are the unknowns of the end-pose fit
    (Gauss-Newton, least change: ``angle_weight`` radians cost as much as a metre),
    so every ramp keeps its rate by construction; the angles stay within
    ``delta_max``.

    Parameters
    ----------
    rows : numpy.ndarray
        ``(N, >=3)`` rows ``[x, y, yaw, ...]`` of exact arcs and lines in driving
        order (at most a few tenths of a metre apart on each arc).
    gear : int
        +1 forward, -1 reverse.
    rate : float
        Sharpness bound ``|d delta / ds|`` of the ramps, rad/m.
    wheelbase : float
        The car's wheelbase.
    delta_max : float
        The steering limit, ``atan(L kappa_max)``.
    spacing : float
        Largest gap between the returned rows.
    angle_weight : float
        Scale of an angle change against a length change in the fit.
    pinned : tuple of bool
        Keep the first / last piece's steering angle as it is (a chunk of a longer
        segment, :mod:`~.ramp_chunks`, meets its neighbour with that steering).

    Returns
    -------
    numpy.ndarray or None
        Rows ``[x, y, yaw, kappa]`` from the exact start pose to the exact end pose,
        or ``None`` when the end-pose fit does not converge.

    Examples
    --------
    >>> from rrtdrive.planning.hybrid.primitives import arc_poses
    >>> a = arc_poses(0.0, 0.0, 0.0, 0.0, 1, np.linspace(0, 5, 21))
    >>> b = arc_poses(*a[-1], 1 / 6, 1, np.linspace(0, 5, 21))
    >>> c = arc_poses(*b[-1], 0.0, 1, np.linspace(0, 5, 21))
    >>> rows = np.vstack([a, b[1:], c[1:]])
    >>> out = ramped_segment(rows, 1, 0.17, 2.51, math.atan(2.51 / 5.9))
    >>> bool(np.allclose(out[[0, -1], :3], rows[[0, -1], :3], atol=1e-9))
    True
    """
    # The rows are sampled for the fitted length, which the fit may lengthen a
    # little beyond the raw one: sample finer until every gap keeps ``spacing``.
    step = spacing
    for _ in range(4):
        out = _ramped_once(rows, gear, rate, wheelbase, delta_max, step, angle_weight, pinned)
        if out is None:
            return None
        d = out[1:, :2] - out[:-1, :2]
        gap = float(np.hypot(d[:, 0], d[:, 1]).max()) if len(out) > 1 else 0.0
        # 1e-9 m of slack: rows exactly ``spacing`` apart measure a few 1e-15 m more,
        # and re-sampling those changed a 1 m segment's rows (5 -> 6) and, through the
        # speed profile on them, the stop at its cusp (u-turn seed 35: 0.05 -> 0.125 m).
        if gap <= spacing + _GAP_SLACK:
            return out
        step *= 0.999 * spacing / gap
    return None


def _ramped_once(
    rows: np.ndarray,
    gear: int,
    rate: float,
    wheelbase: float,
    delta_max: float,
    spacing: float,
    angle_weight: float,
    pinned: tuple[bool, bool] = (False, False),
) -> np.ndarray | None:
    """One fit of :func:`ramped_segment` with rows about ``spacing`` apart.

    Slivers merged first (:func:`_without_slivers`); a fit that then fails is tried on
    the pieces as they are: merging takes a short word's end arc with it, or leaves a
    fit two equal halves, and some fits of the pieces themselves close (26 of 9 079
    words between nearly aligned poses in a session-35 audit, against 99 the merge
    closes that did not).
    """
    rows = np.asarray(rows, dtype=float)
    ds, kappa = _intervals(rows, gear)
    if not len(ds):
        return None
    fit = functools.partial(
        _fitted_pieces, rows, gear, rate, wheelbase, delta_max, spacing, angle_weight, pinned
    )
    pieces = _pieces(ds, kappa, wheelbase)
    merged = _without_slivers(*pieces)
    out = fit(*merged)
    if out is None and merged[0] is not pieces[0]:
        out = fit(*pieces)
    return out


def _fitted_pieces(
    rows: np.ndarray,
    gear: int,
    rate: float,
    wheelbase: float,
    delta_max: float,
    spacing: float,
    angle_weight: float,
    pinned: tuple[bool, bool],
    lengths: np.ndarray,
    angles: np.ndarray,
) -> np.ndarray | None:
    """The fit of :func:`_ramped_once` from these pieces' lengths and steering angles."""
    angles = _clip(angles, -delta_max, delta_max)
    n = len(lengths)
    start, goal = rows[0, :3].copy(), rows[-1, :3]
    total0 = float(lengths.sum())
    m = max(1, math.ceil(total0 / spacing - 1e-9))
    t = _nodes(m * _SUBSTEPS + 1)
    if n == 1:
        # One arc or line: already continuous (no ramp, nothing to fit: the profile and
        # the poses of _profiles and _integrate, bit for bit).
        _, _, delta, poses_of = _end_and_jacobian(
            np.concatenate([lengths, angles]), np.ones(0), rate, t, start, gear, wheelbase
        )
        return _rows(poses_of(_SUBSTEPS), delta, wheelbase, start, goal)
    p = np.concatenate([lengths, angles])
    weight, lower, upper = _fit_bounds(n, angle_weight, delta_max)
    if pinned[0] or pinned[1]:  # a zero weight holds the angle (bounded_step's "free")
        weight = weight.copy()
        weight[[i for i, pin in ((n, pinned[0]), (2 * n - 1, pinned[1])) if pin]] = 0.0
    factors = _widening(lengths, angles, rate)
    pose = None
    previous, flat = math.inf, 0
    for _ in range(_NEWTON_ITERATIONS):
        end, jacobian, d0, poses_of = _end_and_jacobian(
            p, factors, rate, t, start, gear, wheelbase
        )
        err = end - goal
        err[2] = wrap_angle(err[2])
        pose = (d0, poses_of)
        worst = float(np.abs(err).max())
        if worst < _NEWTON_TOL:
            break
        flat = flat + 1 if worst > _STUCK_FROM and worst >= _STUCK_SHARE * previous else 0
        if flat >= _STUCK_AFTER:
            return None
        previous = worst
        step = _bounded_step(jacobian(), err, p, weight, lower, upper)
        if step is None:
            return None
        p = _clip(p + step, lower, upper)
    else:
        return None
    if pose is None:
        return None
    delta, poses_of = pose
    return _rows(poses_of(_SUBSTEPS), delta, wheelbase, start, goal)


def _rows(
    poses: np.ndarray, delta: np.ndarray, wheelbase: float, start: np.ndarray, goal: np.ndarray
) -> np.ndarray:
    """Every ``_SUBSTEPS``-th pose (``poses``: those alone) with its curvature, exact ends."""
    out = np.empty((len(poses), 4))
    out[:, :3] = poses
    # The curvature of the returned rows only (elementwise: the same floats).
    np.divide(np.tan(delta[::_SUBSTEPS]), wheelbase, out=out[:, 3])
    out[0, :3], out[-1, :3] = start, goal
    return out


@functools.lru_cache(maxsize=256)
def _fit_bounds(n: int, angle_weight: float, delta_max: float) -> tuple[np.ndarray, ...]:
    """The fit's ``weight``, ``lower`` and ``upper`` for ``n`` pieces: read-only, made once."""
    weight = np.concatenate([np.ones(n), np.full(n, angle_weight**2)])
    lower = np.concatenate([np.zeros(n), np.full(n, -delta_max)])
    upper = np.concatenate([np.full(n, np.inf), np.full(n, delta_max)])
    for a in (weight, lower, upper):
        a.flags.writeable = False
    return weight, lower, upper


def _clip(a: np.ndarray, lower: np.ndarray | float, upper: np.ndarray | float) -> np.ndarray:
    """``np.clip(a, lower, upper)``, the same floats, without its Python wrappers."""
    return np.minimum(np.maximum(a, lower), upper)


@functools.lru_cache(maxsize=1024)
def _nodes(count: int) -> np.ndarray:
    """``np.linspace(0, 1, count)``, read-only, made once per count (the fit's grid ``t``)."""
    t = np.linspace(0.0, 1.0, count)
    t.flags.writeable = False
    return t
