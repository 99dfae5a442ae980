"""The checker's occupancy grid and the data derived from it, built once per checker.

:func:`grid_resolution` picks the cell size that keeps a map's grid within
:attr:`CheckerConfig.max_grid_cells` (or refuses the bounds);
:func:`rasterise` marks the cells an obstacle or the outside may touch;
:class:`GridCache` owns the clearance field made from it and lazily builds, caches
and times what planners derive from that field: connectivity labels, the cells a
sampler may draw from, narrow-passage cells, and the prepared obstacle union.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Hashable, Sequence
from typing import Any, TypeVar

import numpy as np
import shapely
from scipy import ndimage

from rrtdrive.collision.config import MAX_RESOLUTION, CheckerConfig
from rrtdrive.maps import Obstacle
from rrtdrive.types import InputError, VehicleParams
from rrtdrive.vehicle import axle_disc_radius

T = TypeVar("T")

__all__ = ["LARGE_GRID_CELLS", "grid_shape", "grid_origin", "grid_resolution", "setup_notice",
           "rasterise", "GridCache"]

#: Grids of more cells than this take seconds to set up: the CLI says so before it
#: starts (parking_lot has about 1 M cells; 9 M took 3.5 s on a 2-vCPU machine).
LARGE_GRID_CELLS = 4_000_000


def grid_shape(bounds: Sequence[float], resolution: float, pad: float) -> tuple[int, int]:
    """Cells ``(nx, ny)`` of the grid over ``bounds`` with ``pad`` metres of border each side.

    Cells are aligned with the bounds (the border is a whole number of cells).

    Examples
    --------
    >>> grid_shape((0.0, 0.0, 100.0, 50.0), 0.1, 1.0)
    (1020, 520)
    """
    h = float(resolution)
    n_pad = int(math.ceil(pad / h))
    xmin, ymin, xmax, ymax = (float(b) for b in bounds)
    return (
        int(math.ceil((xmax - xmin) / h)) + 2 * n_pad,
        int(math.ceil((ymax - ymin) / h)) + 2 * n_pad,
    )


#: A cell size (metres) past which no cell is suggested: the map is simply too big.
_NO_CELL = 1e6


def setup_notice(bounds: Sequence[float], config: CheckerConfig) -> str | None:
    """A line announcing a long set-up, for a grid of more than :data:`LARGE_GRID_CELLS`.

    ``None`` for a smaller grid, or for bounds no grid fits (the checker's own
    error names them).

    Examples
    --------
    >>> setup_notice((0.0, 0.0, 100.0, 100.0), CheckerConfig()) is None
    True
    >>> setup_notice((0.0, 0.0, 500.0, 500.0), CheckerConfig())  # doctest: +ELLIPSIS
    'setting up a 500 x 500 m map: 25.2 M grid cells at 0.1 m (seconds; not planning time)'
    """
    try:
        h = grid_resolution(bounds, config)
    except InputError:
        return None
    nx, ny = grid_shape(bounds, h, config.pad)
    if nx * ny <= LARGE_GRID_CELLS:
        return None
    xmin, ymin, xmax, ymax = (float(b) for b in bounds)
    return (
        f"setting up a {xmax - xmin:g} x {ymax - ymin:g} m map: {nx * ny / 1e6:.1f} M grid "
        f"cells at {h:g} m (seconds; not planning time)"
    )


def grid_resolution(bounds: Sequence[float], config: CheckerConfig) -> float:
    """The cell size for ``bounds``: ``config.resolution``, or coarser when the grid is too big.

    The grid may have at most ``config.max_grid_cells`` cells. When it would have
    more, the cell size grows in centimetre steps to the first that fits; up to
    ``config.max_auto_resolution`` (or ``config.resolution`` when that is coarser)
    the checker takes it. Its error margin grows with the cell (rasterisation and
    lookup each ``h / sqrt 2``), so the fast tests stay conservative.

    Parameters
    ----------
    bounds : sequence of float
        ``(xmin, ymin, xmax, ymax)`` in metres.
    config : CheckerConfig
        Requested resolution, pad and the limits.

    Returns
    -------
    float
        Cell size in metres, ``>= config.resolution``.

    Raises
    ------
    InputError
        Naming ``bounds`` when even the coarsest allowed cell makes too many cells.

    Examples
    --------
    >>> grid_resolution((0.0, 0.0, 100.0, 100.0), CheckerConfig())
    0.1
    >>> grid_resolution((0.0, 0.0, 1000.0, 1000.0), CheckerConfig())
    0.15
    """
    h0, limit = config.resolution, config.max_grid_cells
    xmin, ymin, xmax, ymax = (float(b) for b in bounds)
    try:
        nx, ny = grid_shape(bounds, h0, config.pad)
    except OverflowError:  # more cells than a float counts ([0, 0, 1e308, 100])
        raise InputError(
            f"bounds: {xmax - xmin:g} x {ymax - ymin:g} m is too big for any grid: use a "
            "smaller map"
        ) from None
    if nx * ny <= limit:
        return h0
    coarsest = max(h0, config.max_auto_resolution)
    # The area alone gives a lower bound of the cell size; the border adds a few steps.
    least = math.sqrt((xmax - xmin) * (ymax - ymin) / limit)
    if not least <= _NO_CELL:  # no usable cell (and the grid's shape would not fit a float)
        h = least
    else:
        steps = max(int(math.ceil(h0 * 100.0)), int(math.ceil(100.0 * least)))
        while True:
            h = round(steps / 100.0, 10)
            fx, fy = grid_shape(bounds, h, config.pad)
            if h > h0 and fx * fy <= limit:
                break
            # 1 cm at a time, or 0.1 % once the cell is over 10 m: a cell of kilometres
            # stepped by centimetres would take minutes.
            steps += max(1, steps // 1000)
    if h > coarsest + 1e-12:
        cells = nx * ny
        count = f"{cells:,}" if cells < 10**12 else f"about 1e{len(str(cells)) - 1}"
        if not h <= MAX_RESOLUTION:  # a cell --resolution refuses: no advice to give
            raise InputError(
                f"bounds: {xmax - xmin:g} x {ymax - ymin:g} m needs {count} grid cells at "
                f"{h0:g} m; the limit is {limit:,} cells (checker.max_grid_cells): use a "
                f"smaller map"
            )
        raise InputError(
            f"bounds: {xmax - xmin:g} x {ymax - ymin:g} m needs {count} grid cells at "
            f"{h0:g} m; the limit is {limit:,} cells (checker.max_grid_cells), which needs "
            f"{h:g} m cells, coarser than the {coarsest:g} m the checker chooses by itself; "
            f"use a smaller map or cells of {h:g} m (rrtdrive plan or simulate "
            f"--resolution {h:g}; "
            f"CheckerConfig(resolution={h:g}) in Python)"
        )
    return h


def grid_origin(bounds: Sequence[float], resolution: float, pad: float) -> np.ndarray:
    """World position of the lower-left corner of :func:`grid_shape`'s grid.

    Cells are aligned with the bounds, so every point outside lies in an occupied cell.

    Examples
    --------
    >>> grid_origin((0.0, 0.0, 100.0, 50.0), 0.1, 1.0).round(9).tolist()
    [-1.0, -1.0]
    """
    h = float(resolution)
    n_pad = int(math.ceil(pad / h))
    return np.array([bounds[0] - n_pad * h, bounds[1] - n_pad * h])


def rasterise(
    bounds: tuple[float, ...],
    obstacles: Sequence[Obstacle],
    origin: np.ndarray,
    resolution: float,
    nx: int,
    ny: int,
) -> np.ndarray:
    """Occupancy of an ``(nx, ny)`` grid of cells of size ``resolution`` from ``origin``.

    Cells outside ``bounds`` are occupied, and so is every cell that touches an
    obstacle (a superset: conservative).

    Parameters
    ----------
    bounds : tuple of float
        ``(xmin, ymin, xmax, ymax)``.
    obstacles : sequence of Obstacle
        Oriented rectangles.
    origin : numpy.ndarray
        World position of the grid's lower-left corner.
    resolution : float
        Cell size in metres.
    nx, ny : int
        Grid shape.

    Returns
    -------
    numpy.ndarray
        Boolean ``(nx, ny)``.
    """
    h = resolution
    xs = origin[0] + h * (np.arange(nx) + 0.5)
    ys = origin[1] + h * (np.arange(ny) + 0.5)
    xmin, ymin, xmax, ymax = bounds
    occupied = np.zeros((nx, ny), dtype=bool)
    # A cell that reaches past xmax / ymax touches the outside (the grid is aligned with
    # xmin / ymin only): occupied, as a cell touching an obstacle is.
    eps = 1e-9 * h
    occupied[(xs < xmin) | (xs + 0.5 * h > xmax + eps), :] = True
    occupied[:, (ys < ymin) | (ys + 0.5 * h > ymax + eps)] = True
    # A cell is occupied when its centre lies in the rectangle grown by h/sqrt2 on
    # every side: a superset of every cell that touches the rectangle.
    grow = h / math.sqrt(2.0)
    # Cell indices are clipped to the grid before the cast: a rectangle reaching 1e19 m
    # would overflow int64 and drop out of the grid (a planner would drive through it).
    top = np.array([nx, ny], dtype=float)
    for o in obstacles:
        corners = o.corners()
        with np.errstate(over="ignore"):  # a corner at 1e308 m: inf, clipped like the rest
            low = np.floor((corners.min(axis=0) - grow - origin) / h)
            high = np.ceil((corners.max(axis=0) + grow - origin) / h)
        lo = np.clip(low, -1, top).astype(int) - 1
        hi = np.clip(high, -1, top).astype(int) + 1
        i0, j0 = max(lo[0], 0), max(lo[1], 0)
        i1, j1 = min(hi[0], nx), min(hi[1], ny)
        if i0 >= i1 or j0 >= j1:
            continue
        gx, gy = np.meshgrid(xs[i0:i1] - o.center[0], ys[j0:j1] - o.center[1], indexing="ij")
        c, s = math.cos(o.yaw), math.sin(o.yaw)
        along = c * gx + s * gy
        across = -s * gx + c * gy
        inside = (np.abs(along) <= o.size[0] / 2 + grow) & (
            np.abs(across) <= o.size[1] / 2 + grow
        )
        occupied[i0:i1, j0:j1] |= inside
    return occupied


class GridCache:
    """Grid-derived data of one checker, each piece built on first use and kept.

    Every build is timed into :attr:`setup_time_s`, so a planner can report the
    set-up of a map apart from its planning time.

    Parameters
    ----------
    clearance : numpy.ndarray
        ``(nx, ny)`` lower bound of the distance to the nearest obstacle at each
        cell centre (the checker's field, error already subtracted).
    origin : numpy.ndarray
        World position of the grid's lower-left corner.
    resolution : float
        Cell size in metres.
    grid_error : float
        The error subtracted from the field (added back for upper bounds).
    vehicle : VehicleParams
        The car.
    bounds : tuple of float
        ``(xmin, ymin, xmax, ymax)``.
    obstacles : sequence of Obstacle
        The map's obstacles (for the union).
    edge_radius : float
        Radius of the checker's swept-capsule edge test, metres.
    setup_time_s : float
        Seconds already spent building the field (counted in :attr:`setup_time_s`).
    """

    def __init__(
        self,
        clearance: np.ndarray,
        origin: np.ndarray,
        resolution: float,
        grid_error: float,
        vehicle: VehicleParams,
        bounds: tuple[float, ...],
        obstacles: Sequence[Obstacle],
        edge_radius: float,
        setup_time_s: float = 0.0,
    ) -> None:
        self.clearance = clearance
        self.origin = origin
        self.resolution = float(resolution)
        self._inv_h = 1.0 / resolution
        self.shape = clearance.shape
        self.grid_error = grid_error
        self.vehicle = vehicle
        self.bounds = bounds
        self.obstacles = tuple(obstacles)
        self.edge_radius = edge_radius
        self.setup_time_s = float(setup_time_s)
        self._labels: np.ndarray | None = None
        self._union: shapely.Geometry | None = None
        self._free: dict[int, np.ndarray] = {}
        self._passages: dict[tuple[int, float], np.ndarray] = {}
        self._derived: dict[Hashable, Any] = {}

    def derived(self, key: Hashable, build: Callable[[], T]) -> T:
        """Data a planner derives from this map (e.g. an expanded-obstacle checker), built once.

        ``build()`` runs on the first call with ``key`` and is timed into
        :attr:`setup_time_s`; later calls return the same object.

        Parameters
        ----------
        key : hashable
            Names the data (e.g. a planner's name and the settings it depends on).
        build : callable
            Makes it, with no arguments.

        Returns
        -------
        object
            What ``build`` returned, the first time or since.
        """
        if key not in self._derived:
            t0 = time.perf_counter()
            self._derived[key] = build()
            self.setup_time_s += time.perf_counter() - t0
        return self._derived[key]

    # ------------------------------------------------------------------ connectivity

    def reachable_components(self) -> tuple[np.ndarray, float]:
        """Label the cells the rear axle could ever occupy (see the checker's method)."""
        h = self.resolution
        # Field measures distance to occupied centres; an occupied centre lies within
        # h of the true obstacle (grown by h/sqrt2 per side), and any point of a cell
        # is within h/sqrt2 of its centre.
        slack = h + h / math.sqrt(2.0)
        r = axle_disc_radius(self.vehicle)
        upper = self.clearance + self.grid_error + slack
        kept = upper >= r
        labels, _ = ndimage.label(kept, structure=np.ones((3, 3), dtype=bool))
        return labels, slack

    @property
    def component_labels(self) -> np.ndarray:
        """The labels of :meth:`reachable_components`, computed once."""
        if self._labels is None:
            t0 = time.perf_counter()
            self._labels, _ = self.reachable_components()
            self._labels.flags.writeable = False  # shared by every query on the map
            self.setup_time_s += time.perf_counter() - t0
        return self._labels

    def label_at(self, p: Sequence[float]) -> int:
        """Component label of the cell holding point ``p`` (0: none, or outside the grid).

        Parameters
        ----------
        p : sequence of float
            A position ``(x, y)``.

        Returns
        -------
        int
        """
        i = int(math.floor((p[0] - self.origin[0]) * self._inv_h))
        j = int(math.floor((p[1] - self.origin[1]) * self._inv_h))
        if not (0 <= i < self.shape[0] and 0 <= j < self.shape[1]):
            return 0
        return int(self.component_labels[i, j])

    def _start_label(self, start: Sequence[float]) -> int:
        # Divides by h where label_at multiplies by 1/h: kept as the samplers had it,
        # so the cells they draw from stay bit-identical.
        labels = self.component_labels
        origin, h = self.origin, self.resolution
        i = int(math.floor((start[0] - origin[0]) / h))
        j = int(math.floor((start[1] - origin[1]) / h))
        inside = 0 <= i < labels.shape[0] and 0 <= j < labels.shape[1]
        return int(labels[i, j]) if inside else 0

    # ------------------------------------------------------------------ sampling support

    def free_cells(self, start: Sequence[float]) -> np.ndarray:
        """Flat indices of the cells where the rear axle can stand, connected to ``start``.

        A cell qualifies when its clearance admits the car with some heading (the
        checker's ``point_free`` test) and it lies in the start's component of
        :meth:`reachable_components`. Cached per component.

        Parameters
        ----------
        start : sequence of float
            Start position ``(x, y)``.

        Returns
        -------
        numpy.ndarray
            Indices into ``clearance.ravel()``; empty if the start is in no component.
        """
        label = self._start_label(start)
        cells = self._free.get(label)
        if cells is None:
            t0 = time.perf_counter()
            if label == 0:
                cells = np.zeros(0, dtype=np.int64)
            else:
                stand = self.clearance >= axle_disc_radius(self.vehicle)
                cells = np.flatnonzero(stand & (self.component_labels == label))
            cells.flags.writeable = False  # a caller's shuffle would change later plans
            self._free[label] = cells
            self.setup_time_s += time.perf_counter() - t0
        return cells

    def passage_cells(self, start: Sequence[float], width: float = 0.6) -> np.ndarray:
        """Centres of the cells on the centre lines of narrow passages reachable from ``start``.

        A cell qualifies when its clearance is a local maximum across some grid
        direction (a ridge of the distance field, i.e. the medial axis) with walls
        on both sides (one clearance away along that direction the clearance nearly
        vanishes) and lies between the edge test's radius ``W/2 + margin`` and that
        plus ``width``: an edge through it can pass, but only just. Medial-axis
        sampling after Wilmarth, Amato & Stiller (ICRA 1999). Cached per start
        component and width.

        Parameters
        ----------
        start : sequence of float
            A point of the component to keep (the start position).
        width : float
            How much wider than the edge test a passage may be, in metres.

        Returns
        -------
        numpy.ndarray
            ``(K, 2)`` cell centres (possibly empty).
        """
        label = self._start_label(start)
        key = (label, float(width))
        cached = self._passages.get(key)
        if cached is not None:
            return cached
        t0 = time.perf_counter()
        labels = self.component_labels
        origin, h = self.origin, self.resolution
        cl = self.clearance
        nx, ny = cl.shape
        # The band is a thin fraction of the grid: test only its inner cells (a whole-grid
        # test per direction took seconds on a 1 km map), in row-major order as before.
        inner = cl[1:-1, 1:-1]
        bi, bj = np.nonzero((inner >= self.edge_radius) & (inner <= self.edge_radius + width))
        bi += 1
        bj += 1
        if label:
            keep = labels[bi, bj] == label
            bi, bj = bi[keep], bj[keep]
        c_all = cl[bi, bj]
        ridge = np.zeros(len(bi), dtype=bool)
        for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
            # A local maximum of the clearance across direction (di, dj) ...
            a = cl[bi + di, bj + dj]
            b = cl[bi - di, bj - dj]
            cand = np.flatnonzero((c_all >= a) & (c_all >= b) & (c_all > np.minimum(a, b)))
            if len(cand) == 0:
                continue
            # ... with walls on both sides: one clearance away, either way, the
            # clearance nearly vanishes (it does not beside a convex corner).
            c = c_all[cand]
            k = np.round(c / (math.hypot(di, dj) * h)).astype(np.int64)
            both = np.ones(len(cand), dtype=bool)
            for sgn in (1, -1):
                ii = np.clip(bi[cand] + sgn * k * di, 0, nx - 1)
                jj = np.clip(bj[cand] + sgn * k * dj, 0, ny - 1)
                both &= cl[ii, jj] <= 0.3 * c
            ridge[cand[both]] = True
        ij = np.column_stack((bi[ridge], bj[ridge]))
        cells = origin + (ij + 0.5) * h
        xmin, ymin, xmax, ymax = self.bounds
        cells = cells[
            (cells[:, 0] > xmin)
            & (cells[:, 0] < xmax)
            & (cells[:, 1] > ymin)
            & (cells[:, 1] < ymax)
        ]
        cells.flags.writeable = False
        self._passages[key] = cells
        self.setup_time_s += time.perf_counter() - t0
        return cells

    # ------------------------------------------------------------------ geometry

    @property
    def obstacle_union(self) -> shapely.Geometry:
        """The prepared shapely union of the obstacles (empty geometry when there are none)."""
        if self._union is None:
            t0 = time.perf_counter()
            union = shapely.union_all([o.polygon() for o in self.obstacles])
            shapely.prepare(union)
            self._union = union
            self.setup_time_s += time.perf_counter() - t0
        return self._union
