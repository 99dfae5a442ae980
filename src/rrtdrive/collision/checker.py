"""The collision checker of one map and car: fast conservative tests and an exact body test.

It implements :class:`rrtdrive.checking.Checker`; the grid-derived data it
serves (connectivity labels, sampler cells, passage cells, the obstacle union)
lives on its :class:`~rrtdrive.collision.grid.GridCache`.
"""

from __future__ import annotations

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
from rrtdrive.collision.lock import QueryLock
from rrtdrive.collision.lookup import ClearanceLookup
from rrtdrive.collision.width_proof import free_parts, parts_disconnected
from rrtdrive.geometry import densify
from rrtdrive.maps import Map, Obstacle
from rrtdrive.types import InputWarning, VehicleParams
from rrtdrive.vehicle import axle_disc_radius, cover_discs, footprint_corners

__all__ = ["CollisionChecker"]


class CollisionChecker(ClearanceLookup):
    """Collision queries against one map's obstacles and bounds for one car.

    Implements :class:`rrtdrive.checking.Checker`. The clearance look-ups are
    :class:`~rrtdrive.collision.lookup.ClearanceLookup`'s. The grid-derived data lives on
    :attr:`grid` (a :class:`~rrtdrive.collision.grid.GridCache`), built lazily and
    timed in :attr:`setup_time_s`. Threads may share it: a planner holds :attr:`lock`
    for a whole query, and so must code calling its methods from several threads.

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
        #: Held by a planner for a whole query; threads sharing this checker take turns.
        self.lock = QueryLock()
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
        origin = grid_origin(self.bounds, h, self.config.pad)
        nx, ny = grid_shape(self.bounds, h, self.config.pad)
        occupied = rasterise(self.bounds, self.obstacles, origin, h, nx, ny)
        # Distance from each cell centre to the nearest occupied cell centre (scaled
        # and shifted in place: big grids hold one float field, not three).
        field = distance_field(~occupied)
        del occupied
        field *= h
        # The point-to-centre error (h/sqrt2) plus the rasterisation error (h/sqrt2).
        self.grid_error = h * math.sqrt(2.0) + 1e-9
        field -= self.grid_error
        super().__init__(field, origin, h, self.config.min_trace_step)
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
        """The checker for map ``m`` (its obstacles and bounds).

        Parameters
        ----------
        m : Map
            The map.
        vehicle : VehicleParams, optional
            The car; the map's own by default.
        config : CheckerConfig, optional
            Grid resolution and margins; ``CheckerConfig()`` by default.

        Returns
        -------
        CollisionChecker
        """
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

    # ------------------------------------------------------------------ fast tests

    def edge_free(self, a: Sequence[float] | np.ndarray, b: Sequence[float] | np.ndarray) -> bool:
        """Fast conservative test of a tree edge a->b driven with heading along the edge.

        The swept body lies inside the capsule of radius ``r = W/2 + margin``
        around the centre line from ``a - (rear_overhang - e) * u`` to
        ``b + (front_extent - e) * u``, where ``e = sqrt(r^2 - (W/2)^2)`` pulls
        the round caps in just so far that they still contain the body's corners
        (without it the caps would reach ``r`` past each bumper).
        A degenerate edge (a == b) is checked as the body at ``a`` with any heading,
        i.e. the disc that contains every orientation.

        Parameters
        ----------
        a, b : sequence of float
            The edge's ends, rear-axle positions ``(x, y)``.

        Returns
        -------
        bool
            True is a proof that the swept body keeps ``config.margin`` clear;
            False proves nothing.
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

        Parameters
        ----------
        x, y : float
            The rear axle's position.

        Returns
        -------
        bool
            False is a proof that no heading fits; True proves nothing.
        """
        return self.clearance(x, y) >= axle_disc_radius(self.vehicle)

    def pose_free_fast(self, x: float, y: float, yaw: float, clearance: float = 0.0) -> bool:
        """Scalar :meth:`poses_free_fast` for one pose (no numpy overhead, about 2 µs).

        Parameters
        ----------
        x, y, yaw : float
            The rear-axle pose.
        clearance : float
            Extra distance the body must keep from obstacles and bounds.

        Returns
        -------
        bool
            True means provably clear, False means maybe not.
        """
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

        Parameters
        ----------
        poses : numpy.ndarray
            ``(N, 3)`` rear-axle poses.
        clearance : float
            Distance the body must keep from every obstacle and from the bounds.

        Returns
        -------
        numpy.ndarray
            Boolean ``(N,)``, as :meth:`poses_free`.
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

        Parameters
        ----------
        pose : sequence of float
            The rear-axle pose ``(x, y, yaw, ...)``; further entries are ignored.
        clearance : float
            Distance the body must keep from every obstacle and from the bounds.

        Returns
        -------
        bool
            True when the body rectangle keeps ``clearance`` and lies inside the bounds.
        """
        x, y, yaw = float(pose[0]), float(pose[1]), float(pose[2])
        return self.pose_free_fast(x, y, yaw, clearance) or bool(
            self._exact(np.array([[x, y, yaw]]), clearance)[0]
        )

    def body_clearance(self, pose: Sequence[float]) -> float:
        """Exact distance from the body at ``pose`` to the nearest obstacle or the bounds.

        Zero when the body touches or overlaps an obstacle or leaves the bounds.

        Parameters
        ----------
        pose : sequence of float
            The rear-axle pose ``(x, y, yaw, ...)``.

        Returns
        -------
        float
            The distance in metres (shapely's, exact up to floating point).
        """
        rect = shapely.Polygon(footprint_corners(np.asarray(pose, dtype=float)[:3], self.vehicle))
        with self.lock:  # prepared geometry (see _exact)
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

        Parameters
        ----------
        poses : numpy.ndarray
            ``(N, 3)`` rear-axle poses.
        clearance : float
            Distance the body must keep from every obstacle and from the bounds.

        Returns
        -------
        numpy.ndarray
            Boolean ``(N,)``, as :meth:`poses_free`.
        """
        return self._exact(poses, clearance)

    def _exact(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        # The prepared union is not thread-safe: a caller of the process's shared checker
        # that held no lock (random_free_poses, the footprint judge) crashed (SIGSEGV).
        with self.lock:
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

        Parameters
        ----------
        a, b : sequence of float
            Rear-axle positions ``(x, y)`` (further entries are ignored).

        Returns
        -------
        bool
        """
        la = self.grid.label_at(a)
        lb = self.grid.label_at(b)
        return la == 0 or lb == 0 or la != lb

    def too_narrow_between(
        self, a: Sequence[float] | np.ndarray, b: Sequence[float] | np.ndarray, keep: float = 0.0
    ) -> bool:
        """True proves every way for the rear axle from ``a`` to ``b`` is too narrow for the car.

        The exact twin of :meth:`provably_disconnected`, free of the grid's error
        (:mod:`rrtdrive.collision.width_proof`): it proves gaps up to the car's width
        where the grid proves them up to about 1.45-1.6 m. Its region is built once per map
        and timed into :attr:`setup_time_s`.

        Parameters
        ----------
        a, b : sequence of float
            Rear-axle positions ``(x, y)`` (further entries are ignored).
        keep : float
            Body clearance the car keeps, metres: a proof for paths keeping it.

        Returns
        -------
        bool
            True is a proof; False proves nothing.
        """
        r = axle_disc_radius(self.vehicle) + keep
        parts = self.grid.derived(
            ("width_proof", r),
            lambda: free_parts(self.bounds, [o.corners() for o in self.obstacles], r),
        )
        return parts_disconnected(parts, a, b)

    # ------------------------------------------------------------------ cached grid data

    def free_cells(self, start: Sequence[float]) -> np.ndarray:
        """Flat indices of the cells where the rear axle can stand, connected to ``start``.

        See :meth:`rrtdrive.collision.grid.GridCache.free_cells` (cached per component).

        Parameters
        ----------
        start : sequence of float
            A rear-axle position ``(x, y)``.

        Returns
        -------
        numpy.ndarray
            Flat indices into :attr:`clearance_grid` (empty when ``start`` is in no
            kept cell).
        """
        return self.grid.free_cells(start)

    def passage_cells(self, start: Sequence[float], width: float = 0.6) -> np.ndarray:
        """``(K, 2)`` centres of narrow-passage cells reachable from ``start``.

        See :meth:`rrtdrive.collision.grid.GridCache.passage_cells` (cached).

        Parameters
        ----------
        start : sequence of float
            A rear-axle position ``(x, y)``.
        width : float
            How much wider than the edge test a passage may be, in metres.

        Returns
        -------
        numpy.ndarray
            ``(K, 2)`` cell centres.
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
