"""The collision checker of one map and car: fast conservative tests and an exact body test.

It implements :class:`rrtdrive.checking.Checker`; the grid-derived data it
serves (connectivity labels, sampler cells, passage cells, the obstacle union)
lives on its :class:`~rrtdrive.collision.grid.GridCache`.
"""

from __future__ import annotations

import array
import dataclasses
import math
import time
import warnings
from collections.abc import Sequence

import numpy as np
import shapely

from rrtdrive.collision.config import CheckerConfig
from rrtdrive.collision.distance import distance_field
from rrtdrive.collision.exact import RectangleTest
from rrtdrive.collision.grid import GridCache, grid_origin, grid_resolution, grid_shape, rasterise
from rrtdrive.geometry import densify
from rrtdrive.maps import Map, Obstacle
from rrtdrive.types import InputWarning, VehicleParams
from rrtdrive.vehicle import cover_discs, footprint_corners

__all__ = ["CollisionChecker"]



class CollisionChecker:
    """Collision queries against one map's obstacles and bounds for one car.

    Implements :class:`rrtdrive.checking.Checker`. The grid-derived data lives on
    :attr:`grid` (a :class:`~rrtdrive.collision.grid.GridCache`), built lazily and
    timed in :attr:`setup_time_s`.

    Parameters
    ----------
    bounds : sequence of float
        ``(xmin, ymin, xmax, ymax)``.
    obstacles : sequence of Obstacle
        Oriented rectangles.
    vehicle : VehicleParams
        The car.
    config : CheckerConfig, optional
        Grid resolution and margins. A map whose grid would exceed
        ``config.max_grid_cells`` gets a coarser grid (a warning is logged;
        :attr:`resolution` is the cell size used, :attr:`requested_resolution`
        the one asked for, and :attr:`config` carries the one used).

    Raises
    ------
    InputError
        Naming ``bounds`` when the map is too big for any allowed grid
        (see :func:`~rrtdrive.collision.grid.grid_resolution`).

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> m = builtin_map("overtake")
    >>> checker = CollisionChecker.for_map(m)
    >>> checker.edge_free((5.0, 44.0), (30.0, 44.0))
    True
    >>> checker.edge_free((30.0, 44.0), (60.0, 44.0))
    False
    """

    def __init__(
        self,
        bounds: Sequence[float],
        obstacles: Sequence[Obstacle],
        vehicle: VehicleParams,
        config: CheckerConfig | None = None,
    ) -> None:
        self.bounds = tuple(float(b) for b in bounds)
        self.obstacles = tuple(obstacles)
        self.vehicle = vehicle
        config = config or CheckerConfig()
        self.requested_resolution = config.resolution
        t_setup = time.perf_counter()
        # Before anything is allocated: refuse, or coarsen, a grid too big for memory.
        h = grid_resolution(self.bounds, config)
        if h != config.resolution:
            width, height = self.bounds[2] - self.bounds[0], self.bounds[3] - self.bounds[1]
            # An InputWarning, as the map's others: the CLI prints it as one "warning:" line.
            warnings.warn(
                f"bounds: a {width:g} x {height:g} m map at {config.resolution:g} m would "
                f"exceed checker.max_grid_cells = {config.max_grid_cells}; using {h:g} m "
                f"cells (grid error {h * math.sqrt(2.0):.3f} m)", InputWarning, stacklevel=2,
            )
            config = dataclasses.replace(config, resolution=h)
        self.config = config
        self._origin = grid_origin(self.bounds, h, self.config.pad)
        nx, ny = grid_shape(self.bounds, h, self.config.pad)
        self._shape = (nx, ny)
        self._inv_h = 1.0 / h
        self._ox, self._oy = float(self._origin[0]), float(self._origin[1])
        occupied = rasterise(self.bounds, self.obstacles, self._origin, h, nx, ny)
        # Distance from each cell centre to the nearest occupied cell centre (scaled
        # and shifted in place: big grids hold one float field, not three).
        field = distance_field(~occupied)
        del occupied
        field *= h
        # The point-to-centre error (h/sqrt2) plus the rasterisation error (h/sqrt2).
        self.grid_error = h * math.sqrt(2.0) + 1e-9
        field -= self.grid_error
        self._clearance = np.ascontiguousarray(field, dtype=np.float64)
        # A flat array of C doubles for the scalar lookups: compact in memory, so
        # the walks along edges miss the cache far less than nested lists would.
        self._clearance_cells = array.array("d")
        self._clearance_cells.frombytes(memoryview(self._clearance).cast("B"))
        self._clearance_flat = self._clearance.ravel()
        self.edge_radius = vehicle.width / 2.0 + self.config.margin
        self.grid = GridCache(
            self._clearance, self._origin, h, self.grid_error, vehicle, self.bounds,
            self.obstacles, self.edge_radius, time.perf_counter() - t_setup,
        )
        # The exact tests need the union at once: built (and timed) by the cache.
        self._union = self.grid.obstacle_union
        self._inside = shapely.box(*self.bounds)
        shapely.prepare(self._inside)
        self._cap_inset = math.sqrt(self.edge_radius**2 - (vehicle.width / 2.0) ** 2)
        self._cap_back = vehicle.rear_overhang - self._cap_inset
        self._cap_front = vehicle.front_extent - self._cap_inset
        # segment_clear's constants, once: the trace step and the box a cell inside the grid.
        self._min_step = self.config.min_trace_step
        self._inner = (self._ox + h, self._oy + h, self._ox + (nx - 1) * h, self._oy + (ny - 1) * h)
        self._rectangles = RectangleTest(self.bounds, self._union, vehicle)
        self._disc_offsets, disc_radius = cover_discs(vehicle, 3)
        self._disc_offsets_list = [float(o) for o in self._disc_offsets]
        self.disc_radius = disc_radius + self.config.margin
        # The exact test's screens need no margin (the field is a lower bound already):
        # three discs first, then six smaller ones for the poses still unsure.
        self._screens = tuple(
            (np.asarray(offsets, dtype=float), float(radius))
            for offsets, radius in (cover_discs(vehicle, 3), cover_discs(vehicle, 6))
        )

    @classmethod
    def for_map(
        cls, m: Map, vehicle: VehicleParams | None = None, config: CheckerConfig | None = None
    ) -> CollisionChecker:
        """The checker for map ``m`` (its obstacles and bounds)."""
        return cls(m.bounds, m.obstacles, vehicle or m.vehicle, config)

    # ------------------------------------------------------------------ grid

    @property
    def clearance_grid(self) -> np.ndarray:
        """Lower bound of the distance to the nearest obstacle at each cell centre, ``(nx, ny)``."""
        return self._clearance

    @property
    def grid_origin(self) -> np.ndarray:
        """World position of the grid's lower-left corner."""
        return self._origin.copy()

    @property
    def resolution(self) -> float:
        """Grid cell size in metres used (coarser than requested for a very big map)."""
        return self.config.resolution

    def clearance(self, x: float, y: float) -> float:
        """A lower bound of the distance from ``(x, y)`` to the nearest obstacle or the outside.

        Negative or ``-inf`` means possibly inside an obstacle. Scalar and fast
        (about a microsecond); use :meth:`clearances` for many points.
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
        """Vectorised :meth:`clearance` for points of shape ``(N, 2)``."""
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

    # ------------------------------------------------------------------ fast tests

    def segment_clear(self, a: Sequence[float], b: Sequence[float], radius: float) -> bool:
        """True when the capsule of ``radius`` around segment a-b is provably clear.

        Sphere tracing on the clearance field: where the field says ``d`` of room
        beyond ``radius``, the next ``d`` metres of the segment are clear too (the
        distance is 1-Lipschitz), so the walk takes steps of ``d``. The far end is
        looked at first, which rejects most colliding edges with one lookup.
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

    def edge_free(self, a: Sequence[float] | np.ndarray, b: Sequence[float] | np.ndarray) -> bool:
        """Fast conservative test of a tree edge a->b driven with heading along the edge.

        The swept body lies inside the capsule of radius ``r = W/2 + margin``
        around the centre line from ``a - (rear_overhang - e) * u`` to
        ``b + (front_extent - e) * u``, where ``e = sqrt(r^2 - (W/2)^2)`` pulls
        the round caps in just so far that they still contain the body's corners
        (without it the caps would reach ``r`` past each bumper).
        A degenerate edge (a == b) is checked as the body at ``a`` with any heading,
        i.e. the disc that contains every orientation.
        """
        ax, ay = float(a[0]), float(a[1])
        dx, dy = float(b[0]) - ax, float(b[1]) - ay
        length = math.hypot(dx, dy)
        if length < 1e-9:
            reach = math.hypot(self.vehicle.front_extent, self.vehicle.width / 2)
            return self.clearance(ax, ay) - reach - self.config.margin >= 0.0
        ux, uy = dx / length, dy / length
        back, front = self._cap_back, self._cap_front
        return self.segment_clear(
            (ax - ux * back, ay - uy * back),
            (ax + dx + ux * front, ay + dy + uy * front),
            self.edge_radius,
        )

    @property
    def edge_capsule(self) -> tuple[float, float, float]:
        """:meth:`edge_free`'s capsule: its reach behind and ahead of an edge, its radius."""
        return self._cap_back, self._cap_front, self.edge_radius

    def point_free(self, x: float, y: float) -> bool:
        """Fast test: could a car with its rear axle at ``(x, y)`` fit with *some* heading.

        This is a cheap necessary condition for sampling (the inscribed disc of
        the body around the rear axle must be clear); it is not a body test.
        """
        return self.clearance(x, y) >= min(self.vehicle.rear_overhang, self.vehicle.width / 2)

    def pose_free_fast(self, x: float, y: float, yaw: float, clearance: float = 0.0) -> bool:
        """Scalar :meth:`poses_free_fast` for one pose (no numpy overhead, about 2 µs)."""
        c, s = math.cos(yaw), math.sin(yaw)
        room, need = self.clearance, self.disc_radius + clearance
        for off in self._disc_offsets_list:
            if room(x + c * off, y + s * off) < need:
                return False
        return True

    def poses_free_fast(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        """Conservative vectorised body test: three covering discs per pose.

        Parameters
        ----------
        poses : numpy.ndarray
            ``(N, 3)`` rear-axle poses.
        clearance : float
            Extra distance the body must keep from obstacles and bounds.

        Returns
        -------
        numpy.ndarray
            Boolean ``(N,)``; True means provably clear, False means maybe not.
        """
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
        off = self._disc_offsets
        centres = np.stack(
            [p[:, None, 0] + c[:, None] * off[None, :], p[:, None, 1] + s[:, None] * off[None, :]],
            axis=-1,
        ).reshape(-1, 2)
        ok = self.clearances(centres) >= self.disc_radius + clearance
        return ok.reshape(len(p), len(off)).all(axis=1)

    # ------------------------------------------------------------------ exact test

    def poses_free(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        """Exact body-rectangle test at each pose (agrees with shapely).

        Poses cleared by the conservative disc screens (three, then six discs, on
        the clearance field) are free; the rest are decided by shapely polygon
        tests against the obstacles and the bounds.

        Parameters
        ----------
        poses : numpy.ndarray
            ``(N, 3)`` rear-axle poses.
        clearance : float
            Distance the body must keep from every obstacle and from the bounds
            (0: it may not touch them).

        Returns
        -------
        numpy.ndarray
            Boolean ``(N,)``: True where the body rectangle keeps ``clearance``
            from every obstacle and lies inside the bounds shrunk by it.
        """
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        free = np.zeros(len(p), dtype=bool)
        unsure = np.arange(len(p))
        for offsets, radius in self._screens:
            if len(unsure) == 0:
                return free
            sure = self._discs_clear(p.take(unsure, axis=0), offsets, radius + clearance)
            free[unsure[sure]] = True
            unsure = unsure[~sure]
        if len(unsure):
            free[unsure] = self._exact(p.take(unsure, axis=0), clearance)
        return free

    def poses_free_unscreened(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        """:meth:`poses_free` for poses that the three-disc screen does not clear.

        The same answer as :meth:`poses_free` for such poses (for them its first
        screen is False by assumption, so it is skipped): the six-disc screen, then
        the exact shapely test. A caller that ran the three-disc screen with the
        same ``clearance`` (e.g. the Hybrid A* body test) saves repeating it.
        """
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        free = np.zeros(len(p), dtype=bool)
        if not len(p):
            return free
        offsets, radius = self._screens[1]
        sure = self._discs_clear(p, offsets, radius + clearance)
        free[sure] = True
        unsure = np.flatnonzero(~sure)
        if len(unsure):
            free[unsure] = self._exact(p[unsure], clearance)
        return free

    def _discs_clear(self, p: np.ndarray, offsets: np.ndarray, need: float) -> np.ndarray:
        """True where every disc centre on the body axis at ``offsets`` has clearance ``need``.

        Conservative: with discs of radius ``r`` covering the body and ``need =
        r + clearance``, True proves the body keeps ``clearance`` (the field is a
        lower bound of the true distance).
        """
        return (self.axis_clearances(p.T, offsets) >= need).all(axis=0)

    def pose_free(self, pose: Sequence[float], clearance: float = 0.0) -> bool:
        """Exact body test for one pose (scalar disc screen first, shapely when unsure).

        With ``clearance`` > 0 the body must keep that distance from obstacles and
        bounds, as in :meth:`poses_free` (the same answer, without numpy's per-call
        overhead: an outside planner's validity checker calls it once per state).
        """
        x, y, yaw = float(pose[0]), float(pose[1]), float(pose[2])
        return self.pose_free_fast(x, y, yaw, clearance) or bool(
            self._exact(np.array([[x, y, yaw]]), clearance)[0]
        )

    def body_clearance(self, pose: Sequence[float]) -> float:
        """Exact distance from the body at ``pose`` to the nearest obstacle or the bounds.

        Zero when the body touches or overlaps an obstacle or leaves the bounds.
        """
        rect = shapely.Polygon(footprint_corners(np.asarray(pose, dtype=float)[:3], self.vehicle))
        if not self._inside.contains(rect):
            return 0.0
        to_bounds = self._inside.exterior.distance(rect)
        if self._union.is_empty:
            return float(to_bounds)
        return float(min(to_bounds, self._union.distance(rect)))

    def _corners(self, poses: np.ndarray) -> np.ndarray:
        """:func:`~rrtdrive.vehicle.footprint_corners` of poses ``(N, 3)``, the same floats."""
        return self._rectangles.corners(poses)

    def rectangles_free(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        """The exact test alone, no screen: each body rectangle ``clearance`` clear.

        The same answer as :meth:`poses_free` (whose screens only save this work);
        for a handful of poses that its screens would not clear anyway it is the
        cheaper call.
        """
        return self._exact(poses, clearance)

    def _exact(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        return self._rectangles.free(poses, clearance)

    def path_free(
        self, samples: np.ndarray, spacing: float = 0.1, clearance: float = 0.0
    ) -> tuple[bool, np.ndarray]:
        """Exact test of a sampled path, densified to poses at most ``spacing`` apart.

        Parameters
        ----------
        samples : numpy.ndarray
            ``(N, >=3)`` rows ``x, y, yaw, ...``.
        spacing : float
            Largest distance between tested poses.
        clearance : float
            Distance the body must keep from obstacles and bounds (see :meth:`poses_free`).

        Returns
        -------
        ok : bool
            True when every tested pose is free.
        bad : numpy.ndarray
            Indices into ``samples`` of segments (i -> i+1) that contain a colliding pose.
        """
        s = np.asarray(samples, dtype=float)[:, :3]
        if len(s) == 0:
            return False, np.zeros(0, dtype=np.int64)
        if len(s) == 1:
            ok = bool(self.poses_free(s, clearance)[0])
            return ok, np.zeros(0 if ok else 1, dtype=np.int64)
        dense = densify(s, spacing, angle_column=2)
        if dense.pieces.max() == 1:
            # Dense enough already: the poses themselves (what the interpolation gives).
            free = self.poses_free(s, clearance)
            owner = np.minimum(np.arange(len(s)), len(dense.pieces) - 1)
            return bool(free.all()), np.unique(owner[~free])
        free = self.poses_free(dense.points, clearance)
        if free.all():  # nothing to list (what np.unique of no segment gives)
            return True, np.zeros(0, dtype=np.int64)
        return False, np.unique(dense.segment[~free])

    # ------------------------------------------------------------------ connectivity

    def reachable_components(self) -> tuple[np.ndarray, float]:
        """Label the cells the rear axle could ever occupy, for an unreachability proof.

        A collision-free rear axle has true clearance at least ``r`` = the
        radius of the largest disc about the rear axle inside the body
        (``min(rear_overhang, width/2)``). A cell is kept when an *upper* bound of
        the true clearance anywhere in it reaches ``r``; any continuous motion of
        the rear axle then passes only through kept cells, 8-connected. Start and
        goal in different components therefore proves that no path exists.

        Returns
        -------
        labels : numpy.ndarray
            Component label per cell (0 = not kept).
        slack : float
            Upper-bound slack used.
        """
        return self.grid.reachable_components()

    @property
    def component_labels(self) -> np.ndarray:
        """The labels of :meth:`reachable_components`, computed once per checker."""
        return self.grid.component_labels

    def provably_disconnected(
        self, a: Sequence[float] | np.ndarray, b: Sequence[float] | np.ndarray
    ) -> bool:
        """True when no collision-free motion can take the rear axle from ``a`` to ``b``.

        Conservative in the safe direction: True is a proof (by
        :meth:`reachable_components`); False proves nothing.
        """
        la = self.grid.label_at(a)
        lb = self.grid.label_at(b)
        return la == 0 or lb == 0 or la != lb

    # ------------------------------------------------------------------ cached grid data

    def free_cells(self, start: Sequence[float]) -> np.ndarray:
        """Flat indices of the cells where the rear axle can stand, connected to ``start``.

        See :meth:`rrtdrive.collision.grid.GridCache.free_cells` (cached per component).
        """
        return self.grid.free_cells(start)

    def passage_cells(self, start: Sequence[float], width: float = 0.6) -> np.ndarray:
        """``(K, 2)`` centres of narrow-passage cells reachable from ``start``.

        See :meth:`rrtdrive.collision.grid.GridCache.passage_cells` (cached).
        """
        return self.grid.passage_cells(start, width)

    @property
    def obstacle_union(self) -> shapely.Geometry:
        """The prepared shapely union of the obstacles (empty geometry when there are none)."""
        return self._union

    @property
    def setup_time_s(self) -> float:
        """Seconds spent building grid data so far: the field at construction plus lazy builds."""
        return self.grid.setup_time_s
