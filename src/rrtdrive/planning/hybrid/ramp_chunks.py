"""Steering ramps for a long gear segment, fitted a stretch at a time.

:func:`~.ramps.ramped_segment` closes the end pose by the least change of every
piece's length and steering: on a long segment the ramps' small offsets add up and
the least change spreads their sum over the whole path, which then leaves the arcs
the search checked by metres (a 745 m segment across a 500 m map with 1 000 boxes:
13.5 m mid-way, where it hit a box; every one of the search's 429 connections shared
that stretch, and all were rejected). :func:`ramped_in_chunks` cuts the segment at
rows in the middle of long pieces, clear of the ramps at their ends, into stretches
of at least :data:`CHUNK_M`, and fits each stretch to its own end pose with the
steering at the cuts held (:func:`~.ramps.ramped_segment`'s ``pinned``), so the
offsets are closed where they arise and the steering stays continuous across a cut.
"""

from __future__ import annotations

from collections.abc import MutableMapping

import numpy as np

from rrtdrive.planning.hybrid.pieces import intervals, run_starts
from rrtdrive.planning.hybrid.ramps import ramped_segment

__all__ = ["CHUNK_M", "cut_rows", "ramped_in_chunks"]

#: Shortest stretch fitted on its own, metres: long enough for a few turns' ramps,
#: short enough that their offsets stay centimetres.
CHUNK_M = 20.0
#: How far a cut stays from a piece's ends, in widths of the ramp there (ramps that
#: overlap are widened, so with room to spare), plus :data:`_CUT_SLACK_M`.
_CUT_CLEAR = 1.5
_CUT_SLACK_M = 0.5


def cut_rows(rows: np.ndarray, gear: int, rate: float, wheelbase: float) -> list[int]:
    """Row indices where :func:`ramped_in_chunks` cuts ``rows`` (first and last row not among them).

    A cut is a row inside a piece of constant steering, nearest its middle, at least
    :data:`_CUT_CLEAR` ramp widths (plus :data:`_CUT_SLACK_M`) from each of the
    piece's joints, and :data:`CHUNK_M` or more along the path from the previous cut.

    Examples
    --------
    >>> from rrtdrive.planning.hybrid.primitives import arc_poses
    >>> a = arc_poses(0.0, 0.0, 0.0, 0.0, 1, np.linspace(0, 50, 251))  # 50 m straight on
    >>> b = arc_poses(*a[-1], 1 / 6, 1, np.linspace(0, 5, 26))  # 5 m of a left turn
    >>> c = arc_poses(*b[-1], 0.0, 1, np.linspace(0, 50, 251))  # 50 m straight on
    >>> rows = np.vstack([a, b[1:], c[1:]])
    >>> cuts = cut_rows(rows, 1, 0.2, 2.51)  # the middle of each line
    >>> cuts, rows[cuts, :2].round(2).tolist()
    ([125, 400], [[25.0, 0.0], [71.25, 20.47]])
    """
    rows = np.asarray(rows, dtype=float)
    ds, kappa = intervals(rows, gear)
    if len(ds) != len(rows) - 1:  # repeated rows: no cut (the fit of the whole decides)
        return []
    delta = np.arctan(wheelbase * kappa)
    s = np.concatenate([[0.0], np.cumsum(ds)])  # arc length at each row
    # Pieces: runs of intervals with the same steering, as the fit merges them.
    first = np.flatnonzero(run_starts(delta))  # first interval of each piece
    last = np.concatenate([first[1:], [len(ds)]])  # one past its last interval
    angle = delta[first]
    jump = np.abs(np.diff(angle))
    width = np.concatenate([[0.0], jump / rate, [0.0]])  # ramp width at each piece boundary
    cuts: list[int] = []
    previous = 0.0
    for p in range(len(first)):
        lo, hi = s[first[p]], s[last[p]]
        room_lo = lo + _CUT_CLEAR * width[p] + _CUT_SLACK_M
        room_hi = hi - _CUT_CLEAR * width[p + 1] - _CUT_SLACK_M
        if room_lo > room_hi:
            continue
        # The row nearest the piece's middle, within the room (rows of the piece only).
        inside = np.arange(first[p] + 1, last[p])
        inside = inside[(s[inside] >= room_lo) & (s[inside] <= room_hi)]
        if not len(inside):
            continue
        row = int(inside[np.argmin(np.abs(s[inside] - 0.5 * (lo + hi)))])
        if s[row] - previous >= CHUNK_M and s[-1] - s[row] >= CHUNK_M:
            cuts.append(row)
            previous = s[row]
    return cuts


def ramped_in_chunks(
    rows: np.ndarray,
    gear: int,
    rate: float,
    wheelbase: float,
    delta_max: float,
    spacing: float = 0.2,
    fits: MutableMapping[tuple[int, tuple[bool, bool], bytes], np.ndarray | None] | None = None,
) -> np.ndarray | None:
    """:func:`~.ramps.ramped_segment` a stretch at a time, or ``None`` (no cut, or a fit failed).

    Each stretch between cuts (:func:`cut_rows`) is fitted to its own exact end
    poses, the steering at a cut held on both sides; the stretches' rows are joined
    (the cut row once). The caller checks the result as it checks a whole fit
    (body, curvature, sharpness across the cuts too). ``fits``: the stretches fitted
    before with the same other arguments (a search's connections share their first
    ones), read and added to; the same rows as fitting them again.
    """
    cuts = cut_rows(rows, gear, rate, wheelbase)
    if not cuts:
        return None
    bounds = [0, *cuts, len(rows) - 1]
    parts: list[np.ndarray] = []
    for k, (a, b) in enumerate(zip(bounds[:-1], bounds[1:], strict=True)):
        pinned = (k > 0, k < len(bounds) - 2)
        stretch = rows[a : b + 1]
        key = (gear, pinned, stretch.tobytes())
        if fits is not None and key in fits:
            part = fits[key]
        else:
            part = ramped_segment(
                stretch, gear, rate, wheelbase, delta_max, spacing=spacing, pinned=pinned
            )
            if fits is not None:
                fits[key] = part
        if part is None:
            return None
        # The steering must meet the last stretch's at the cut: a ramp the fit widened
        # (or a piece it shortened) can reach across the cut and move it (an audit's
        # fuzz: 5 of 8 429 random chains, up to 0.7 rad/m there).
        if parts and abs(part[0, 3] - parts[-1][-1, 3]) > 1e-9:
            return None
        parts.append(part if k == 0 else part[1:])
    return np.vstack(parts)
