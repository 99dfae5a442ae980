"""Adaptive obstacle expansion (paper Sec. 3.1.4) and the end poses' clearance cap."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np
from scipy.spatial import cKDTree

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Obstacle
from rrtdrive.types import Pose

__all__ = [
    "default_expansion_lmin",
    "endpoint_capped_clearance",
    "envelope_gaps",
    "expand_obstacles",
    "expanded_checker",
]


def endpoint_capped_clearance(
    checker: CollisionChecker, start: Pose, goal: Pose, wanted: float
) -> float:
    """``wanted``, lowered to the exact body clearance of the start or goal pose if smaller.

    A path cannot keep more room than its own end poses have; asking for it
    would make a car parked near a wall unplannable.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker (its exact ``body_clearance``).
    start, goal : Pose
        The query's rear-axle end poses.
    wanted : float
        The clearance asked for, metres (<= 0: none).

    Returns
    -------
    float
        Metres, in ``[0, wanted]`` (just under the end poses' clearance when capped).
    """
    if wanted <= 0.0:
        return 0.0
    have = min(checker.body_clearance(start.as_tuple()), checker.body_clearance(goal.as_tuple()))
    return max(0.0, min(wanted, have * 0.999))


def default_expansion_lmin(width: float, margin: float, a: float) -> float:
    """Default ``L_min = W + 2 margin + sqrt(2) a``.

    Growing a rectangle by ``a`` in length and width moves each of its points by
    at most ``a / sqrt(2)`` (a corner, diagonally), so two grown neighbours lose at
    most ``sqrt(2) a`` of their gap. A pair whose envelope circles are more than
    ``L_min`` apart (and so the rectangles too) keeps a gap above ``W + 2 margin``,
    the width of the swept disc of the edge test: no gap the car could use is closed.

    Parameters
    ----------
    width : float
        The car's width ``W``, metres.
    margin : float
        The edge test's margin, metres.
    a : float
        The expansion's growth of length and width, metres.

    Returns
    -------
    float
        ``L_min`` in metres.

    Examples
    --------
    >>> round(default_expansion_lmin(1.8, 0.1, 1.0), 3)
    3.414
    """
    return width + 2.0 * margin + math.sqrt(2.0) * a


def envelope_gaps(
    obstacles: Iterable[Obstacle], bounds: Iterable[float] | None = None
) -> np.ndarray:
    """``L2`` of each obstacle: the smallest gap between its envelope circle and any other's.

    The envelope circle is centred on the rectangle with radius half its diagonal.
    When ``bounds`` are given, the map boundary counts as an obstacle too (the gap
    from the circle to each side of the bounds box), so expansion never closes a
    passage along the map's edge.

    Parameters
    ----------
    obstacles : iterable of Obstacle
        The map's rectangles.
    bounds : iterable of float, optional
        ``(xmin, ymin, xmax, ymax)`` of the map (``None``: the boundary does not count).

    Returns
    -------
    numpy.ndarray
        One gap per obstacle (``inf`` for a lone obstacle without bounds).

    Examples
    --------
    >>> obs = [Obstacle((0.0, 0.0), (6.0, 8.0)), Obstacle((20.0, 0.0), (6.0, 8.0))]
    >>> envelope_gaps(obs).tolist()
    [10.0, 10.0]
    """
    obs = list(obstacles)
    if not obs:
        return np.zeros(0)
    c = np.array([o.center for o in obs], dtype=float)
    r = np.array([math.hypot(*o.size) / 2.0 for o in obs])
    out = _nearest_circle_gaps(c, r)
    if bounds is not None:
        xmin, ymin, xmax, ymax = (float(b) for b in bounds)
        wall = (
            np.minimum.reduce([c[:, 0] - xmin, xmax - c[:, 0], c[:, 1] - ymin, ymax - c[:, 1]]) - r
        )
        out = np.minimum(out, wall)
    return out


#: Nearest neighbours a circle is given before its gap is computed against every circle
#: (in blocks of bounded memory): only maps with many circles piled on one spot get there.
_MOST_NEIGHBOURS = 256
#: Pairwise distances held at once by that fallback (16 MB of floats).
_BLOCK_PAIRS = 2_000_000


def _nearest_circle_gaps(c: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Each circle's smallest gap ``|c_i - c_j| - r_i - r_j`` to any other, exactly.

    A KD-tree of the centres gives each circle its nearest others, 8 at first and
    twice as many while a farther one could still be closer by its radius (the
    pairwise matrix took 3 GB at 20 000 obstacles): once the k-th nearest centre is
    ``d_k`` away and ``R`` is the largest radius, no unseen circle's gap can be below
    ``d_k - r_i - R``. A circle still open after ``_MOST_NEIGHBOURS`` is compared with
    all, a block of rows at a time. Every gap uses the pairwise matrix's arithmetic,
    so the result is the same to the bit.
    """
    n = len(c)
    out = np.full(n, np.inf)
    if n < 2:
        return out
    tree = cKDTree(c)
    largest = float(r.max())
    rows = np.arange(n)
    k = 8
    while rows.size and k < n and k <= _MOST_NEIGHBOURS:
        dist, idx = tree.query(c[rows], k=k)
        out[rows] = _gaps(c, r, rows, idx).min(axis=1)
        # Unseen circles are at least dist[:, -1] away: the tree's distances may differ
        # from hypot's by an ulp or two, hence the hair of slack; rounding is monotonic,
        # so no unseen gap is below this floor.
        floor = dist[:, -1] * (1.0 - 1e-12) - r[rows] - largest
        rows = rows[floor < out[rows]]
        k *= 2
    block = max(1, _BLOCK_PAIRS // n)
    for start in range(0, rows.size, block):
        part = rows[start : start + block]
        out[part] = _gaps(c, r, part, np.broadcast_to(np.arange(n), (part.size, n))).min(axis=1)
    return out


def _gaps(c: np.ndarray, r: np.ndarray, rows: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Gaps of circles ``rows`` to circles ``idx`` (one row each); ``inf`` to themselves."""
    d = np.hypot(c[rows, None, 0] - c[idx, 0], c[rows, None, 1] - c[idx, 1])
    return np.where(idx != rows[:, None], d - r[rows, None] - r[idx], np.inf)


def expand_obstacles(
    obstacles: Iterable[Obstacle],
    a: float,
    lmin: float,
    bounds: Iterable[float] | None = None,
) -> tuple[tuple[Obstacle, ...], np.ndarray]:
    """Adaptive obstacle expansion (paper Sec. 3.1.4): grow by ``a`` where ``L2 > L_min``.

    Parameters
    ----------
    obstacles : iterable of Obstacle
        The map's rectangles.
    a : float
        Growth of length and width in metres.
    lmin : float
        Smallest allowed passing distance ``L_min``.
    bounds : iterable of float, optional
        Map bounds; the boundary then counts as an obstacle (see :func:`envelope_gaps`).

    Returns
    -------
    obstacles : tuple of Obstacle
        The rectangles, grown or as they were, in the same order.
    grown : numpy.ndarray
        Boolean flag per rectangle.

    Examples
    --------
    >>> obs = [Obstacle((0.0, 0.0), (6.0, 8.0)), Obstacle((20.0, 0.0), (6.0, 8.0))]
    >>> new, grown = expand_obstacles(obs, 1.0, 3.4)
    >>> new[0].size, grown.tolist()
    ((7.0, 9.0), [True, True])
    """
    obs = list(obstacles)
    gaps = envelope_gaps(obs, bounds)
    grown = gaps > lmin
    out = tuple(o.grown(a) if g else o for o, g in zip(obs, grown.tolist(), strict=True))
    return out, grown


def expanded_checker(
    checker: CollisionChecker, a: float, lmin: float
) -> tuple[CollisionChecker | None, int]:
    """The checker of the expanded obstacles, built once per map checker and parameters.

    Returns ``(None, 0)`` when no obstacle grows (the original checker serves).
    Kept on the map checker's grid cache (:meth:`rrtdrive.collision.GridCache.derived`),
    so building it counts as per-map set-up.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker (its obstacles, bounds, car and settings).
    a : float
        Growth of length and width in metres.
    lmin : float
        Smallest allowed passing distance ``L_min`` (:func:`expand_obstacles`).

    Returns
    -------
    checker : CollisionChecker or None
        The expanded map's checker, or ``None`` when no obstacle grows.
    grown : int
        How many obstacles grew.
    """

    def build() -> tuple[CollisionChecker | None, int]:
        new, grown = expand_obstacles(checker.obstacles, a, lmin, checker.bounds)
        count = int(grown.sum())
        if count == 0 or a == 0.0:
            return None, 0
        return CollisionChecker(checker.bounds, new, checker.vehicle, checker.config), count

    return checker.grid.derived(("expanded_checker", float(a), float(lmin)), build)
