"""The exact body test: the car's rectangle at each pose against the bounds and the obstacles.

:class:`RectangleTest` is what :class:`~rrtdrive.collision.CollisionChecker`'s
exact test runs once its disc screens cannot decide: the body rectangle must lie
strictly inside the bounds box shrunk by the clearance (compared exactly, corner by corner)
and keep the clearance from the prepared shapely union of the obstacles. It is
called thousands of times per search with a handful of poses, so its fixed cost
(the array calls around one shapely predicate) is what it is written for.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely

from rrtdrive.types import VehicleParams

__all__ = ["RectangleTest"]


def _ring_args() -> tuple[np.intc, ...]:
    """The extra arguments of ``shapely.lib.linearrings`` in this shapely.

    shapely >= 2.1 takes the NaN handling (``shapely.linearrings``'s default,
    'allow' = 0) as a second argument; 2.0 takes the coordinates alone.
    """
    probe = np.zeros((1, 4, 2))
    probe[0, 1:3, 0] = 1.0
    probe[0, 2:, 1] = 1.0
    try:
        shapely.lib.linearrings(probe, np.intc(0))
    except TypeError:
        return ()
    return (np.intc(0),)


#: Arguments after the coordinates for the ring ufunc (see :func:`_ring_args`).
_RING_ARGS = _ring_args()


class RectangleTest:
    """Exact test of body rectangles against a bounds box and an obstacle union.

    Parameters
    ----------
    bounds : sequence of float
        ``(xmin, ymin, xmax, ymax)``.
    union : shapely.Geometry
        The obstacles' union, prepared (may be empty).
    vehicle : VehicleParams
        The car (rear-axle reference: ``-rear_overhang <= u <= front_extent``,
        ``|v| <= width / 2``).

    Examples
    --------
    >>> from rrtdrive.types import VehicleParams
    >>> test = RectangleTest((0.0, 0.0, 20.0, 20.0), shapely.box(9.0, 0.0, 11.0, 20.0),
    ...                      VehicleParams())
    >>> test.free(np.array([[2.0, 10.0, 0.0], [8.0, 10.0, 0.0]]), 0.1).tolist()
    [True, False]
    """

    def __init__(
        self, bounds: Sequence[float], union: shapely.Geometry, vehicle: VehicleParams
    ) -> None:
        self.bounds = tuple(float(b) for b in bounds)
        self.union = union
        # Asked once: the property is a shapely call (microseconds) on every test.
        self._empty = bool(union.is_empty)
        back, front, half = -vehicle.rear_overhang, vehicle.front_extent, vehicle.width / 2.0
        self._lx = np.array([back, front, front, back], dtype=float)
        ly = np.array([-half, -half, half, half], dtype=float)
        # Rows [-ly, ly]: the factors of s and c in corners() (negation is exact).
        self._ly = np.stack([-ly, ly])
        #: Empty hole lists for up to this many polygons (grown on demand).
        self._holes = np.empty((64, 0), dtype=object)

    def corners(self, poses: np.ndarray) -> np.ndarray:
        """:func:`~rrtdrive.vehicle.footprint_corners` of poses ``(N, 3)``, the same floats.

        Built as ``(N, 2, 4)`` (the x row, the y row) and returned as its
        ``(N, 4, 2)`` view, in four array operations: ``x + c lx - s ly`` as
        ``(c lx + x) + s (-ly)`` and ``y + s lx + c ly`` as ``(s lx + y) + c ly``
        (commuted operands and a negated factor round alike: the same floats).
        """
        trig = np.empty((len(poses), 2, 1))  # c, s
        np.cos(poses[:, 2], out=trig[:, 0, 0])
        np.sin(poses[:, 2], out=trig[:, 1, 0])
        out = trig * self._lx
        out += poses[:, 0:2, None]
        out += trig[:, ::-1] * self._ly
        return out.swapaxes(1, 2)

    def polygons(self, corners: np.ndarray) -> np.ndarray:
        """``shapely.polygons(corners)`` for corners ``(N, 4, 2)``: the same geometries.

        The two ufuncs behind it, without its argument handling (a few
        microseconds a call, more than the polygons cost).
        """
        n = len(corners)
        if n > len(self._holes):
            self._holes = np.empty((n, 0), dtype=object)
        rings = shapely.lib.linearrings(corners, *_RING_ARGS)
        return shapely.lib.polygons(rings, self._holes[:n])

    def free(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        """Boolean ``(N,)``: True where the rectangle keeps ``clearance`` from everything.

        That is: strictly inside the bounds shrunk by ``clearance`` and farther than
        ``clearance`` from the union (touching neither when ``clearance`` is 0).
        """
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        if not len(p):
            return np.zeros(0, dtype=bool)
        corners = self.corners(p)
        # Inside the bounds box shrunk by the clearance: both are convex and the box
        # is axis-aligned, so that is all four corners inside, compared exactly; the
        # extremes over every corner decide a batch wholly inside in two reductions.
        xmin, ymin, xmax, ymax = self.bounds
        if clearance > 0.0:
            xmin, ymin, xmax, ymax = (
                xmin + clearance, ymin + clearance, xmax - clearance, ymax - clearance
            )
        lo = np.minimum.reduce(corners, axis=(0, 1)).tolist()
        hi = np.maximum.reduce(corners, axis=(0, 1)).tolist()
        # Strictly inside: a corner on the (shrunk) bounds touches them, as a body
        # touching an obstacle, or at exactly ``clearance`` from one, collides.
        if lo[0] > xmin and lo[1] > ymin and hi[0] < xmax and hi[1] < ymax:
            inside, test = None, corners
        else:
            x, y = corners[..., 0], corners[..., 1]
            inside = ((x > xmin) & (x < xmax) & (y > ymin) & (y < ymax)).all(axis=1)
            test = corners[inside]
            if not len(test):
                return inside
        if self._empty:
            return np.ones(len(p), dtype=bool) if inside is None else inside
        rects = self.polygons(test)
        if clearance > 0.0:
            hit = shapely.lib.dwithin(self.union, rects, clearance)
        else:
            hit = shapely.lib.intersects(self.union, rects)
        if inside is None:
            return ~hit
        inside[inside] = ~hit
        return inside
