"""The steering ramps' sum of :mod:`~.ramps`: every joint's ramp on the fit's grid.

``sum_j jumps_j * clip((s - joints_j) / widths_j + 0.5, 0, 1)``, summed in ``j``
order from 0.0, bit for bit as the whole ``(B, J, T)`` array sums along ``j``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["FULL_SUM_MAX", "ramp_sum", "ramp_sum_full", "ramp_sum_one"]

#: The ufuncs that ``ndarray.cumsum`` / ``.sum`` call (the same floats), without their wrappers.
_accumulate, _add_reduce = np.add.accumulate, np.add.reduce
#: Size ``B * J * T`` up to which the steering sum is the whole ``(B, J, T)`` array.
FULL_SUM_MAX = 4096


def ramp_sum(
    s: np.ndarray,
    t: np.ndarray,
    total: np.ndarray,
    joints: np.ndarray,
    jumps: np.ndarray,
    widths: np.ndarray,
) -> np.ndarray:
    """``sum_j jumps_j * clip((s - joints_j) / widths_j + 0.5, 0, 1)``, summed in ``j`` order.

    Bit for bit the sum of the ``(B, J, T)`` array along ``j`` (numpy adds along a
    non-contiguous axis one term after the other), computed one joint at a time:
    before a ramp's columns its term is zero (adding it changes nothing), after
    them it is the jump itself; only the columns its ramp may cover, in some row,
    are evaluated. ``s`` is ``total * t`` per row, ``t`` increasing from 0 to 1.
    One row (the fit's) is summed by :func:`_ramp_sum_row`, the loop's floats
    without its dozen numpy calls a joint.
    """
    B, T = s.shape
    # Small sums (the common short segment) in one piece: the joint-by-joint loop's
    # numpy calls cost more there than the (B, J, T) array they spare.
    if B * joints.shape[1] * T <= FULL_SUM_MAX:
        return ramp_sum_full(s, joints, jumps, widths)
    if not (np.isfinite(jumps).all() and np.isfinite(joints).all() and np.isfinite(s).all()):
        return ramp_sum_full(s, joints, jumps, widths)  # NaN/inf propagate as they did
    acc = np.zeros((B, T))
    if not joints.shape[1]:
        return acc
    span = np.maximum(total, 1e-300)
    # Columns where some row's ramp may start or end, two columns of slack each way
    # (t's spacing is far above the rounding of s = total * t); beyond them u <= 0
    # or u >= 1 in every row, so clip gives exactly 0 or 1.
    lo = t.searchsorted(((joints - 0.5 * widths) / span[:, None]).min(axis=0)) - 2
    hi = t.searchsorted(((joints + 0.5 * widths) / span[:, None]).max(axis=0)) + 2
    lo, hi = np.minimum(np.maximum(lo, 0), T), np.minimum(np.maximum(hi, 0), T)  # clip
    if B == 1:
        return _ramp_sum_row(s[0], lo, np.maximum(hi, lo), joints[0], jumps[0], widths[0])[None]
    for j in range(joints.shape[1]):
        a, b = int(lo[j]), int(max(hi[j], lo[j]))
        if b > a:
            u = s[:, a:b] - joints[:, j : j + 1]
            u /= widths[:, j : j + 1]
            u += 0.5
            np.maximum(u, 0.0, out=u)
            np.minimum(u, 1.0, out=u)
            u *= jumps[:, j : j + 1]
            acc[:, a:b] += u
        if b < T:
            acc[:, b:] += jumps[:, j : j + 1]
    return acc


def ramp_sum_one(
    s: np.ndarray,
    t: np.ndarray,
    total: float,
    joints: np.ndarray,
    jumps: np.ndarray,
    widths: np.ndarray,
) -> np.ndarray:
    """:func:`ramp_sum` of one row as 1-D arrays (``total`` a number), without the 2-D wrappers.

    The same floats as ``ramp_sum(s[None], t, total[None], ...)[0]`` when ``J * T``
    exceeds :data:`FULL_SUM_MAX`: the ramps' columns from the same quotients (the
    minimum and maximum over one row are its own values), then :func:`_ramp_sum_row`.
    NaN or inf anywhere (then the sum below is not finite either: an overflow of a
    finite sum only sends it to the full sum too, which is the reference) takes the
    full sum, as there.
    """
    if not math.isfinite(float(_add_reduce(jumps)) + float(_add_reduce(joints)) + float(s[-1])):
        return ramp_sum_full(s[None], joints[None], jumps[None], widths[None])[0]
    T = len(s)
    if not len(joints):
        return np.zeros(T)
    span = np.maximum(total, 1e-300)
    lo = t.searchsorted((joints - 0.5 * widths) / span) - 2
    hi = t.searchsorted((joints + 0.5 * widths) / span) + 2
    lo, hi = np.minimum(np.maximum(lo, 0), T), np.minimum(np.maximum(hi, 0), T)  # clip
    return _ramp_sum_row(s, lo, np.maximum(hi, lo), joints, jumps, widths)


def _ramp_sum_row(
    s: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    joints: np.ndarray,
    jumps: np.ndarray,
    widths: np.ndarray,
) -> np.ndarray:
    """:func:`ramp_sum`'s joint loop for one row, in a few numpy calls (not a dozen a joint).

    The loop adds at column ``c``, in ``j`` order from 0.0: the jump of each ramp
    whose columns ``[a_j, b_j)`` end at or before ``c``, the clipped term of each
    ramp whose columns hold ``c``, nothing for a ramp that starts after ``c``. The
    leading ramps ``0 .. p-1`` that all end by ``c`` (``p``: how many of the running
    maxima of ``b`` are ``<= c``) give their jumps one after the other from 0.0,
    the running sum ``prefix[p]``; every later ramp that starts by ``c`` is a
    ``(column, ramp)`` pair (its term, computed from the same operands with the same
    operations, or its jump once it has ended), and ``np.add.at`` adds the pairs one
    after the other in the order given, ``j`` ascending: the loop's additions at
    ``c``, in its order, the same floats.
    """
    J, T = len(jumps), len(s)
    prefix = np.empty(J + 1)
    prefix[0] = 0.0
    _accumulate(jumps, out=prefix[1:])
    # The loop's sums start from 0.0: 0.0 + x is x but for x = -0.0 (then 0.0), and a
    # running sum from 0.0 is never -0.0; so each accumulated sum + 0.0 is the loop's.
    prefix[1:] += 0.0
    ended = np.maximum.accumulate(b)  # ended[j]: ramps 0 .. j have all ended here
    edges = np.empty(J + 2, dtype=np.int64)
    edges[0], edges[1:-1], edges[-1] = 0, ended, T
    acc = prefix.repeat(edges[1:] - edges[:-1])  # prefix[#{j: ended_j <= c}] at column c
    lens = np.maximum(ended, a) - a
    k = int(_add_reduce(lens))
    if k:
        starts = _accumulate(lens) - lens  # where ramp j's columns begin in the pairs
        cols = np.arange(k) + (a - starts).repeat(lens)
        jj = np.arange(J).repeat(lens)
        u = s[cols] - joints[jj]
        u /= widths[jj]
        u += 0.5
        np.maximum(u, 0.0, out=u)
        np.minimum(u, 1.0, out=u)
        u *= jumps[jj]
        if (ended != b).any():  # a ramp ended under an earlier one: past b_j, its jump
            np.copyto(u, jumps[jj], where=cols >= b[jj])
        np.add.at(acc, cols, u)
    return acc


def ramp_sum_full(
    s: np.ndarray, joints: np.ndarray, jumps: np.ndarray, widths: np.ndarray
) -> np.ndarray:
    """:func:`ramp_sum` over the whole ``(B, J, T)`` array (the reference)."""
    u = s[:, None, :] - joints[:, :, None]
    u /= widths[:, :, None]
    u += 0.5
    np.maximum(u, 0.0, out=u)
    np.minimum(u, 1.0, out=u)
    u *= jumps[:, :, None]
    return u.sum(axis=1) if u.shape[1] else np.zeros(s.shape)
