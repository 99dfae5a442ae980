"""A gear segment's rows as pieces of steady steering, for the ramp fit (:mod:`.ramps`).

:func:`intervals` reads each row interval's length and steering curvature from the
geometry, :func:`runs` joins runs of equal steering into pieces, and
:func:`without_slivers` merges pieces too short to ramp to and from.
"""

from __future__ import annotations

import numpy as np

from rrtdrive.geometry import wrap_angle

__all__ = ["SLIVER_M", "intervals", "run_starts", "runs", "without_slivers"]


def intervals(rows: np.ndarray, gear: int) -> tuple[np.ndarray, np.ndarray]:
    """Arc length of each row interval and its signed steering curvature.

    The curvature is read from the geometry (``d yaw / (gear ds)``), not from the
    rows' kappa column, so the row convention at joints does not matter.
    """
    step = rows[1:, :3] - rows[:-1, :3]  # np.diff's arithmetic, one call for the three columns
    chord = np.hypot(step[:, 0], step[:, 1])
    dyaw = wrap_angle(step[:, 2])
    half = 0.5 * np.abs(dyaw)
    # The arc through two poses of an arc: chord * (theta/2) / sin(theta/2). No errstate
    # needed: wrapped, half <= pi/2, so sin(max(half, 1e-300)) > 0; NaN raises no flag.
    factor = np.where(half > 1e-9, half / np.sin(np.maximum(half, 1e-300)), 1.0)
    ds = chord * factor
    keep = ds > 1e-9
    ds, dyaw = ds[keep], dyaw[keep]
    return ds, dyaw / (gear * ds)


def run_starts(delta: np.ndarray) -> np.ndarray:
    """Whether each interval starts a new piece: its steering differs from the last by > 1e-6."""
    new = np.empty(len(delta), dtype=bool)
    new[0] = True
    np.greater(np.abs(delta[1:] - delta[:-1]), 1e-6, out=new[1:])
    return new


def runs(ds: np.ndarray, kappa: np.ndarray, wheelbase: float) -> tuple[np.ndarray, np.ndarray]:
    """Runs of equal curvature merged: their lengths and steering angles."""
    delta = np.arctan(wheelbase * kappa)
    new = run_starts(delta)
    idx = new.cumsum() - 1
    lengths = np.bincount(idx, weights=ds)
    angles = np.bincount(idx, weights=delta * ds) / lengths
    return lengths, angles


#: Pieces shorter than this (metres) are slivers: merged into a neighbour before the fit.
#: A Reeds-Shepp word between nearly aligned poses has full-lock arcs of a few 1e-5 m at
#: its ends (a turn of about 5e-6 rad); ramping the steering to full lock and back for
#: each took some 2 m and wove the fitted path into the walls of a lane (the overtake
#: road with goal yaw -3.14159 against a start at 3.14159: all 132 connections rejected,
#: session 35). A sliver turns the car at most ``kappa_max`` x 1 mm (2e-4 rad), which the
#: end-pose fit takes up in the other pieces' lengths and angles.
SLIVER_M = 1e-3


def without_slivers(lengths: np.ndarray, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``lengths``/``angles`` with every piece under :data:`SLIVER_M` merged into a neighbour.

    Each sliver goes to the neighbour whose steering is nearer its own (the previous one
    on a tie), runs of equal steering are joined again, and a segment left with one piece
    is split into two halves, so that the fit still has the four unknowns a pose's three
    coordinates need (a sliver's turn must be taken up somewhere). Pieces with no
    sliver come back as they are (the same arrays).

    Examples
    --------
    >>> lengths, angles = without_slivers(np.array([2e-5, 87.0, 2e-5]), np.array([0.39, 0, 0.39]))
    >>> np.round(lengths, 5).tolist(), angles.tolist()
    ([43.50002, 43.50002], [0.0, 0.0])
    >>> without_slivers(np.array([3.0, 5e-4, 4.0]), np.array([0.2, 0.0, 0.2]))[1].tolist()
    [0.2, 0.2]
    """
    if len(lengths) < 2 or lengths.min() >= SLIVER_M:
        return lengths, angles
    kept_l, kept_a = list(lengths), list(angles)
    while len(kept_l) > 1:
        i = min(range(len(kept_l)), key=kept_l.__getitem__)
        if kept_l[i] >= SLIVER_M:
            break
        if i == 0:
            j = 1
        elif i == len(kept_l) - 1:
            j = i - 1
        else:
            before, after = abs(kept_a[i - 1] - kept_a[i]), abs(kept_a[i + 1] - kept_a[i])
            j = i - 1 if before <= after else i + 1
        kept_l[j] += kept_l[i]
        del kept_l[i], kept_a[i]
        # Join the neighbours the sliver stood between (now at i - 1 and i) when they
        # steer alike.
        k = i
        if 0 < k < len(kept_l) and abs(kept_a[k] - kept_a[k - 1]) <= 1e-6:
            kept_l[k - 1] += kept_l[k]
            del kept_l[k], kept_a[k]
    if len(kept_l) == 1:
        kept_l, kept_a = [0.5 * kept_l[0]] * 2, kept_a * 2
    return np.array(kept_l), np.array(kept_a)
