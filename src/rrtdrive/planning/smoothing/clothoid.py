"""Symmetric clothoid turns: a polygon corner rounded with continuous curvature.

A turn of deflection ``theta`` starts on the incoming leg with ``kappa = 0``, raises
the curvature linearly with arc length (a clothoid of sharpness ``sigma = dkappa/ds``)
to the arc's ``kappa``, runs along the arc and lowers it again symmetrically
(clothoid-arc-clothoid); when the two clothoids alone turn by ``theta`` before
reaching ``kappa`` it is clothoid-clothoid with the peak ``sqrt(theta sigma)``.
Positions are exact: the clothoid is the Fresnel integral
(``scipy.special.fresnel``), the arc closed form, the second half the mirror image
of the first in the corner's bisector.

The steering angle is ``delta = atan(L kappa)``, so along a clothoid
``|d delta / ds| = L sigma / (1 + L^2 kappa^2)``: its largest value on the turn is
``L sigma``, at the ends where ``kappa = 0`` (see :func:`sharpness_levels`).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from scipy.special import fresnel

__all__ = [
    "ClothoidTurn",
    "clothoid_turn",
    "clothoid_turns",
    "turn_tangent",
    "turn_circle",
    "sample_turn",
    "sharpness_levels",
]


class ClothoidTurn(NamedTuple):
    """A symmetric turn in its own frame (see :func:`clothoid_turn`).

    Attributes
    ----------
    theta : float
        Deflection in radians, signed (positive: left).
    sigma : float
        Sharpness ``|dkappa/ds|`` of the clothoids in 1/m^2.
    kappa : float
        Largest ``|kappa|`` reached (the arc's, or the clothoid-clothoid peak).
    clothoid : float
        Length of each clothoid in metres.
    arc : float
        Length of the arc in metres (0 for clothoid-clothoid).
    tangent : float
        Distance from the corner to the turn's start and end along the legs.
    """

    theta: float
    sigma: float
    kappa: float
    clothoid: float
    arc: float
    tangent: float

    @property
    def length(self) -> float:
        """Arc length of the whole turn in metres."""
        return 2.0 * self.clothoid + self.arc


def _clothoid_xy(s: np.ndarray, sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Position on the clothoid ``kappa = sigma s`` from the origin heading along x."""
    a = math.sqrt(math.pi / sigma)
    sf, cf = fresnel(np.asarray(s, dtype=float) / a)
    return a * cf, a * sf


@functools.lru_cache(maxsize=4096)
def _clothoid_end(lc: float, sigma: float) -> tuple[float, float]:
    """``_clothoid_xy(np.array(lc), sigma)`` as floats, remembered: a query's turns share a few."""
    xc, yc = _clothoid_xy(np.array(lc), sigma)
    return float(xc), float(yc)


def clothoid_turn(theta: float, kappa: float, sigma: float) -> ClothoidTurn:
    """The symmetric turn of deflection ``theta``, arc curvature ``kappa``, sharpness ``sigma``.

    Parameters
    ----------
    theta : float
        Deflection in radians, ``|theta| < pi``; its sign is the turn's direction.
    kappa : float
        Curvature of the arc (> 0), the largest the turn may reach.
    sigma : float
        Sharpness of the clothoids (> 0), in 1/m^2.

    Returns
    -------
    ClothoidTurn

    Examples
    --------
    >>> t = clothoid_turn(math.pi / 2, 1 / 6, 0.08)
    >>> round(t.clothoid, 4), round(t.kappa, 4), round(t.tangent, 3)
    (2.0833, 0.1667, 7.071)
    """
    th = abs(float(theta))
    if th < 1e-12:
        return ClothoidTurn(float(theta), sigma, 0.0, 0.0, 0.0, 0.0)
    if th >= math.pi - 1e-9:
        return ClothoidTurn(float(theta), sigma, kappa, math.inf, 0.0, math.inf)
    if kappa * kappa / sigma >= th:  # the clothoids alone turn far enough
        peak, lc, arc = math.sqrt(th * sigma), math.sqrt(th / sigma), 0.0
    else:
        peak, lc = kappa, kappa / sigma
        arc = (th - kappa * lc) / kappa
    xc, yc = _clothoid_end(lc, sigma)
    phi = 0.5 * peak * lc
    half = 0.5 * th
    if arc > 0.0:
        xm = xc + (math.sin(half) - math.sin(phi)) / peak
        ym = yc - (math.cos(half) - math.cos(phi)) / peak
    else:
        xm, ym = xc, yc
    # The turn's midpoint lies on the corner's bisector: the corner is where the
    # incoming leg (the x axis) meets the line through it at the heading theta/2 + pi/2.
    tangent = xm + ym * math.tan(half)
    return ClothoidTurn(float(theta), sigma, peak, lc, arc, tangent)


def clothoid_turns(theta: float, kappa: np.ndarray, sigma: np.ndarray) -> list[ClothoidTurn]:
    """:func:`clothoid_turn` for many ``(kappa, sigma)`` pairs at once (one Fresnel call).

    Examples
    --------
    >>> many = clothoid_turns(1.0, np.array([1 / 6, 0.1]), np.array([0.08, 0.02]))
    >>> [round(t.tangent, 9) for t in many] == [
    ...     round(clothoid_turn(1.0, 1 / 6, 0.08).tangent, 9),
    ...     round(clothoid_turn(1.0, 0.1, 0.02).tangent, 9)]
    True
    """
    th = abs(float(theta))
    k = np.asarray(kappa, dtype=float)
    sg = np.asarray(sigma, dtype=float)
    if th < 1e-12 or th >= math.pi - 1e-9:
        return [clothoid_turn(theta, float(a), float(b)) for a, b in zip(k, sg, strict=True)]
    cc = k * k / sg >= th  # clothoid-clothoid
    peak = np.where(cc, np.sqrt(th * sg), k)
    lc = np.where(cc, np.sqrt(th / sg), k / sg)
    arc = np.where(cc, 0.0, (th - k * lc) / k)
    a = np.sqrt(math.pi / sg)
    sf, cf = fresnel(lc / a)
    xc, yc = a * cf, a * sf
    phi = 0.5 * peak * lc
    half = 0.5 * th
    xm = np.where(cc, xc, xc + (math.sin(half) - np.sin(phi)) / peak)
    ym = np.where(cc, yc, yc - (math.cos(half) - np.cos(phi)) / peak)
    tangent = xm + ym * math.tan(half)
    t = float(theta)
    return [
        ClothoidTurn(t, *row)
        for row in zip(sg.tolist(), peak.tolist(), lc.tolist(), arc.tolist(), tangent.tolist(),
                       strict=True)
    ]  # fmt: skip


def turn_tangent(theta: float, kappa: float, sigma: float) -> float:
    """Distance from the corner to the start of :func:`clothoid_turn` (``inf`` for a reversal).

    Examples
    --------
    >>> round(turn_tangent(math.pi / 2, 1 / 6, 0.08), 3), turn_tangent(0.0, 1 / 6, 0.08)
    (7.071, 0.0)
    """
    return clothoid_turn(theta, kappa, sigma).tangent


def turn_circle(kappa: float, sigma: float) -> tuple[float, float]:
    """The circle a clothoid-arc-clothoid turn is equivalent to: ``(r_in, d)``.

    The arc's centre lies ``d`` along the incoming leg from the turn's start and
    ``r_in`` beside it (Fraichard & Scheuer's inner circle), so a turn of
    deflection ``theta >= kappa^2 / sigma`` has the tangent length
    ``r_in tan(theta / 2) + d``: the turn is the arc of radius ``r_in`` tangent to
    both legs, lengthened by ``d`` at either end.

    Examples
    --------
    >>> r_in, d = turn_circle(1 / 6, 0.08)
    >>> t = clothoid_turn(math.pi / 2, 1 / 6, 0.08)
    >>> round(r_in * math.tan(math.pi / 4) + d - t.tangent, 12)
    0.0
    """
    lc = kappa / sigma
    xc, yc = (float(v) for v in _clothoid_xy(np.array(lc), sigma))
    phi = 0.5 * kappa * lc
    return yc + math.cos(phi) / kappa, xc - math.sin(phi) / kappa


def sample_turn(turn: ClothoidTurn, s: np.ndarray) -> np.ndarray:
    """Rows ``[x, y, yaw, kappa]`` at arc lengths ``s`` in the turn's frame.

    The frame: the turn starts at the origin heading along +x, the corner is at
    ``(tangent, 0)``. Values of ``s`` lie in ``[0, turn.length]``.

    Parameters
    ----------
    turn : ClothoidTurn
        The turn (:func:`clothoid_turn`).
    s : numpy.ndarray
        Arc lengths from the turn's start, metres (flattened to ``(N,)``).

    Returns
    -------
    numpy.ndarray
        ``(N, 4)`` rows ``x, y, yaw, kappa`` (metres, radians, 1/m).

    Examples
    --------
    >>> t = clothoid_turn(math.pi / 2, 1 / 6, 0.08)
    >>> end = sample_turn(t, np.array([t.length]))[0]
    >>> np.round(end, 6).tolist() == [round(t.tangent, 6), round(t.tangent, 6),
    ...                                round(math.pi / 2, 6), 0.0]
    True
    """
    s = np.asarray(s, dtype=float).reshape(-1)
    th = abs(turn.theta)
    sign = 1.0 if turn.theta >= 0.0 else -1.0
    out = np.zeros((len(s), 4))
    if th < 1e-12:
        out[:, 0] = s
        return out
    total = turn.length
    half_len = 0.5 * total
    first = s <= half_len
    # The first half at q = s (first) or q = total - s (mirrored).
    q = np.where(first, s, total - s)
    x = np.empty_like(q)
    y = np.empty_like(q)
    yaw = np.empty_like(q)
    kap = np.empty_like(q)
    lc, sig, k = turn.clothoid, turn.sigma, turn.kappa
    on_clo = q <= lc
    xs, ys = _clothoid_xy(q[on_clo], sig)
    x[on_clo], y[on_clo] = xs, ys
    yaw[on_clo] = 0.5 * sig * q[on_clo] ** 2
    kap[on_clo] = sig * q[on_clo]
    on_arc = ~on_clo
    if np.any(on_arc):
        xc, yc = (float(v) for v in _clothoid_xy(np.array(lc), sig))
        phi = 0.5 * k * lc
        ang = phi + k * (q[on_arc] - lc)
        x[on_arc] = xc + (np.sin(ang) - math.sin(phi)) / k
        y[on_arc] = yc - (np.cos(ang) - math.cos(phi)) / k
        yaw[on_arc] = ang
        kap[on_arc] = k
    # Mirror the second half in the bisector through the corner (tangent, 0).
    m = ~first
    if np.any(m):
        d = np.array([-math.sin(0.5 * th), math.cos(0.5 * th)])
        rx, ry = x[m] - turn.tangent, y[m]
        proj = rx * d[0] + ry * d[1]
        x[m] = turn.tangent + 2.0 * proj * d[0] - rx
        y[m] = 2.0 * proj * d[1] - ry
        yaw[m] = th - yaw[m]
    out[:, 0] = x
    out[:, 1] = sign * y
    out[:, 2] = sign * yaw
    out[:, 3] = sign * kap
    return out


def sharpness_levels(bound: float, floor: float, wheelbase: float, margin: float) -> np.ndarray:
    """Clothoid sharpnesses ``sigma`` to choose from, tightest first.

    The steering rate per metre of a clothoid is at most ``wheelbase * sigma`` (at
    ``kappa = 0``), so the tightest level is ``margin * bound / wheelbase`` and each
    next one is ``sqrt(2)`` gentler, down to ``floor / wheelbase``.

    Parameters
    ----------
    bound, floor : float
        Largest and smallest ``|d delta / ds|`` wanted, in rad/m.
    wheelbase : float
        ``L`` in metres.
    margin : float
        Design margin in ``(0, 1]`` on the bound.

    Examples
    --------
    >>> np.round(sharpness_levels(0.2, 0.05, 2.5, 1.0) * 2.5, 4).tolist()
    [0.2, 0.1414, 0.1, 0.0707, 0.05]
    """
    top = margin * bound
    low = min(floor, top)
    levels = [top]
    while levels[-1] / math.sqrt(2.0) > low * (1.0 + 1e-9):
        levels.append(levels[-1] / math.sqrt(2.0))
    if levels[-1] > low * (1.0 + 1e-9):
        levels.append(low)
    return np.array(levels) / wheelbase
