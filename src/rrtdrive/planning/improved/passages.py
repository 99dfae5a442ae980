"""Passage sampling (beyond the paper): cells on the centre lines of narrow passages."""

from __future__ import annotations

import math
import weakref
from collections.abc import Sequence

import numpy as np

from rrtdrive.collision import CollisionChecker

__all__ = ["passage_cells"]


_PASSAGES: weakref.WeakKeyDictionary[CollisionChecker, dict[int, np.ndarray]] = (
    weakref.WeakKeyDictionary()
)


def passage_cells(
    checker: CollisionChecker, start: Sequence[float], width: float = 0.6
) -> np.ndarray:
    """Centres of the grid cells on the centre lines of narrow passages reachable from ``start``.

    A cell qualifies when its clearance is a local maximum across some grid
    direction (a ridge of the distance field, i.e. the medial axis) with walls
    on both sides (one clearance away along that direction the clearance nearly
    vanishes) and lies between the edge test's radius ``W/2 + margin`` and that
    plus ``width``: an edge through it can pass, but only just. Wide aisles, the
    gaps between parked cars (too narrow), convex corners and open space do not
    qualify. Beyond the paper;
    medial-axis sampling after Wilmarth, Amato & Stiller (ICRA 1999). Cached per
    checker and start component.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker.
    start : sequence of float
        A point of the component to keep (the start position).
    width : float
        How much wider than the edge test a passage may be, in metres.

    Returns
    -------
    numpy.ndarray
        ``(K, 2)`` cell centres (possibly empty).

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> from rrtdrive.planning.base import cached_checker
    >>> cells = passage_cells(cached_checker(builtin_map("narrow_gap")), (10.0, 20.0))
    >>> bool(np.any((np.abs(cells[:, 0] - 50.0) < 1.0) & (np.abs(cells[:, 1] - 50.0) < 0.2)))
    True
    """
    labels = checker.component_labels
    origin, h = checker.grid_origin, checker.resolution
    i = int(math.floor((start[0] - origin[0]) / h))
    j = int(math.floor((start[1] - origin[1]) / h))
    inside = 0 <= i < labels.shape[0] and 0 <= j < labels.shape[1]
    label = int(labels[i, j]) if inside else 0
    per_checker = _PASSAGES.setdefault(checker, {})
    key = (label, float(width))
    cached = per_checker.get(hash(key))
    if cached is not None:
        return cached
    cl = checker.clearance_grid
    nx, ny = cl.shape
    band = (cl >= checker.edge_radius) & (cl <= checker.edge_radius + width)
    if label:
        band &= labels == label
    ridge = np.zeros(cl.shape, dtype=bool)
    inner = cl[1:-1, 1:-1]
    for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
        # A local maximum of the clearance across direction (di, dj) ...
        a = cl[1 + di : nx - 1 + di, 1 + dj : ny - 1 + dj]
        b = cl[1 - di : nx - 1 - di, 1 - dj : ny - 1 - dj]
        peak = np.zeros(cl.shape, dtype=bool)
        peak[1:-1, 1:-1] = (inner >= a) & (inner >= b) & (inner > np.minimum(a, b))
        cand = np.argwhere(peak & band)
        if len(cand) == 0:
            continue
        # ... with walls on both sides: one clearance away, either way, the
        # clearance nearly vanishes (it does not beside a convex corner).
        c = cl[cand[:, 0], cand[:, 1]]
        k = np.round(c / (math.hypot(di, dj) * h)).astype(np.int64)
        both = np.ones(len(cand), dtype=bool)
        for sgn in (1, -1):
            ii = np.clip(cand[:, 0] + sgn * k * di, 0, nx - 1)
            jj = np.clip(cand[:, 1] + sgn * k * dj, 0, ny - 1)
            both &= cl[ii, jj] <= 0.3 * c
        ridge[cand[both, 0], cand[both, 1]] = True
    ij = np.argwhere(ridge)
    cells = origin + (ij + 0.5) * h
    xmin, ymin, xmax, ymax = checker.bounds
    cells = cells[
        (cells[:, 0] > xmin) & (cells[:, 0] < xmax) & (cells[:, 1] > ymin) & (cells[:, 1] < ymax)
    ]
    per_checker[hash(key)] = cells
    return cells
