"""The cost-to-go estimate of the Hybrid A* search (Dolgov et al. 2008, Sec. 3).

Two lower-bound-like estimates, and their maximum:

* *holonomic with obstacles*: the shortest 8-connected distance from the goal
  over the free cells of a coarse grid (:class:`FreeCellGraph`, built once per
  map; one :func:`scipy.sparse.csgraph.dijkstra` per query). A cell is free when
  any of its fine cells lies in a component of the checker's reachability labels,
  a superset of where the rear axle can stand, so no reachable pose is cut off; a
  pose in a cell the goal cannot reach gets ``inf`` and is never expanded.
* *non-holonomic without obstacles*: the Dubins length (forward only,
  :func:`dubins_lengths`, vectorised) or the Reeds-Shepp length (with reverse).
"""

from __future__ import annotations

import array
import functools
import math
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy import sparse
from scipy.sparse.csgraph import dijkstra

from rrtdrive.collision import CollisionChecker
from rrtdrive.planning.dubins import LOOP_SNAP, WORD_NOISE
from rrtdrive.types import Pose

__all__ = ["FreeCellGraph", "HolonomicField", "DubinsTable", "Heuristic", "dubins_lengths"]

_TWO_PI = 2.0 * math.pi

#: The most cells a :class:`FreeCellGraph` has: a larger map gets coarser cells (a 2 km
#: map at 1 m). Its Dijkstra, one per query, cannot look at the wall-clock cap: on a
#: 5 km map at 0.71 m (49 million cells) it took 54 s of a query capped at 5 s.
MAX_FREE_CELLS = 4_000_000
#: ``lengths(poses (N, 3)) -> (N,)``: an obstacle-free non-holonomic length to the goal.
NonHolonomic = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True, eq=False)
class FreeCellGraph:
    """The free cells of a coarse grid over one map and their 8-neighbour graph.

    Attributes
    ----------
    origin : numpy.ndarray
        World position of the coarse grid's lower-left corner.
    resolution : float
        Coarse cell size, metres (a multiple of the checker's).
    index : numpy.ndarray
        ``(NX, NY)`` node number of each free cell, -1 elsewhere.
    graph : scipy.sparse.csr_matrix
        Symmetric edge lengths between neighbouring free cells.
    """

    origin: np.ndarray
    resolution: float
    index: np.ndarray
    graph: sparse.csr_matrix
    #: The last few distance fields, by goal node (a field depends on the goal's cell only):
    #: ``[dist, flat]``, ``flat`` its C doubles for scalar look-ups once asked for (else None).
    _fields: OrderedDict[int, list] = field(
        default_factory=OrderedDict, init=False, repr=False, compare=False
    )

    @classmethod
    def build(cls, checker: CollisionChecker, resolution: float) -> FreeCellGraph:
        """The graph of ``checker``'s map at about ``resolution`` metres per cell."""
        kept = checker.component_labels > 0
        h = checker.resolution
        nx, ny = kept.shape
        f = max(1, round(resolution / h))
        # Coarser on a huge map only: the built-in and benchmark maps (100 m a side or
        # less) are far below the limit; a 500 m map's finest search (0.25 m) gets 0.3 m.
        f = max(f, math.ceil(math.sqrt(nx * ny / MAX_FREE_CELLS)))
        # A coarse cell bigger than the whole grid is the whole grid (bounds the padding).
        f = min(f, max(nx, ny))
        while -(-nx // f) * -(-ny // f) > MAX_FREE_CELLS:
            f += 1
        NX, NY = -(-nx // f), -(-ny // f)
        padded = np.zeros((NX * f, NY * f), dtype=bool)
        padded[:nx, :ny] = kept
        free = padded.reshape(NX, f, NY, f).any(axis=(1, 3))
        index = np.full(free.shape, -1, dtype=np.int64)
        index[free] = np.arange(int(free.sum()))
        H = f * h
        rows, cols, weights = [], [], []
        for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
            i0, i1 = max(0, -di), NX - max(0, di)
            j0, j1 = max(0, -dj), NY - max(0, dj)
            a = index[i0:i1, j0:j1]
            b = index[i0 + di : i1 + di, j0 + dj : j1 + dj]
            both = (a >= 0) & (b >= 0)
            rows.append(a[both])
            cols.append(b[both])
            weights.append(np.full(int(both.sum()), H * math.hypot(di, dj)))
        n = int(free.sum())
        graph = sparse.csr_matrix(
            (np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
        )
        return cls(np.asarray(checker.grid_origin, dtype=float), float(H), index, graph)

    def distances(self, node: int) -> np.ndarray:
        """``(NX, NY)`` distance from each cell centre to node ``node``'s, less a cell diagonal.

        ``inf`` where unreachable; one Dijkstra per node, the last
        :data:`FIELD_CACHE` of them kept (read-only), so queries to one goal, or
        from one start, share it.

        Parameters
        ----------
        node : int
            The goal cell's node number (see :attr:`index`).

        Returns
        -------
        numpy.ndarray
            ``(NX, NY)`` metres, read-only.
        """
        return self._entry(node)[0]

    def flat_distances(self, node: int) -> array.array:
        """:meth:`distances` as a flat array of C doubles, row-major (scalar look-ups).

        Kept with the field: every query to one goal reads the same copy (making it
        cost a query about 20 microseconds).

        Parameters
        ----------
        node : int
            The goal cell's node number.

        Returns
        -------
        array.array
            ``NX * NY`` doubles, cell ``(i, j)`` at ``i * NY + j``.
        """
        entry = self._entry(node)
        if entry[1] is None:
            flat = array.array("d")
            flat.frombytes(np.ascontiguousarray(entry[0], dtype=np.float64).tobytes())
            entry[1] = flat
        return entry[1]

    def _entry(self, node: int) -> list:
        """The cache entry ``[dist, flat or None]`` of node ``node``'s field (made if new)."""
        entry = self._fields.get(node)
        if entry is not None:
            self._fields.move_to_end(node)
            return entry
        d = dijkstra(self.graph, directed=False, indices=node)
        out = np.full(self.index.shape, np.inf)
        out[self.index >= 0] = d
        out = np.maximum(out - self.resolution * math.sqrt(2.0), 0.0)
        out.flags.writeable = False
        entry = self._fields[node] = [out, None]
        while len(self._fields) > FIELD_CACHE:
            self._fields.popitem(last=False)
        return entry

    def cell(self, x: float, y: float) -> tuple[int, int]:
        """The coarse cell ``(i, j)`` holding ``(x, y)`` (possibly outside the grid).

        Parameters
        ----------
        x, y : float
            Position in metres.

        Returns
        -------
        tuple of int
        """
        return (
            int(math.floor((x - self.origin[0]) / self.resolution)),
            int(math.floor((y - self.origin[1]) / self.resolution)),
        )


#: Distance fields a :class:`FreeCellGraph` keeps (by goal cell).
FIELD_CACHE = 8


@dataclass(frozen=True, eq=False)
class HolonomicField:
    """Distances to one goal over a :class:`FreeCellGraph`, looked up per position.

    Attributes
    ----------
    grid : FreeCellGraph
        The map's graph.
    node : int
        The goal cell's node (-1: the goal lies in no free cell).
    dist : numpy.ndarray
        ``(NX, NY)`` distance from each cell centre to the goal's cell, less a cell
        diagonal (a position may lie anywhere in its cell), ``inf`` where
        unreachable; computed at the first look-up (a search that never runs
        needs no Dijkstra).
    """

    grid: FreeCellGraph
    node: int

    @classmethod
    def towards(cls, grid: FreeCellGraph, goal: Pose) -> HolonomicField:
        """The field of one Dijkstra from the goal's cell (unreachable: ``inf`` everywhere)."""
        i, j = grid.cell(goal.x, goal.y)
        inside = 0 <= i < grid.index.shape[0] and 0 <= j < grid.index.shape[1]
        return cls(grid, int(grid.index[i, j]) if inside else -1)

    @functools.cached_property
    def dist(self) -> np.ndarray:  # noqa: D102 - documented as an attribute
        if self.node < 0:
            return np.full(self.grid.index.shape, np.inf)
        return self.grid.distances(self.node)

    @functools.cached_property
    def cells(self) -> array.array:
        """:attr:`dist` as a flat array of C doubles, row-major (scalar look-ups)."""
        if self.node >= 0:
            return self.grid.flat_distances(self.node)  # cached with the field
        out = array.array("d")
        out.frombytes(np.ascontiguousarray(self.dist, dtype=np.float64).tobytes())
        return out

    def value(self, x: float, y: float) -> float:
        """The distance at one position (scalar :meth:`at`).

        Parameters
        ----------
        x, y : float
            Position in metres.

        Returns
        -------
        float
            Metres; ``inf`` outside the grid or unreachable.
        """
        g = self.grid
        i = math.floor((x - g.origin[0]) / g.resolution)
        j = math.floor((y - g.origin[1]) / g.resolution)
        nx, ny = self.dist.shape
        if 0 <= i < nx and 0 <= j < ny:
            return float(self.dist[i, j])
        return math.inf

    def at(self, xy: np.ndarray) -> np.ndarray:
        """Distances at positions ``(N, 2)`` (``inf`` outside the grid or unreachable).

        Parameters
        ----------
        xy : numpy.ndarray
            ``(N, 2)`` positions in metres.

        Returns
        -------
        numpy.ndarray
            ``(N,)`` metres.
        """
        g = self.grid
        ij = np.floor((np.asarray(xy, dtype=float) - g.origin) / g.resolution).astype(np.int64)
        nx, ny = self.dist.shape
        ok = (ij[:, 0] >= 0) & (ij[:, 1] >= 0) & (ij[:, 0] < nx) & (ij[:, 1] < ny)
        out = np.full(len(ij), np.inf)
        out[ok] = self.dist[ij[ok, 0], ij[ok, 1]]
        return out


def _mod2pi(a: np.ndarray) -> np.ndarray:
    return np.mod(a, _TWO_PI)


def _roots(p2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``dubins._root`` element-wise: whether each word exists, and its straight's length."""
    return p2 >= -WORD_NOISE, np.sqrt(np.maximum(p2, 0.0))


def _cosines(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``dubins._cosine`` element-wise: whether each word exists, and the clipped cosine."""
    return np.abs(c) <= 1.0 + WORD_NOISE, np.clip(c, -1.0, 1.0)


def _arc(a: np.ndarray) -> np.ndarray:
    """A word's arc wrapped to ``[0, 2 pi)``, a hair under 2 pi as 0 (``dubins._unloop``)."""
    v = np.mod(a, _TWO_PI)
    return np.where(_TWO_PI - v <= LOOP_SNAP, 0.0, v)


def dubins_lengths(poses: np.ndarray, goal: Pose, radius: float) -> np.ndarray:
    """Lengths of the shortest Dubins paths from each pose ``(N, 3)`` to ``goal``.

    The six words of Shkel & Lumelsky (2001), as in :mod:`rrtdrive.planning.dubins`,
    evaluated for many start poses at once.

    Parameters
    ----------
    poses : numpy.ndarray
        ``(N, 3)`` rows x, y, yaw (metres, radians).
    goal : Pose
        The goal pose.
    radius : float
        Turning radius, metres.

    Returns
    -------
    numpy.ndarray
        ``(N,)`` lengths in metres.

    Examples
    --------
    >>> from rrtdrive.planning.dubins import shortest_dubins
    >>> p = np.array([[0.0, 0.0, 0.0], [3.0, -2.0, 2.0]])
    >>> goal = Pose(10.0, 4.0, -1.0)
    >>> got = dubins_lengths(p, goal, 6.0)
    >>> want = [shortest_dubins(Pose(*q), goal, 6.0).length for q in p]
    >>> bool(np.allclose(got, want))
    True
    """
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    dx, dy = goal.x - p[:, 0], goal.y - p[:, 1]
    d = np.hypot(dx, dy) / radius
    theta = np.where(d > 0, np.arctan2(dy, dx), 0.0)
    a = _mod2pi(p[:, 2] - theta)
    b = _mod2pi(goal.yaw - theta)
    sa, sb, ca, cb = np.sin(a), np.sin(b), np.cos(a), np.cos(b)
    cab = np.cos(a - b)
    best = np.full(len(p), np.inf)
    with np.errstate(invalid="ignore"):
        # LSL
        ok, q = _roots(2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb))
        tmp = np.arctan2(cb - ca, d + sa - sb)
        total = _arc(tmp - a) + q + _arc(b - tmp)
        best = np.fmin(best, np.where(ok, total, np.inf))
        # RSR
        ok, q = _roots(2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa))
        tmp = np.arctan2(ca - cb, d - sa + sb)
        total = _arc(a - tmp) + q + _arc(tmp - b)
        best = np.fmin(best, np.where(ok, total, np.inf))
        # LSR
        ok, q = _roots(-2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb))
        tmp = np.arctan2(-ca - cb, d + sa + sb) - np.arctan2(-2.0, q)
        total = _arc(tmp - a) + q + _arc(tmp - b)
        best = np.fmin(best, np.where(ok, total, np.inf))
        # RSL
        ok, q = _roots(-2.0 + d * d + 2.0 * cab - 2.0 * d * (sa + sb))
        tmp = np.arctan2(ca + cb, d - sa - sb) - np.arctan2(2.0, q)
        total = _arc(a - tmp) + q + _arc(b - tmp)
        best = np.fmin(best, np.where(ok, total, np.inf))
        # RLR
        ok, c = _cosines((6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb)) / 8.0)
        mid = _mod2pi(_TWO_PI - np.arccos(c))
        t = _mod2pi(a - np.arctan2(ca - cb, d - sa + sb) + mid / 2.0)
        total = _arc(t) + _arc(mid) + _arc(a - b - t + mid)
        best = np.fmin(best, np.where(ok, total, np.inf))
        # LRL
        ok, c = _cosines((6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa)) / 8.0)
        mid = _mod2pi(_TWO_PI - np.arccos(c))
        t = _mod2pi(-a + np.arctan2(-ca + cb, d + sa - sb) + mid / 2.0)
        total = _arc(t) + _arc(mid) + _arc(b - a - t + mid)
        best = np.fmin(best, np.where(ok, total, np.inf))
    return best * radius


@dataclass(frozen=True, eq=False)
class DubinsTable:
    """Dubins lengths to a goal at the origin heading +x, tabulated on a grid of start poses.

    The heuristic reads the nearest entry instead of solving six words per
    successor; beyond the table it falls back to the straight-line distance.

    Attributes
    ----------
    radius : float
        Turning radius, metres.
    half_extent, resolution : float
        The table covers ``[-half_extent, half_extent]^2`` at ``resolution`` metres.
    lengths : numpy.ndarray
        ``(n, n, yaw_bins)`` lengths; heading bin ``k`` is ``2 pi k / yaw_bins``.
    """

    radius: float
    half_extent: float
    resolution: float
    lengths: np.ndarray

    @classmethod
    def build(
        cls, radius: float, half_extent: float = 15.0, resolution: float = 0.5, yaw_bins: int = 72
    ) -> DubinsTable:
        """Tabulate with :func:`dubins_lengths`, one heading bin at a time.

        Examples
        --------
        >>> t = DubinsTable.build(6.0, half_extent=4.0, resolution=1.0, yaw_bins=8)
        >>> t.lengths.shape, float(t.lengths[4, 4, 0])
        ((9, 9, 8), 0.0)
        """
        axis = np.arange(-half_extent, half_extent + 1e-9, resolution)
        gx, gy = np.meshgrid(axis, axis, indexing="ij")
        out = np.empty((len(axis), len(axis), yaw_bins))
        origin = Pose(0.0, 0.0, 0.0)
        for k in range(yaw_bins):
            yaw = np.full(gx.size, _TWO_PI * k / yaw_bins)
            poses = np.column_stack([gx.ravel(), gy.ravel(), yaw])
            out[..., k] = dubins_lengths(poses, origin, radius).reshape(gx.shape)
        return cls(float(radius), float(half_extent), float(resolution), out)

    def scalar_to(self, goal: Pose) -> Callable[[float, float, float], float]:
        """The length from one pose to ``goal`` (scalar lookup of :meth:`to`)."""
        c, s = math.cos(goal.yaw), math.sin(goal.yaw)
        n, _, bins = self.lengths.shape
        inv, half = 1.0 / self.resolution, self.half_extent
        table = self.lengths
        gx, gy, gyaw = goal.x, goal.y, goal.yaw
        scale = bins / _TWO_PI

        def length(x: float, y: float, yaw: float) -> float:
            dx, dy = x - gx, y - gy
            i = round((c * dx + s * dy + half) * inv)
            j = round((-s * dx + c * dy + half) * inv)
            if 0 <= i < n and 0 <= j < n:
                return float(table[i, j, round((yaw - gyaw) * scale) % bins])
            return math.hypot(dx, dy)

        return length

    def to(self, goal: Pose) -> NonHolonomic:
        """The lengths from poses ``(N, 3)`` to ``goal`` (table lookups)."""
        c, s = math.cos(goal.yaw), math.sin(goal.yaw)
        n, _, bins = self.lengths.shape
        inv, half = 1.0 / self.resolution, self.half_extent
        table = self.lengths

        def lengths(p: np.ndarray) -> np.ndarray:
            dx, dy = p[:, 0] - goal.x, p[:, 1] - goal.y
            u, v = c * dx + s * dy, -s * dx + c * dy
            i = np.rint((u + half) * inv).astype(np.int64)
            j = np.rint((v + half) * inv).astype(np.int64)
            k = np.rint((p[:, 2] - goal.yaw) * (bins / _TWO_PI)).astype(np.int64) % bins
            inside = (i >= 0) & (j >= 0) & (i < n) & (j < n)
            out = np.hypot(dx, dy)
            out[inside] = table[i[inside], j[inside], k[inside]]
            return out

        return lengths


@dataclass(frozen=True, eq=False)
class Heuristic:
    """``max(holonomic with obstacles, non-holonomic without)`` for poses to one goal.

    Attributes
    ----------
    holonomic : HolonomicField
        Distances over the free cells.
    nonholonomic : callable or None
        Dubins or Reeds-Shepp lengths; ``None``: the straight-line distance.
    scalar_nonholonomic : callable, optional
        The same for one pose ``(x, y, yaw)``, used by :meth:`at`.
    goal : Pose
        The goal.
    """

    holonomic: HolonomicField
    nonholonomic: NonHolonomic | None
    goal: Pose
    scalar_nonholonomic: Callable[[float, float, float], float] | None = None

    def at(self, x: float, y: float, yaw: float) -> float:
        """The estimate for one pose (the search's hot path: no numpy call).

        Parameters
        ----------
        x, y, yaw : float
            Rear-axle pose (metres, radians).

        Returns
        -------
        float
            Metres (``inf``: the goal cannot be reached).
        """
        h = self.holonomic.value(x, y)
        if h == math.inf:
            return h
        if self.scalar_nonholonomic is not None:
            return max(h, self.scalar_nonholonomic(x, y, yaw))
        if self.nonholonomic is not None:
            return max(h, float(self.nonholonomic(np.array([[x, y, yaw]]))[0]))
        return max(h, math.hypot(x - self.goal.x, y - self.goal.y))

    def scalar(self) -> Callable[[float, float, float], float]:
        """:meth:`at` as a closure over its constants: the same values, for the search's loop."""
        if self.scalar_nonholonomic is None and self.nonholonomic is not None:
            return self.at
        field = self.holonomic
        cells, grid = field.cells, field.grid
        ox, oy = float(grid.origin[0]), float(grid.origin[1])
        res = grid.resolution
        nx, ny = field.dist.shape
        floor, hypot, inf = math.floor, math.hypot, math.inf
        other = self.scalar_nonholonomic
        gx, gy = self.goal.x, self.goal.y

        def at(x: float, y: float, yaw: float) -> float:
            i = floor((x - ox) / res)
            j = floor((y - oy) / res)
            if not (0 <= i < nx and 0 <= j < ny):
                return inf
            h = cells[i * ny + j]
            if h == inf:
                return h
            if other is not None:
                return max(h, other(x, y, yaw))
            return max(h, hypot(x - gx, y - gy))

        return at

    def __call__(self, poses: np.ndarray) -> np.ndarray:
        """Estimates for poses ``(N, 3)``, metres (``inf``: the goal cannot be reached)."""
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        h = self.holonomic.at(p[:, :2])
        if self.nonholonomic is not None:
            return np.maximum(h, self.nonholonomic(p))
        return np.maximum(h, np.hypot(p[:, 0] - self.goal.x, p[:, 1] - self.goal.y))
