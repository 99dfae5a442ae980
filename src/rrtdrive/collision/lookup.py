"""Look-ups in a clearance field on a regular grid: points, poses' axis points, capsules.

:class:`ClearanceLookup` holds the field and answers the scalar and vectorised
queries the planners call millions of times; :class:`~rrtdrive.collision.CollisionChecker`
builds the field from a map and adds the body tests on top.
"""

from __future__ import annotations

import array
import math
from collections.abc import Sequence

import numpy as np

__all__ = ["ClearanceLookup"]


class ClearanceLookup:
    """Queries of a clearance field: a lower bound of the distance to the nearest obstacle.

    Parameters
    ----------
    field : numpy.ndarray
        ``(nx, ny)`` lower bounds at the cell centres, in metres (kept, not copied,
        when C-contiguous float64).
    origin : numpy.ndarray
        World position of the grid's lower-left corner ``(x, y)``.
    resolution : float
        Cell size in metres.
    min_trace_step : float
        The smallest step :meth:`segment_clear` takes: a capsule whose room falls
        below it is not proven clear.
    """

    def __init__(
        self, field: np.ndarray, origin: np.ndarray, resolution: float, min_trace_step: float
    ) -> None:
        h = float(resolution)
        self._clearance = np.ascontiguousarray(field, dtype=np.float64)
        # Read-only: a caller writing into clearance_grid made planners pass through walls.
        self._clearance.flags.writeable = False
        self._origin = np.array(origin, dtype=float)  # its own, read-only as the field
        self._origin.flags.writeable = False
        nx, ny = self._clearance.shape
        self._shape = (nx, ny)
        self._inv_h = 1.0 / h
        self._ox, self._oy = float(self._origin[0]), float(self._origin[1])
        # A flat array of C doubles for the scalar lookups: compact in memory, so
        # the walks along edges miss the cache far less than nested lists would.
        self._clearance_cells = array.array("d")
        self._clearance_cells.frombytes(memoryview(self._clearance).cast("B"))
        self._clearance_flat = self._clearance.ravel()
        # segment_clear's constants, once: the trace step and the box a cell inside the grid.
        self._min_step = float(min_trace_step)
        self._inner = (self._ox + h, self._oy + h, self._ox + (nx - 1) * h, self._oy + (ny - 1) * h)

    def clearance(self, x: float, y: float) -> float:
        """A lower bound of the distance from ``(x, y)`` to the nearest obstacle or the outside.

        Negative or ``-inf`` means possibly inside an obstacle. Scalar and fast
        (about a microsecond); use :meth:`clearances` for many points.

        Parameters
        ----------
        x, y : float
            A point in map coordinates (m).

        Returns
        -------
        float
            The lower bound in metres; ``-inf`` outside the grid or for a
            coordinate that is not finite.
        """
        gx = (x - self._ox) * self._inv_h
        gy = (y - self._oy) * self._inv_h
        nx, ny = self._shape
        # Decided on the floats (for g >= 0, int(g) < n exactly when g < n), so an
        # infinite or NaN coordinate is outside too instead of failing int().
        if not (0.0 <= gx < nx and 0.0 <= gy < ny):
            return -math.inf
        return self._clearance_cells[int(gx) * ny + int(gy)]

    def clearances(self, points: np.ndarray) -> np.ndarray:
        """Vectorised :meth:`clearance`: the same value at each point.

        Parameters
        ----------
        points : numpy.ndarray
            Points, reshaped to ``(N, 2)``.

        Returns
        -------
        numpy.ndarray
            ``(N,)`` lower bounds in metres (``-inf`` outside the grid).
        """
        p = np.asarray(points, dtype=float).reshape(-1, 2)
        g = (p - self._origin) * self._inv_h
        # Truncation equals floor where g >= 0, the only cells looked up.
        with np.errstate(invalid="ignore"):
            idx = g.astype(np.int64)
        # On the floats, as in :meth:`clearance`: beyond 2**63 cells the cast wraps round.
        ok = (
            (g[:, 0] >= 0.0)
            & (g[:, 1] >= 0.0)
            & (g[:, 0] < self._shape[0])
            & (g[:, 1] < self._shape[1])
        )
        flat = idx[:, 0] * self._shape[1] + idx[:, 1]
        if ok.all():
            return self._clearance_flat[flat]
        out = np.full(len(p), -np.inf)
        out[ok] = self._clearance_flat[flat[ok]]
        return out

    def clearances_xy(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """:meth:`clearances` for coordinates as two arrays of one shape (the same values).

        The look-up of the hot loops: when every point lies inside the grid (the
        usual case) it takes a few array operations, else it is :meth:`clearances`.

        Parameters
        ----------
        x, y : numpy.ndarray
            Coordinates, arrays of one shape.

        Returns
        -------
        numpy.ndarray
            Lower bounds in metres, in the shape of ``x``.
        """
        gx = (x - self._ox) * self._inv_h
        gy = (y - self._oy) * self._inv_h
        nx, ny = self._shape
        # For g >= 0, int(g) < n exactly when g < n: the float bounds decide alone.
        lo, hi = np.minimum.reduce, np.maximum.reduce  # the bare ufuncs: no method overhead
        if (
            gx.size
            and lo(gx, axis=None) >= 0.0
            and lo(gy, axis=None) >= 0.0
            and hi(gx, axis=None) < nx
            and hi(gy, axis=None) < ny
        ):
            return self._clearance_flat[gx.astype(np.int64) * ny + gy.astype(np.int64)]
        pts = np.stack([np.asarray(x, dtype=float), np.asarray(y, dtype=float)], axis=-1)
        return self.clearances(pts.reshape(-1, 2)).reshape(np.shape(x))

    def axis_clearances(self, rows: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        """:meth:`clearances` at points on the heading axis of poses, ``(K, N)``.

        ``rows`` ``(3, N)`` are the poses' x, y and yaw; point ``k`` of a pose is
        ``(cos(yaw) offsets[k] + x, sin(yaw) offsets[k] + y)``, evaluated in that
        order (the points of the disc screens: the same floats, the same values).
        The screens' look-up: all points in a dozen array operations.

        Parameters
        ----------
        rows : numpy.ndarray
            ``(3, N)``: the poses' x, y and yaw as rows.
        offsets : numpy.ndarray
            ``(K,)`` distances along the heading from each pose (m).

        Returns
        -------
        numpy.ndarray
            ``(K, N)`` lower bounds in metres.
        """
        n = rows.shape[1]
        if not n:
            return np.zeros((len(offsets), 0))
        # Laid out (x or y, offset, pose): every operation runs over contiguous rows.
        trig = np.empty((2, 1, n))
        np.cos(rows[2], out=trig[0, 0])
        np.sin(rows[2], out=trig[1, 0])
        world = trig * offsets[:, None]
        world += rows[:2, None, :]
        g = world - self._origin[:, None, None]
        g *= self._inv_h
        nx, ny = self._shape
        # For g >= 0, int(g) < n exactly when g < n: the float bounds decide alone.
        hi = np.maximum.reduce(g, axis=(1, 2)).tolist()
        if np.minimum.reduce(g, axis=None) >= 0.0 and hi[0] < nx and hi[1] < ny:
            idx = g.astype(np.int64)
            flat = idx[0] * ny
            flat += idx[1]
            return self._clearance_flat.take(flat)
        # Some point outside the grid (or not finite): clearances() reads those as -inf.
        points = np.stack([world[0].ravel(), world[1].ravel()], axis=1)
        return self.clearances(points).reshape(len(offsets), n)

    def segment_clear(self, a: Sequence[float], b: Sequence[float], radius: float) -> bool:
        """True when the capsule of ``radius`` around segment a-b is provably clear.

        Sphere tracing on the clearance field: where the field says ``d`` of room
        beyond ``radius``, the next ``d`` metres of the segment are clear too (the
        distance is 1-Lipschitz), so the walk takes steps of ``d``. The far end is
        looked at first, which rejects most colliding edges with one lookup.

        Parameters
        ----------
        a, b : sequence of float
            The segment's ends ``(x, y)``.
        radius : float
            The capsule's radius (m).

        Returns
        -------
        bool
            True is a proof that the capsule is clear; False proves nothing
            (the field is a lower bound).
        """
        ax, ay = float(a[0]), float(a[1])
        dx, dy = float(b[0]) - ax, float(b[1]) - ay
        length = math.hypot(dx, dy)
        if length < 1e-12:
            return self.clearance(ax, ay) - radius >= 0.0
        min_step = self._min_step
        ux, uy = dx / length, dy / length
        # clearance() inlined (the same arithmetic): this loop is the planners' hot spot.
        ox, oy, inv_h = self._ox, self._oy, self._inv_h
        nx, ny = self._shape
        grid = self._clearance_cells
        # The far end first (the very point the walk ends on, so the answer is the
        # same): most colliding tree extensions end inside an obstacle.
        x, y = ax + ux * length, ay + uy * length
        if x < ox or y < oy:
            return False
        i = int((x - ox) * inv_h)
        j = int((y - oy) * inv_h)
        if i >= nx or j >= ny or grid[i * ny + j] - radius < min_step:
            return False
        t = 0.0
        # Both ends at least a cell inside the grid: so is every point between
        # (rounding moves them by far less), and the walk needs no bounds checks.
        lo_x, lo_y, hi_x, hi_y = self._inner
        if lo_x <= ax <= hi_x and lo_x <= x <= hi_x and lo_y <= ay <= hi_y and lo_y <= y <= hi_y:
            while True:
                room = (
                    grid[int((ax + ux * t - ox) * inv_h) * ny + int((ay + uy * t - oy) * inv_h)]
                    - radius
                )
                if room < min_step:
                    return False
                if t >= length:
                    return True
                t += room
                if t > length:
                    t = length
        while True:
            x, y = ax + ux * t, ay + uy * t
            if x < ox or y < oy:
                return False
            i = int((x - ox) * inv_h)
            j = int((y - oy) * inv_h)
            if i >= nx or j >= ny:
                return False
            room = grid[i * ny + j] - radius
            if room < min_step:
                return False
            if t >= length:
                return True
            t = min(t + room, length)
