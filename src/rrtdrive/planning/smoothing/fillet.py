"""Fillets: control points that round a polygon corner with bounded curvature."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

__all__ = ["Fillet", "fillet_points", "outer_reach"]


class Fillet(NamedTuple):
    """Control points that round one polygon corner (see :func:`fillet_points`).

    Attributes
    ----------
    vertices : numpy.ndarray
        ``(m, 2)`` vertices of the polygon circumscribing the arc.
    tangent : float
        Distance from the corner to the arc's tangent points, ``R tan(theta/2)``.
    half : float
        Half the side of the circumscribing polygon, ``R tan(phi/2)``.
    """

    vertices: np.ndarray
    tangent: float
    half: float

    @property
    def reach(self) -> float:
        """Distance from the corner to each guard point, ``tangent + half``."""
        return self.tangent + self.half


def fillet_points(
    corner: Sequence[float] | np.ndarray,
    u_in: Sequence[float] | np.ndarray,
    u_out: Sequence[float] | np.ndarray,
    radius: float,
    max_angle: float = math.radians(10.0),
) -> Fillet:
    """Control points that turn a polygon corner into a curvature-bounded quadratic B-spline piece.

    The corner's deflection ``theta`` is split into ``m = ceil(theta / max_angle)``
    equal turns ``phi``; the vertices circumscribe the arc of ``radius`` tangent to
    both legs. Add one guard point on each leg at :attr:`Fillet.reach` from the
    corner; a degree-2 clamped uniform B-spline then runs straight along the
    incoming leg up to the tangent point, through ``m`` parabolic pieces, each with
    ``max |kappa| = 1 / (R cos(phi/2))`` (:func:`quadratic_span_max_curvature`),
    and straight along the outgoing leg. A straight corner gives the corner alone
    with ``tangent = half = 0``; a reversal gives ``tangent = inf``.

    Parameters
    ----------
    corner : sequence of float
        The corner ``(x, y)``.
    u_in, u_out : sequence of float
        Unit directions of the incoming and outgoing legs (driving direction).
    radius : float
        Arc radius ``R`` in metres.
    max_angle : float
        Largest turn per vertex in radians.

    Returns
    -------
    Fillet

    Examples
    --------
    >>> f = fillet_points((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), 6.0, math.radians(30.0))
    >>> len(f.vertices), round(f.tangent, 3), round(f.reach, 3)
    (3, 6.0, 7.608)
    """
    cx, cy = float(corner[0]), float(corner[1])
    ax, ay = float(u_in[0]), float(u_in[1])
    bx, by = float(u_out[0]), float(u_out[1])
    cross = ax * by - ay * bx
    dot = ax * bx + ay * by
    theta = math.atan2(abs(cross), dot)
    if theta < 1e-9:
        return Fillet(np.array([[cx, cy]]), 0.0, 0.0)
    if theta > math.pi - 1e-6:
        return Fillet(np.array([[cx, cy]]), math.inf, 0.0)
    m = max(1, math.ceil(theta / max_angle - 1e-9))
    phi = theta / m
    sign = 1.0 if cross > 0 else -1.0
    half = radius * math.tan(phi / 2.0)
    tangent = radius * math.tan(theta / 2.0)
    verts = np.empty((m, 2))
    vx, vy = cx - (tangent - half) * ax, cy - (tangent - half) * ay
    verts[0] = (vx, vy)
    heading = math.atan2(ay, ax)
    for j in range(1, m):
        heading += sign * phi
        vx += 2.0 * half * math.cos(heading)
        vy += 2.0 * half * math.sin(heading)
        verts[j] = (vx, vy)
    # The last vertex lies on the outgoing leg; snap it there against rounding.
    verts[m - 1] = (cx + (tangent - half) * bx, cy + (tangent - half) * by)
    return Fillet(verts, tangent, half)


def outer_reach(fillet: Fillet, degree: int) -> float:
    """Distance from a corner to its outermost guard point.

    One guard per side for degree 2, two for degree 3 (a cubic piece spans four
    control points).

    Examples
    --------
    >>> f = fillet_points((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), 6.0, math.radians(30.0))
    >>> round(outer_reach(f, 2), 3), round(outer_reach(f, 3), 3)
    (7.608, 10.823)
    """
    return fillet.reach + 2.0 * fillet.half * (degree - 2)
