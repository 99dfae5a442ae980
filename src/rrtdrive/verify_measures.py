"""The discrete measures of :mod:`rrtdrive.verify`: curvature, sharpness and travel of rows.

They read positions and yaws only, never the rows' ``kappa`` column, and share no
code with the planners.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from rrtdrive.geometry import wrap_angle

__all__ = [
    "STILL_M",
    "YAW_ROUND",
    "segment_curvature",
    "segment_sharpness",
    "travel_directions",
    "turn_curvature",
]


def _signed_menger(xy: np.ndarray) -> np.ndarray:
    """Curvature of the circle through each three consecutive points, + turning left."""
    a, b, c = xy[:-2], xy[1:-1], xy[2:]
    ab, bc, ca = b - a, c - b, a - c
    cross = ab[:, 0] * bc[:, 1] - ab[:, 1] * bc[:, 0]
    denom = np.hypot(*ab.T) * np.hypot(*bc.T) * np.hypot(*ca.T)
    return np.where(denom > 1e-12, 2.0 * cross / np.maximum(denom, 1e-300), 0.0)


def _menger(xy: np.ndarray) -> np.ndarray:
    return np.abs(_signed_menger(xy))


def _thin(xy: np.ndarray, min_gap: float) -> list[int]:
    """Indices of points of ``xy`` at least ``min_gap`` apart along the polyline, and the last."""
    gaps = np.hypot(*np.diff(xy, axis=0).T)
    keep = [0]
    acc = 0.0
    for i, g in enumerate(gaps, start=1):
        acc += g
        if acc >= min_gap:
            keep.append(i)
            acc = 0.0
    if keep[-1] != len(xy) - 1:
        keep.append(len(xy) - 1)
    return keep


#: The finest point gaps the curvature and sharpness of a short gear segment are
#: measured over, metres: the rows' 6 decimals (1e-6 m) err by about 1e-6 / gap^2 in
#: curvature (0.0025 1/m at 0.02 m) and 1e-6 / gap^3 in sharpness (0.001 rad/m at 0.1 m).
_SHORT_CURVATURE_GAP = 0.02
_SHORT_SHARPNESS_GAP = 0.1


def _polyline_length(xy: np.ndarray) -> float:
    return float(np.hypot(*np.diff(xy, axis=0).T).sum())


def segment_curvature(xy: np.ndarray) -> float:
    """Largest Menger curvature over points about 0.5 m apart (less noise than adjacent samples).

    A segment too short for three such points (under about 1 m: a manoeuvre's short
    move) is measured over points a quarter of its length apart, down to
    :data:`_SHORT_CURVATURE_GAP`; before, it read 0 whatever its turn.
    """
    keep = _thin(xy, 0.5)
    if len(keep) < 3:
        gap = _polyline_length(xy) / 4.0
        if gap < _SHORT_CURVATURE_GAP:
            return 0.0
        keep = _thin(xy, gap)
    return float(_menger(xy[keep]).max()) if len(keep) >= 3 else 0.0


def segment_sharpness(xy: np.ndarray, wheelbase: float) -> float:
    """Largest ``|d delta / ds|`` of one gear segment, from signed Menger curvature.

    Points closer than 0.2 m are thinned out (rounding noise grows as 1 / gap^2).
    The circle through three points a, b, c with gaps ``ab``, ``bc`` has the
    curvature of the curve about ``(bc - ab) / 3`` past b (first order), so the
    rate is taken between those positions. A segment with fewer than five such
    points is measured over gaps of a fifth of its length, down to
    :data:`_SHORT_SHARPNESS_GAP`; one still with fewer than four points (under
    about 0.3 m) has fewer than two estimates and reads 0.
    """
    gap = 0.2
    keep = _thin(xy, gap)
    if len(keep) < 5:
        # Under about 0.8 m: points a fifth of its length apart (see _segment_curvature).
        gap = max(_polyline_length(xy) / 5.0, _SHORT_SHARPNESS_GAP)
        keep = _thin(xy, gap)
    if len(keep) > 2 and np.hypot(*(xy[keep[-1]] - xy[keep[-2]])) < gap:
        del keep[-2]  # the last point stands in for a kept one too close to it
    pts = xy[keep]
    if len(pts) < 4:
        return 0.0
    gaps = np.hypot(*np.diff(pts, axis=0).T)
    where = np.cumsum(gaps)[:-1] + (gaps[1:] - gaps[:-1]) / 3.0
    delta = np.arctan(wheelbase * _signed_menger(pts))
    return float(np.max(np.abs(np.diff(delta)) / np.diff(where)))


#: Steps shorter than this are no move: the plan JSON's 6 decimals leave up to sqrt(2)
#: micrometres between rows that are one pose, whose direction means nothing.
STILL_M = 2e-6


def travel_directions(seg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Chord direction of travel of a segment's non-zero steps, and those steps' indices."""
    d = np.diff(seg[:, :2], axis=0)
    moving = np.flatnonzero(np.hypot(*d.T) > STILL_M)
    return np.arctan2(d[moving, 1], d[moving, 0]), moving


#: Radians a yaw may be off from rounding alone: the JSON's 6 decimals (5e-7 a value).
YAW_ROUND = 2e-6


def turn_curvature(seg: np.ndarray) -> float:
    """Largest curvature the rows' yaw turn asks for: ``2 sin(|dyaw| / 2) / chord`` per step.

    Any curve of curvature at most k that turns by ``dyaw`` (under pi) has a chord
    of at least ``2 sin(dyaw / 2) / k`` (an arc is the shortest), so a larger value
    is a turn the car cannot make there, whatever the positions between the rows.
    A turn where the car does not move (a chord under :data:`STILL_M`) is inf.
    """
    chord = np.hypot(*np.diff(seg[:, :2], axis=0).T)
    turn = np.maximum(np.abs(wrap_angle(np.diff(seg[:, 2]))) - YAW_ROUND, 0.0)
    moving = chord > STILL_M
    if np.any(turn[~moving] > 0.0):
        return math.inf
    if not moving.any():
        return 0.0
    return float(np.max(2.0 * np.sin(0.5 * turn[moving]) / chord[moving]))


def kappa_column_error(seg: np.ndarray, kappa_max: float | None = None) -> tuple[float, int]:
    """How far the rows' ``kappa`` lies outside the curvature their yaw turns at, and where.

    A gear segment's steering curvature between two rows is its yaw's turn per arc
    length, by the gear (``gear * 2 sin(dyaw / 2) / chord``: in reverse a left lock turns
    the nose right); that is the mean over the step, the value at its middle where the
    curvature changes linearly. A row's ``kappa`` (``tan delta / L`` in both gears) must
    lie between the steps' values on either side of it, or their lines through the
    steps beyond extended to the row (a steering ramp's peak lies above both of its
    steps' means by half a step of the ramp). The segment's first and last rows are
    stops, where the car may steer standing: their ``kappa`` is a convention (a Dubins
    word's last row has 0, a junction row the curvature of the piece that starts there)
    and is not checked against the bracket; given ``kappa_max``, it must lie within the
    car's reach: ``kappa_max``, or the first (last) step's own turn where that is more
    (then the curvature check fails, and this one need not say it twice). The excess
    over the bound is returned with its row (index within ``seg``; -1 when no row is
    checked).

    Examples
    --------
    >>> s = np.linspace(0.0, 2.0, 11)
    >>> arc = np.column_stack([np.sin(s / 5) * 5, (1 - np.cos(s / 5)) * 5, s / 5,
    ...                        np.full(11, 0.2), np.ones(11)])
    >>> err, _ = kappa_column_error(arc)
    >>> bool(err < 1e-9)
    True
    >>> arc[:, 3] *= -1.0  # the sign of a reverse segment's convention
    >>> round(kappa_column_error(arc)[0], 3)
    0.4
    """
    chord = np.hypot(*np.diff(seg[:, :2], axis=0).T)
    moving = chord > STILL_M
    if not moving.any():
        return _end_excess(seg, kappa_max, np.zeros(2)) if kappa_max is not None else (0.0, -1)
    gear = -1.0 if seg.shape[1] > 4 and seg[0, 4] < 0 else 1.0
    turn = wrap_angle(np.diff(seg[:, 2]))
    with np.errstate(divide="ignore", invalid="ignore"):
        step = np.where(moving, gear * 2.0 * np.sin(0.5 * turn) / chord, np.nan)
        # The yaws' 6 decimals (YAW_ROUND each) move a short step's value by this much.
        slack = np.where(moving, 2.0 * YAW_ROUND / chord, np.nan)
        # Each step's line through the step before it (``ahead``: after it), at its end.
        share = chord[1:] / (chord[1:] + chord[:-1])
        back = step[1:] + (step[1:] - step[:-1]) * share
        share = chord[:-1] / (chord[:-1] + chord[1:])
        ahead = step[:-1] + (step[:-1] - step[1:]) * share
    none = np.array([np.nan])
    values = (
        np.concatenate([none, step]),  # the step before the row
        np.concatenate([step, none]),  # the step after it
        np.concatenate([none, none, back]),  # the step before, extended to the row
        np.concatenate([ahead, none, none]),  # the step after, extended back to it
    )
    lo, hi = functools.reduce(np.fmin, values), functools.reduce(np.fmax, values)
    pad = np.fmax(np.concatenate([none, slack]), np.concatenate([slack, none]))
    excess = np.fmax(lo - seg[:, 3], seg[:, 3] - hi) - pad
    excess = np.where(np.isnan(excess), 0.0, np.maximum(excess, 0.0))[1:-1]
    err, row = (float(np.max(excess)), int(np.argmax(excess)) + 1) if len(excess) else (0.0, -1)
    if kappa_max is not None:
        reach = np.abs(np.where(np.isnan(step[[0, -1]]), 0.0, step[[0, -1]]))
        end_err, end_row = _end_excess(seg, kappa_max, reach)
        if end_err > err:
            err, row = end_err, end_row
    return err, row


def _end_excess(seg: np.ndarray, kappa_max: float, steps: np.ndarray) -> tuple[float, int]:
    """How far the end rows' ``|kappa|`` exceeds ``kappa_max`` or their steps' turn."""
    # A start row at 5 1/m turned the wheels to full lock before the car moved (an audit).
    over = np.abs(seg[[0, -1], 3]) - np.maximum(kappa_max, steps)
    k = 0 if over[0] >= over[1] else 1
    return float(over[k]), (0, len(seg) - 1)[k]
