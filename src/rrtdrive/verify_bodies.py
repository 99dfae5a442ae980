"""The body check of :func:`rrtdrive.verify.verify_path`.

The car's bodies along a path, the first one that collides, and the least clearance
of the rest. Shapely polygons built here, independent of the planner's collision checker.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from rrtdrive.maps import Map

__all__ = ["body_polygons", "body_corners", "least_clearance", "first_collision"]


def body_polygons(poses: np.ndarray, length: float, width: float, back: float) -> np.ndarray:
    """The car's body rectangles at ``poses`` (rows ``x, y, yaw``), as shapely polygons.

    One vectorised call (building them one by one took half of a bench run's time); the
    corners are the floats of the scalar formula (``math.cos``, the same operation order).
    """
    yaw = poses[:, 2].tolist()
    c = np.array([math.cos(a) for a in yaw]).reshape(-1, 1)
    s = np.array([math.sin(a) for a in yaw]).reshape(-1, 1)
    lx = np.array([-back, length - back, length - back, -back])
    ly = np.array([-width / 2, -width / 2, width / 2, width / 2])
    x = poses[:, :1] + c * lx - s * ly
    y = poses[:, 1:2] + s * lx + c * ly
    return shapely.polygons(np.stack([x, y], axis=-1))


def body_corners(bodies: np.ndarray) -> np.ndarray:
    """The four corners ``(n, 4, 2)`` of :func:`body_polygons`' rectangles."""
    return shapely.get_coordinates(shapely.get_exterior_ring(bodies)).reshape(len(bodies), 5, 2)[
        :, :4
    ]


def least_clearance(
    m: Map, shapes: np.ndarray, polygons: list[shapely.Geometry], corners: np.ndarray
) -> float:
    """The least distance between the bodies and the obstacles or the edge of the bounds.

    ``corners``: the bodies' corners ``(n, 4, 2)``; a body inside the box is nearest to
    its edge at a corner (both are convex).
    """
    xmin, ymin, xmax, ymax = m.bounds
    x, y = corners[..., 0], corners[..., 1]
    edge = float(np.min(np.minimum.reduce([x - xmin, xmax - x, y - ymin, ymax - y])))
    least = max(edge, 0.0)
    if polygons:
        tree = shapely.STRtree(polygons)
        _, distance = tree.query_nearest(shapes, return_distance=True, all_matches=False)
        # No pair at all when the distances overflow (an obstacle at 1e200 m: accepted by
        # plan, a traceback here; an audit): such an obstacle is as far as can be.
        if len(distance):
            least = min(least, float(np.min(distance)))
    return least


def first_collision(
    rows: np.ndarray, region: shapely.Geometry, shapes: np.ndarray,
    polygons: list[shapely.Geometry], poses: list[np.ndarray], row_on_map: np.ndarray,
) -> tuple[tuple[float, float, float] | None, str]:
    """The first pose whose body leaves ``region`` or overlaps an obstacle, and what it hits.

    ``shapes``: the bodies at ``poses``; ``polygons``: the obstacles, in map order.
    Bodies are drawn up to the first row off the map (``row_on_map`` false), which is
    the first collision when none of them collides.
    """
    off = None
    if not row_on_map.all():
        k = int(np.argmin(row_on_map))
        off = (float(rows[k, 0]), float(rows[k, 1]), float(rows[k, 2])), "the bounds"
    if not len(shapes):
        return off if off is not None else (None, "")
    # Touching the bounds is a collision, as touching an obstacle is (the walls stand there).
    shapely.prepare(region)
    outside = ~shapely.contains_properly(region, shapes)
    hit = np.zeros(len(shapes), dtype=bool)
    if polygons:
        walls = shapely.union_all(polygons)
        shapely.prepare(walls)  # one geometry against thousands of bodies
        hit = shapely.intersects(walls, shapes)
    bad = outside | hit
    if not bad.any():
        return off if off is not None else (None, "")
    k = int(np.argmax(bad))
    x, y, yaw = (float(c) for c in np.concatenate(poses)[k])
    if outside[k]:
        return (x, y, yaw), "the bounds"
    index = next(i for i, p in enumerate(polygons) if p.intersects(shapes[k]))
    return (x, y, yaw), f"obstacle {index}"
