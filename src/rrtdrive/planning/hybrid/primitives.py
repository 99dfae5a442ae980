"""Motion primitives of the Hybrid A* search: arcs of constant steering, forward and reverse.

A primitive drives ``length`` metres of arc with steering curvature ``kappa``
(``tan(delta) / L``) in ``gear`` (+1 forward, -1 reverse). The nose yaw turns by
``gear * kappa * s`` after ``s`` metres, and the rear axle moves along
``gear * (cos yaw, sin yaw)``: a reverse arc is the forward arc with the same
steering driven backwards in time. Poses are closed-form on the arc.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["PrimitiveSet", "arc_poses", "primitive_sets"]


def arc_poses(x: float, y: float, yaw: float, kappa: float, gear: int, s: np.ndarray) -> np.ndarray:
    """Poses ``(len(s), 3)`` after driving arc lengths ``s`` from ``(x, y, yaw)``.

    Parameters
    ----------
    x, y, yaw : float
        Rear-axle pose at the arc's start; ``yaw`` is where the nose points.
    kappa : float
        Steering curvature (positive: the wheels turned left).
    gear : int
        +1 forward, -1 reverse.
    s : numpy.ndarray
        Arc lengths driven, metres (>= 0).

    Returns
    -------
    numpy.ndarray
        Rows ``[x, y, yaw]`` (yaw unwrapped).

    Examples
    --------
    >>> arc_poses(0.0, 0.0, 0.0, 0.0, -1, np.array([2.0])).round(6)
    array([[-2.,  0.,  0.]])
    >>> p = arc_poses(0.0, 0.0, 0.0, 0.5, 1, np.array([math.pi]))
    >>> p.round(6)
    array([[2.      , 2.      , 1.570796]])
    """
    s = np.asarray(s, dtype=float)
    yaws = yaw + gear * kappa * s
    if abs(kappa) < 1e-12:
        return np.column_stack([x + gear * s * math.cos(yaw), y + gear * s * math.sin(yaw), yaws])
    xs = x + (np.sin(yaws) - math.sin(yaw)) / kappa
    ys = y - (np.cos(yaws) - math.cos(yaw)) / kappa
    return np.column_stack([xs, ys, yaws])


@dataclass(frozen=True, eq=False)
class PrimitiveSet:
    """The primitives of one search, in the frame of a pose at the origin heading +x.

    Attributes
    ----------
    kappas, gears : numpy.ndarray
        Steering curvature and gear of each primitive, shape ``(P,)``.
    local : numpy.ndarray
        ``(P, n, 3)`` poses ``[x, y, dyaw]`` along each primitive at arc lengths
        ``length * k / n`` for ``k = 1..n`` (the last row: its end pose).
    length : float
        Arc length of every primitive, metres.
    """

    kappas: np.ndarray
    gears: np.ndarray
    local: np.ndarray
    length: float

    @classmethod
    def build(
        cls, kappa_max: float, count: int, length: float, spacing: float, reverse: bool
    ) -> PrimitiveSet:
        """``count`` curvatures over ``[-kappa_max, kappa_max]``, forward (and reverse).

        Parameters
        ----------
        kappa_max : float
            Largest steering curvature of the primitives.
        count : int
            Number of curvatures (odd).
        length : float
            Arc length of each primitive.
        spacing : float
            Largest gap between the poses of a primitive (the body-test spacing).
        reverse : bool
            Whether reverse primitives are included.

        Examples
        --------
        >>> ps = PrimitiveSet.build(1 / 6, 3, 1.0, 0.1, reverse=True)
        >>> ps.kappas.round(4).tolist(), ps.gears.tolist(), ps.local.shape
        ([-0.1667, 0.0, 0.1667, -0.1667, 0.0, 0.1667], [1, 1, 1, -1, -1, -1], (6, 10, 3))
        """
        ks = np.linspace(-kappa_max, kappa_max, count) if count > 1 else np.zeros(1)
        gears = (1, -1) if reverse else (1,)
        n = max(1, math.ceil(length / spacing - 1e-9))
        s = length * np.arange(1, n + 1) / n
        kappas, gs, local = [], [], []
        for g in gears:
            for k in ks:
                kappas.append(float(k))
                gs.append(g)
                local.append(arc_poses(0.0, 0.0, 0.0, float(k), g, s))
        return cls(np.array(kappas), np.array(gs, dtype=np.int64), np.array(local), float(length))

    def scaled(self, factor: float) -> PrimitiveSet:
        """The same curvatures and gears, each primitive ``factor`` times as long.

        Its poses keep at most the spacing of these (``length / poses per primitive``).

        Parameters
        ----------
        factor : float
            Ratio of the new arc length to :attr:`length`.

        Returns
        -------
        PrimitiveSet
        """
        length = self.length * factor
        spacing = self.length / self.local.shape[1]
        n = max(1, math.ceil(length / spacing - 1e-9))
        s = length * np.arange(1, n + 1) / n
        pairs = zip(self.kappas.tolist(), self.gears.tolist(), strict=True)
        local = np.array([arc_poses(0.0, 0.0, 0.0, k, g, s) for k, g in pairs])
        return PrimitiveSet(self.kappas.copy(), self.gears.copy(), local.reshape(-1, n, 3), length)

    def __len__(self) -> int:
        return len(self.kappas)

    def gear(self, gear: int) -> PrimitiveSet:
        """The primitives of one gear only.

        Parameters
        ----------
        gear : int
            +1 forward, -1 reverse.

        Returns
        -------
        PrimitiveSet
        """
        keep = self.gears == gear
        return PrimitiveSet(self.kappas[keep], self.gears[keep], self.local[keep], self.length)

    @functools.cached_property
    def rows(self) -> np.ndarray:
        """:attr:`local` as contiguous rows ``(3, P, n)``: x, y and dyaw (:meth:`rows_from`)."""
        return np.ascontiguousarray(self.local.transpose(2, 0, 1))

    def rows_from(
        self, x: float, y: float, yaw: float, keep: Sequence[int] | None = None
    ) -> np.ndarray:
        """:meth:`poses_from` of the primitives ``keep`` (None: all) as rows ``(3, P n)``.

        The same floats: ``x + c lx - s ly`` as ``(lx c + x) - s ly``, and so on
        (commuted operands round alike), in seven array operations.

        Parameters
        ----------
        x, y, yaw : float
            Rear-axle pose the primitives start from (metres, radians).
        keep : sequence of int, optional
            Indices of the primitives (``None``: all).

        Returns
        -------
        numpy.ndarray
            ``(3, P * n)`` rows of x, y and yaw (unwrapped), primitive by primitive.
        """
        c, s = math.cos(yaw), math.sin(yaw)
        loc = self.rows if keep is None else self.rows.take(keep, axis=1)  # contiguous
        lx, ly = loc[0], loc[1]
        out = np.empty(loc.shape)
        np.multiply(lx, c, out=out[0])
        out[0] += x
        out[0] -= s * ly
        np.multiply(lx, s, out=out[1])
        out[1] += y
        out[1] += c * ly
        np.add(loc[2], yaw, out=out[2])
        return out.reshape(3, -1)

    def poses_from(self, x: float, y: float, yaw: float) -> np.ndarray:
        """World poses ``(P, n, 3)`` of every primitive driven from ``(x, y, yaw)``.

        Parameters
        ----------
        x, y, yaw : float
            Rear-axle start pose (metres, radians).

        Returns
        -------
        numpy.ndarray
            ``(P, n, 3)`` rows ``x, y, yaw`` (yaw unwrapped).
        """
        c, s = math.cos(yaw), math.sin(yaw)
        lx, ly = self.local[..., 0], self.local[..., 1]
        out = np.empty_like(self.local)
        out[..., 0] = x + c * lx - s * ly
        out[..., 1] = y + s * lx + c * ly
        out[..., 2] = yaw + self.local[..., 2]
        return out


@functools.lru_cache(maxsize=32)
def primitive_sets(
    kappa_max: float, count: int, length: float, spacing: float, gear: int, long_steps: tuple
) -> tuple[PrimitiveSet, ...]:
    """The search's primitives of one gear (0: both) and their longer copies, built once.

    The first set has arcs of ``length``; then one per factor of ``long_steps``
    (:meth:`PrimitiveSet.scaled`). The sets are shared, their arrays read-only.
    """
    base = PrimitiveSet.build(kappa_max, count, length, spacing, reverse=True)
    if gear:
        base = base.gear(gear)
    sets = (base, *(base.scaled(f) for f in long_steps))
    for one in sets:  # shared by every later query: read-only, so a stray write raises
        for a in (one.kappas, one.gears, one.local):
            a.setflags(write=False)
    return sets
