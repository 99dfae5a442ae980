"""Reeds-Shepp lengths for many poses at once, and a lookup table for heuristics.

A search that reverses (Hybrid A*) scores every node it creates by the Reeds-Shepp
length to the goal, tens of thousands of times per query; one exact call costs tens
of microseconds in Python (``experiments/bench_reeds_shepp.py``). Two helpers:

* :func:`shortest_lengths`: the exact shortest length (radius 1) for arrays of goals
  in the start frame, the same 44 formula evaluations as
  :mod:`rrtdrive.planning.reeds_shepp_words` written over numpy arrays;
* :class:`ReedsSheppTable`: those lengths on a grid of goal poses relative to the
  start, ``(dx, dy, dyaw)`` in the start frame, built once per radius and grid
  (:func:`reeds_shepp_table` caches it) and read by trilinear interpolation. It is
  an approximation: near the start the length grows like the square root of a
  sideways offset, so the error there is larger than a cell;
  :attr:`ReedsSheppTable.max_error` is measured at build time on random poses.
  Goals outside the grid fall back to the exact length.

The length is invariant under the reflect and timeflip symmetries (see
:mod:`rrtdrive.planning.reeds_shepp_words`), so the grid covers ``dx >= 0, dy >= 0``
only and maps the other three quadrants onto it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from rrtdrive.planning.reeds_shepp import reeds_shepp_distance
from rrtdrive.types import Pose, require_int, require_positive

__all__ = ["ReedsSheppTable", "reeds_shepp_table", "shortest_lengths"]

_PI = math.pi
_HALF_PI = 0.5 * math.pi
_TWO_PI = 2.0 * math.pi
#: Slack on the sign conditions and the snap of float noise in a goal's lateral offset
#: or heading, as in :mod:`rrtdrive.planning.reeds_shepp_words` (OMPL's 10 eps lost a
#: 0.125 m straight to noise and answered 0.3018 m, radius 9; an audit).
_ZERO = 1e-10
_SNAP = 1e-12


def _mod2pi(a: np.ndarray) -> np.ndarray:
    v = np.fmod(a, _TWO_PI)
    v[v < -_PI] += _TWO_PI
    v[v > _PI] -= _TWO_PI
    return v


def _tau_omega(
    u: np.ndarray, v: np.ndarray, xi: np.ndarray, eta: np.ndarray, phi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    delta = _mod2pi(u - v)
    a = np.sin(u) - np.sin(delta)
    b = np.cos(u) - np.cos(delta) - 1.0
    t1 = np.arctan2(eta * a - xi * b, xi * a + eta * b)
    t2 = 2.0 * (np.cos(delta) - np.cos(v) - np.cos(u)) + 3.0
    tau = _mod2pi(np.where(t2 < 0, t1 + _PI, t1))
    return tau, _mod2pi(tau - u + v - phi)


# Each returns the total length (radius 1) of its base word, inf where it fails.


def _csc(
    x: np.ndarray, y: np.ndarray, phi: np.ndarray, sp: np.ndarray, cp: np.ndarray
) -> np.ndarray:
    inf = np.inf
    xi, eta = x - sp, y - 1.0 + cp  # L+ S+ L+ (8.1)
    u, t = np.hypot(xi, eta), np.arctan2(eta, xi)
    v = _mod2pi(phi - t)
    lsl = np.where((t >= -_ZERO) & (v >= -_ZERO), np.abs(t) + u + np.abs(v), inf)
    xi, eta = x + sp, y - 1.0 - cp  # L+ S+ R+ (8.2)
    rho2 = xi * xi + eta * eta
    u = np.sqrt(np.maximum(rho2 - 4.0, 0.0))
    t = _mod2pi(np.arctan2(eta, xi) + np.arctan2(2.0, u))
    v = _mod2pi(t - phi)
    lsr = np.where((rho2 >= 4.0) & (t >= -_ZERO) & (v >= -_ZERO), np.abs(t) + u + np.abs(v), inf)
    return np.minimum(lsl, lsr)


def _ccc(
    x: np.ndarray, y: np.ndarray, phi: np.ndarray, sp: np.ndarray, cp: np.ndarray
) -> np.ndarray:
    xi, eta = x - sp, y - 1.0 + cp  # L+ R- L (8.3/8.4)
    rho = np.hypot(xi, eta)
    u = -2.0 * np.arcsin(np.minimum(0.25 * rho, 1.0))
    t = _mod2pi(np.arctan2(eta, xi) + 0.5 * u + _PI)
    v = _mod2pi(phi - t + u)
    ok = (rho <= 4.0) & (t >= -_ZERO) & (u <= _ZERO)
    return np.where(ok, np.abs(t) + np.abs(u) + np.abs(v), np.inf)


def _cccc(
    x: np.ndarray, y: np.ndarray, phi: np.ndarray, sp: np.ndarray, cp: np.ndarray
) -> np.ndarray:
    xi, eta = x + sp, y - 1.0 - cp
    rho = 0.25 * (2.0 + np.hypot(xi, eta))  # L+ R+ L- R- (8.7)
    u = np.arccos(np.minimum(rho, 1.0))
    t, v = _tau_omega(u, -u, xi, eta, phi)
    ok = (rho <= 1.0) & (t >= -_ZERO) & (v <= _ZERO)
    a = np.where(ok, np.abs(t) + 2.0 * np.abs(u) + np.abs(v), np.inf)
    rho = (20.0 - xi * xi - eta * eta) / 16.0  # L+ R- L- R+ (8.8)
    u = -np.arccos(np.clip(rho, 0.0, 1.0))
    t, v = _tau_omega(u, u, xi, eta, phi)
    ok = (rho >= 0.0) & (rho <= 1.0) & (u >= -_HALF_PI) & (t >= -_ZERO) & (v >= -_ZERO)
    return np.minimum(a, np.where(ok, np.abs(t) + 2.0 * np.abs(u) + np.abs(v), np.inf))


def _ccsc(
    x: np.ndarray, y: np.ndarray, phi: np.ndarray, sp: np.ndarray, cp: np.ndarray
) -> np.ndarray:
    xi, eta = x - sp, y - 1.0 + cp  # L+ R-(pi/2) S- L- (8.9)
    rho2 = xi * xi + eta * eta
    r = np.sqrt(np.maximum(rho2 - 4.0, 0.0))
    u = 2.0 - r
    t = _mod2pi(np.arctan2(eta, xi) + np.arctan2(r, -2.0))
    v = _mod2pi(phi - _HALF_PI - t)
    ok = (rho2 >= 4.0) & (t >= -_ZERO) & (u <= _ZERO) & (v <= _ZERO)
    a = np.where(ok, np.abs(t) + np.abs(u) + np.abs(v), np.inf)
    xi, eta = x + sp, y - 1.0 - cp  # L+ R-(pi/2) S- R- (8.10)
    rho = np.hypot(eta, xi)
    t = np.arctan2(xi, -eta)
    u = 2.0 - rho
    v = _mod2pi(t + _HALF_PI - phi)
    ok = (rho >= 2.0) & (t >= -_ZERO) & (u <= _ZERO) & (v <= _ZERO)
    return np.minimum(a, np.where(ok, np.abs(t) + np.abs(u) + np.abs(v), np.inf)) + _HALF_PI


def _ccscc(
    x: np.ndarray, y: np.ndarray, phi: np.ndarray, sp: np.ndarray, cp: np.ndarray
) -> np.ndarray:
    xi, eta = x + sp, y - 1.0 - cp  # L+ R-(pi/2) S- L-(pi/2) R+ (8.11)
    rho2 = xi * xi + eta * eta
    u = 4.0 - np.sqrt(np.maximum(rho2 - 4.0, 0.0))
    t = _mod2pi(np.arctan2((4.0 - u) * xi - 2.0 * eta, -2.0 * xi + (u - 4.0) * eta))
    v = _mod2pi(t - phi)
    ok = (rho2 >= 4.0) & (u <= _ZERO) & (t >= -_ZERO) & (v >= -_ZERO)
    return np.where(ok, np.abs(t) + np.abs(u) + np.abs(v), np.inf) + _PI


def shortest_lengths(x: np.ndarray, y: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Shortest Reeds-Shepp lengths at radius 1 to goals ``(x, y, phi)`` in the start frame.

    Parameters
    ----------
    x, y, phi : numpy.ndarray
        Goal positions (in turning radii) and headings relative to the start, of one
        shape (broadcast).

    Returns
    -------
    numpy.ndarray
        The lengths, the same as :func:`~rrtdrive.planning.reeds_shepp_words.shortest_length`
        element by element.

    Examples
    --------
    >>> shortest_lengths(np.array([2.0, -0.5]), np.zeros(2), np.zeros(2)).tolist()
    [2.0, 0.5]
    """
    x, y, phi = (np.array(a, dtype=float) for a in np.broadcast_arrays(x, y, phi))
    y[np.abs(y) <= _SNAP] = 0.0
    phi[np.abs(_mod2pi(phi)) <= _SNAP] = 0.0
    sp, cp = np.sin(phi), np.cos(phi)
    xb, yb = x * cp + y * sp, x * sp - y * cp
    best = np.full(x.shape, np.inf)
    for px, py, back in ((x, y, False), (xb, yb, True)):
        # timeflip (-x, y, -phi), reflect (x, -y, -phi), both (-x, -y, phi)
        for gx, gy, mirrored in ((px, py, 1), (-px, py, -1), (px, -py, -1), (-px, -py, 1)):
            args = (gx, gy, mirrored * phi, mirrored * sp, cp)
            families = (_ccc, _ccsc) if back else (_csc, _ccc, _cccc, _ccsc, _ccscc)
            for family in families:
                np.minimum(best, family(*args), out=best)
    return best


@dataclass(frozen=True, eq=False)
class ReedsSheppTable:
    """Shortest Reeds-Shepp lengths on a grid of relative goal poses.

    Build with :meth:`build` (or the cached :func:`reeds_shepp_table`).

    Attributes
    ----------
    radius : float
        Turning radius in metres.
    extent : float
        The grid covers ``|dx|, |dy| <= extent`` metres in the start frame.
    resolution : float
        Grid spacing of ``dx`` and ``dy`` in metres.
    yaw_bins : int
        Number of heading samples over a full turn.
    values : numpy.ndarray
        Lengths in metres, shape ``(nx, ny, yaw_bins)`` for ``dx = i * resolution``,
        ``dy = j * resolution`` (``i, j >= 0``), ``dyaw = k * 2 pi / yaw_bins``.
    max_error : float
        Largest difference to the exact length over random poses inside the grid
        (measured by :meth:`build`), in metres.
    """

    radius: float
    extent: float
    resolution: float
    yaw_bins: int
    values: np.ndarray
    max_error: float

    @classmethod
    def build(
        cls,
        radius: float,
        extent: float = 24.0,
        resolution: float = 0.5,
        yaw_bins: int = 72,
        seed: int = 0,
    ) -> ReedsSheppTable:
        """Compute the grid and measure its interpolation error on 2000 seeded poses.

        Examples
        --------
        >>> table = ReedsSheppTable.build(2.0, extent=4.0, resolution=0.5, yaw_bins=16)
        >>> table.values.shape
        (9, 9, 16)
        """
        require_positive("radius", radius)
        require_positive("extent", extent)
        require_positive("resolution", resolution)
        require_int("yaw_bins", yaw_bins, minimum=4)
        n = int(math.floor(extent / resolution + 1e-9)) + 1
        axis = np.arange(n) * (resolution / radius)
        gx, gy, gyaw = np.meshgrid(
            axis, axis, np.arange(yaw_bins) * (_TWO_PI / yaw_bins), indexing="ij"
        )
        values = shortest_lengths(gx, gy, gyaw) * radius
        values.setflags(write=False)
        table = cls(radius, (n - 1) * resolution, resolution, yaw_bins, values, math.nan)
        rng = np.random.default_rng(seed)
        q = rng.uniform(-table.extent, table.extent, (2000, 2))
        yaw = rng.uniform(-_PI, _PI, 2000)
        exact = shortest_lengths(q[:, 0] / radius, q[:, 1] / radius, yaw) * radius
        error = float(np.max(np.abs(table.lookup(q[:, 0], q[:, 1], yaw) - exact)))
        object.__setattr__(table, "max_error", error)
        return table

    def lookup(self, dx: np.ndarray, dy: np.ndarray, dyaw: np.ndarray) -> np.ndarray:
        """Interpolated lengths to goals ``(dx, dy, dyaw)`` in the start frame (metres).

        Goals outside the grid get the exact length (:func:`shortest_lengths`).
        """
        dx, dy, dyaw = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (dx, dy, dyaw)))
        # Reflect (dy < 0) and timeflip (dx < 0) each negate the heading.
        sign = np.where((dx < 0) != (dy < 0), -1.0, 1.0)
        ax, ay = np.abs(dx) / self.resolution, np.abs(dy) / self.resolution
        ak = np.mod(sign * dyaw, _TWO_PI) / (_TWO_PI / self.yaw_bins)
        n = self.values.shape[0]
        inside = (ax <= n - 1) & (ay <= n - 1)
        i0 = np.minimum(np.floor(ax), n - 2).astype(int)
        j0 = np.minimum(np.floor(ay), n - 2).astype(int)
        k0 = np.floor(ak).astype(int) % self.yaw_bins
        fx, fy, fk = ax - i0, ay - j0, ak - np.floor(ak)
        i0, j0 = np.where(inside, i0, 0), np.where(inside, j0, 0)
        k1 = (k0 + 1) % self.yaw_bins
        v = self.values
        out = np.zeros(dx.shape)
        for di, wx in ((0, 1.0 - fx), (1, fx)):
            for dj, wy in ((0, 1.0 - fy), (1, fy)):
                out += (
                    wx * wy * ((1.0 - fk) * v[i0 + di, j0 + dj, k0] + fk * v[i0 + di, j0 + dj, k1])
                )
        if not np.all(inside):
            far = ~inside
            c = self.radius
            out[far] = shortest_lengths(dx[far] / c, dy[far] / c, dyaw[far]) * c
        return out

    def distance(self, start: Pose, goal: Pose) -> float:
        """The interpolated length from ``start`` to ``goal`` (exact outside the grid).

        Scalar Python (no numpy call), for one pose at a time.

        Examples
        --------
        >>> table = reeds_shepp_table(2.0, extent=4.0, resolution=0.5, yaw_bins=16)
        >>> round(table.distance(Pose(1.0, 1.0, 0.0), Pose(3.0, 1.0, 0.0)), 6)
        2.0
        """
        c, s = math.cos(start.yaw), math.sin(start.yaw)
        dx, dy = goal.x - start.x, goal.y - start.y
        lx, ly = c * dx + s * dy, c * dy - s * dx
        phi = goal.yaw - start.yaw
        if (lx < 0) != (ly < 0):
            phi = -phi
        res = self.resolution
        ax, ay = abs(lx) / res, abs(ly) / res
        n = self.values.shape[0]
        if ax > n - 1 or ay > n - 1:
            return reeds_shepp_distance(start, goal, self.radius)
        bins = self.yaw_bins
        ak = (phi % _TWO_PI) * (bins / _TWO_PI)
        i, j, k = min(int(ax), n - 2), min(int(ay), n - 2), int(ak)
        fx, fy, fk = ax - i, ay - j, ak - k
        k %= bins
        k1 = (k + 1) % bins
        flat, sj, si = self._flat, bins, bins * n
        out = 0.0
        for di, wx in ((0, 1.0 - fx), (1, fx)):
            for dj, wy in ((0, 1.0 - fy), (1, fy)):
                base = (i + di) * si + (j + dj) * sj
                out += wx * wy * ((1.0 - fk) * flat[base + k] + fk * flat[base + k1])
        return out

    @functools.cached_property
    def _flat(self) -> memoryview:
        # A memoryview reads one float in tens of nanoseconds, a numpy index in ~100.
        return memoryview(np.ascontiguousarray(self.values).ravel())


@functools.lru_cache(maxsize=8)
def reeds_shepp_table(
    radius: float, extent: float = 24.0, resolution: float = 0.5, yaw_bins: int = 72
) -> ReedsSheppTable:
    """:meth:`ReedsSheppTable.build`, cached per argument tuple (built once per process)."""
    return ReedsSheppTable.build(radius, extent, resolution, yaw_bins)
