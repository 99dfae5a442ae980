"""The clamped uniform B-spline: knots, fitting, curvature and sampling (paper Sec. 3.2.2).

Eqs. 13–15. :func:`quadratic_span_max_curvature` gives the exact largest
curvature of each piece of a quadratic curve; :func:`parameter_grid` bounds the
arc length between samples.
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy.interpolate import BSpline

__all__ = [
    "clamped_uniform_knots",
    "fit_bspline",
    "curvature",
    "spline_curvature",
    "quadratic_span_max_curvature",
    "parameter_grid",
    "sample_spline",
]

# ----------------------------------------------------------------------------- B-spline


def clamped_uniform_knots(n_ctrl: int, degree: int) -> np.ndarray:
    """The knot vector of Eq. 15: ends repeated ``k + 1`` times, uniform interior on [0, 1].

    Parameters
    ----------
    n_ctrl : int
        Number of control points ``n + 1``; must exceed ``degree``.
    degree : int
        Spline degree ``k``.

    Returns
    -------
    numpy.ndarray
        ``n_ctrl + degree + 1`` knots.

    Examples
    --------
    >>> clamped_uniform_knots(5, 2).tolist()
    [0.0, 0.0, 0.0, 0.3333333333333333, 0.6666666666666666, 1.0, 1.0, 1.0]
    """
    if n_ctrl <= degree:
        raise ValueError(f"a degree-{degree} B-spline needs more than {degree} control points")
    interior = np.arange(1, n_ctrl - degree) / (n_ctrl - degree)
    return np.concatenate([np.zeros(degree + 1), interior, np.ones(degree + 1)])


def fit_bspline(control_points: np.ndarray, degree: int = 2) -> BSpline:
    """The clamped uniform B-spline with the given control points (Eqs. 13–15).

    Parameters
    ----------
    control_points : numpy.ndarray
        ``(M, 2)`` control points in metres, ``M > degree``.
    degree : int
        Spline degree ``k``.

    Returns
    -------
    scipy.interpolate.BSpline
        Parametrised on ``[0, 1]``, from the first control point to the last.

    Raises
    ------
    ValueError
        When there are no more control points than ``degree`` (:func:`clamped_uniform_knots`).

    Examples
    --------
    >>> spl = fit_bspline(np.array([[0.0, 0.0], [5.0, 0.0], [5.0, 5.0]]))
    >>> spl(0.0).tolist(), spl(1.0).tolist()
    ([0.0, 0.0], [5.0, 5.0])
    """
    c = np.ascontiguousarray(np.asarray(control_points, dtype=float).reshape(-1, 2))
    # The knots are valid by construction (clamped_uniform_knots raises for too few
    # control points), so scipy's checks are skipped.
    return BSpline.construct_fast(clamped_uniform_knots(len(c), degree), c, degree)


def curvature(d1: np.ndarray, d2: np.ndarray) -> np.ndarray:
    """Signed curvature ``(x'y'' - y'x'') / (x'^2 + y'^2)^1.5`` from first and second derivatives.

    Parameters
    ----------
    d1, d2 : numpy.ndarray
        ``(N, 2)`` first and second derivatives of a planar curve.

    Returns
    -------
    numpy.ndarray
        ``(N,)`` curvature (positive: turning left); ``inf`` where ``d1`` vanishes.

    Examples
    --------
    >>> t = np.array([0.3])
    >>> d1 = np.column_stack([-2 * np.sin(t), 2 * np.cos(t)])   # circle of radius 2
    >>> d2 = np.column_stack([-2 * np.cos(t), -2 * np.sin(t)])
    >>> curvature(d1, d2).round(12).tolist()
    [0.5]
    """
    d1 = np.asarray(d1, dtype=float).reshape(-1, 2)
    d2 = np.asarray(d2, dtype=float).reshape(-1, 2)
    cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    speed2 = d1[:, 0] ** 2 + d1[:, 1] ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        k = cross / speed2**1.5
    return np.where(speed2 > 0.0, k, np.inf)


def spline_curvature(spline: BSpline, u: np.ndarray) -> np.ndarray:
    """Curvature of a planar spline at parameters ``u`` (see :func:`curvature`).

    Parameters
    ----------
    spline : scipy.interpolate.BSpline
        A planar spline of degree >= 2.
    u : numpy.ndarray
        ``(N,)`` parameters.

    Returns
    -------
    numpy.ndarray
        ``(N,)`` signed curvature, 1/m.
    """
    u = np.asarray(u, dtype=float)
    return curvature(spline(u, nu=1), spline(u, nu=2))


def quadratic_span_max_curvature(control_points: np.ndarray) -> np.ndarray:
    """Exact largest ``|kappa|`` of each span of a clamped uniform quadratic B-spline.

    With a uniform interior knot vector every span is a quadratic Bézier curve
    ``(A, B, C)``: ``(P0, P1, mid(P1, P2))`` first, ``(mid(P_{i-1}, P_i), P_i,
    mid(P_i, P_{i+1}))`` inside and ``(mid(P_{n-2}, P_{n-1}), P_{n-1}, P_n)`` last.
    With ``u = B - A`` and ``v = C - B`` the cross product of the derivatives is
    the constant ``4 u x v``, so the curvature peaks where the speed ``2|(1-t)u +
    t v|`` is least: ``max |kappa| = |u x v| / (2 d^3)`` with ``d`` the distance from
    the origin to the segment ``[u, v]``; ``inf`` where the speed vanishes (a cusp).

    Parameters
    ----------
    control_points : numpy.ndarray
        ``(M, 2)`` with ``M >= 3``.

    Returns
    -------
    numpy.ndarray
        ``(M - 2,)``; span ``j`` belongs to control point ``j + 1``.

    Examples
    --------
    >>> quadratic_span_max_curvature(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])).round(4)
    array([0.1414])
    """
    p = np.asarray(control_points, dtype=float).reshape(-1, 2)
    m = len(p)
    if m < 3:
        return np.zeros(0)
    mid = 0.5 * (p[:-1] + p[1:])
    a = mid[:-1].copy()
    c = mid[1:].copy()
    a[0] = p[0]
    c[-1] = p[-1]
    b = p[1:-1]
    u = b - a
    v = c - b
    cross = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    w = v - u
    ww = np.sum(w * w, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(-np.sum(u * w, axis=1) / ww, 0.0, 1.0)
    t = np.where(ww > 0.0, t, 0.0)
    closest = u + t[:, None] * w
    d = np.hypot(closest[:, 0], closest[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        k = cross / (2.0 * d**3)
    # d = 0: the speed vanishes inside the span, a cusp (e.g. a reversal): not drivable.
    return np.where(d > 1e-12, k, np.inf)


def parameter_grid(spline: BSpline, spacing: float) -> np.ndarray:
    """Parameters at which consecutive points of ``spline`` are at most ``spacing`` apart.

    The derivative of a B-spline is a B-spline of degree ``k - 1`` with control
    points ``Q_i = k (P_{i+1} - P_i) / (t_{i+k+1} - t_{i+1})``, so on each knot span
    the speed is bounded: by the largest ``|Q_i|`` acting on the span (convex hull)
    and, for degree 2, by the linear interpolation of the two ``|Q_i|`` (the
    derivative is linear there). Parameters are placed so that the integral of
    the bound between neighbours is at most ``spacing``, which bounds the arc
    length between them. Both ends are included.

    Parameters
    ----------
    spline : scipy.interpolate.BSpline
        A planar curve (coefficients ``(n, 2)``).
    spacing : float
        Largest arc length between consecutive parameters (m).

    Returns
    -------
    numpy.ndarray
        Sorted parameters, from the start of the domain to its end.

    Examples
    --------
    >>> spl = fit_bspline(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]))
    >>> u = parameter_grid(spl, 0.5)
    >>> bool(np.hypot(*np.diff(spl(u), axis=0).T).max() <= 0.5), u[0], u[-1]
    (True, np.float64(0.0), np.float64(1.0))
    """
    t, c, k = spline.t, np.asarray(spline.c), spline.k
    n = len(c)
    q = k * np.diff(c, axis=0) / (t[k + 1 : n + k] - t[1:n])[:, None]
    qn = np.hypot(q[:, 0], q[:, 1])
    lo, hi = t[k:n], t[k + 1 : n + 1]
    width = hi - lo
    if k == 2:
        a, b = qn[:-1], qn[1:]  # speed bound at either end of each span, linear between
        total = width * 0.5 * (a + b)
    else:
        a = b = sliding_window_view(qn, k).max(axis=1)
        total = width * a
    counts = np.where(width > 0, np.maximum(1, np.ceil(total / spacing)), 0).astype(np.int64)
    owner = np.repeat(np.arange(len(counts)), counts)
    first = np.repeat(np.cumsum(counts) - counts, counts)
    frac = (np.arange(int(counts.sum())) - first) / np.repeat(np.maximum(counts, 1), counts)
    # Invert the bound's integral S(x) = w (a x + (b - a) x^2 / 2) at the fractions of S(1).
    aa, bb, w = a[owner], b[owner], width[owner]
    target = frac * 0.5 * (aa + bb)
    slope = bb - aa
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.where(
            np.abs(slope) > 1e-12 * np.maximum(aa + bb, 1e-300),
            (np.sqrt(np.maximum(aa * aa + 2.0 * slope * target, 0.0)) - aa) / slope,
            frac,
        )
    u = lo[owner] + np.clip(x, 0.0, 1.0) * w
    return np.append(u, t[n])


def sample_spline(spline: BSpline, spacing: float = 0.25) -> tuple[np.ndarray, np.ndarray]:
    """Rows ``[x, y, yaw, kappa]`` along ``spline`` at most ``spacing`` apart, and their parameters.

    Parameters
    ----------
    spline : scipy.interpolate.BSpline
        A planar spline (:func:`fit_bspline`).
    spacing : float
        Largest distance between consecutive rows, metres (:func:`parameter_grid`).

    Returns
    -------
    rows : numpy.ndarray
        ``(N, 4)`` rows ``x, y, yaw, kappa``, both ends included.
    u : numpy.ndarray
        ``(N,)`` their parameters.

    Examples
    --------
    >>> spl = fit_bspline(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]))
    >>> rows, u = sample_spline(spl, 0.25)
    >>> bool(np.all(np.hypot(*np.diff(rows[:, :2], axis=0).T) <= 0.25))
    True
    """
    u = parameter_grid(spline, spacing)
    xy = spline(u)
    d1 = spline(u, nu=1)
    d2 = spline(u, nu=2)
    yaw = np.arctan2(d1[:, 1], d1[:, 0])
    return np.column_stack([xy, yaw, curvature(d1, d2)]), u
