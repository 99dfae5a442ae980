"""An exact proof that the car cannot get from one place to another: every way is too narrow.

The car's body always holds the disc of radius ``r = min(rear_overhang, width / 2)``
about its rear axle, so the rear axle of any collision-free pose lies at least ``r``
from every obstacle and from the map's edge. A motion from the start to the goal
moves the rear axle continuously through that region; when the start's and the
goal's rear axles lie in different connected parts of it, no motion joins them.

The clearance grid proves the same (:meth:`~rrtdrive.collision.grid.GridCache.reachable_components`)
up to its cells' error, so it proves gaps only up to about 1.45-1.6 m for a 1.8 m wide
car.
Here the region is shapely's: the obstacles grown by ``r`` with polygonal buffers,
whose vertices lie on the true circles, so they are a little smaller than the true grown
obstacles and the region a little larger. A larger region split in two is a true region
split in two: a proof never rejects a solvable query (a gap of 1.7 m, narrower than the
car, ran every planner's whole budget; an audit).
"""

from __future__ import annotations

from collections.abc import Sequence

import shapely

__all__ = ["free_parts", "parts_disconnected"]

#: Segments per quarter circle of the grown obstacles' rounded corners.
_QUAD_SEGS = 16


def free_parts(
    bounds: Sequence[float], obstacles: Sequence[Sequence[Sequence[float]]], radius: float
) -> tuple[shapely.Polygon, ...]:
    """The connected parts of the region a disc of ``radius`` can be centred in.

    Parameters
    ----------
    bounds : sequence of float
        ``(xmin, ymin, xmax, ymax)`` of the map, metres.
    obstacles : sequence
        Each obstacle's corners, ``(x, y)`` rows.
    radius : float
        The disc's radius, metres.

    Returns
    -------
    tuple of shapely.Polygon
        The parts (a little larger than the true ones; none when nothing fits).

    Examples
    --------
    >>> wall = [[(9.0, 0.0), (11.0, 0.0), (11.0, 4.0), (9.0, 4.0)],
    ...         [(9.0, 5.7), (11.0, 5.7), (11.0, 10.0), (9.0, 10.0)]]  # a 1.7 m gap
    >>> len(free_parts((0, 0, 20, 10), wall, 0.895))
    2
    >>> len(free_parts((0, 0, 20, 10), wall, 0.8))
    1
    """
    xmin, ymin, xmax, ymax = (float(v) for v in bounds)
    if xmax - xmin <= 2 * radius or ymax - ymin <= 2 * radius:
        return ()
    region = shapely.box(xmin + radius, ymin + radius, xmax - radius, ymax - radius)
    if len(obstacles):
        grown = shapely.buffer(
            shapely.polygons([list(map(tuple, c)) for c in obstacles]), radius,
            quad_segs=_QUAD_SEGS,
        )
        region = shapely.difference(region, shapely.union_all(grown))
    return tuple(p for p in shapely.get_parts(region) if not p.is_empty)


def parts_disconnected(
    parts: Sequence[shapely.Polygon], a: Sequence[float], b: Sequence[float]
) -> bool:
    """True when points ``a`` and ``b`` lie in different parts (a proof); False proves nothing.

    A point in no part, or on the border of one (rounding), proves nothing either.

    Parameters
    ----------
    parts : sequence of shapely.Polygon
        :func:`free_parts`.
    a, b : sequence of float
        Points ``(x, y, ...)``; further entries are ignored.

    Returns
    -------
    bool

    Examples
    --------
    >>> parts = (shapely.box(0, 0, 1, 1), shapely.box(2, 0, 3, 1))
    >>> parts_disconnected(parts, (0.5, 0.5), (2.5, 0.5))
    True
    >>> parts_disconnected(parts, (0.5, 0.5), (0.7, 0.2))
    False
    """
    pa, pb = shapely.Point(a[0], a[1]), shapely.Point(b[0], b[1])
    in_a = {k for k, p in enumerate(parts) if p.contains_properly(pa)}
    in_b = {k for k, p in enumerate(parts) if p.contains_properly(pb)}
    return bool(in_a) and bool(in_b) and not in_a & in_b
