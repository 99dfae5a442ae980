"""Post-processing of a tree path into a drivable B-spline (paper Sec. 3.2; SPEC §3 items 5–9).

The steps are small functions over arrays and a collision checker, so each can
be tested and switched off on its own:

* :func:`prune` – keep the farthest later node with a free edge (Sec. 3.2.1, step 1);
* :func:`repair_sharp_angles` – Eq. 12 with the Douglas–Peucker choice of ``q_t``
  (Sec. 3.2.1, step 2);
* :func:`supplement` – control-point supplement (Sec. 3.2.3, Eq. 16);
* :func:`fit_bspline`, :func:`clamped_uniform_knots`, :func:`sample_spline`,
  :func:`curvature` – the clamped uniform B-spline (Sec. 3.2.2, Eqs. 13–15);
* :func:`fillet_points` – control points of a curvature-bounded corner;
* :func:`make_drivable` – the guarantee of SPEC §3 item 9: headings at both ends,
  ``|kappa| <= kappa_max`` everywhere and an exactly collision-free body, with a
  bounded repair loop that ends in an honest failure rather than an unsafe path.

All points are rear-axle positions; a segment ``a -> b`` is driven with the
heading along it, which is what ``checker.edge_free(a, b)`` tests.

How the guarantee is checked: the curvature of a degree-2 curve exactly, span by
span (:func:`quadratic_span_max_curvature`; a cusp counts as infinite), of a
degree-3 curve on a parameter grid eight times finer than the output; the body
with ``checker.path_free`` at curve poses at most ``check_spacing`` (0.1 m) apart
(:func:`parameter_grid` bounds the arc length between them); and, as a backstop,
the heading may turn by at most ``kappa_max`` times the arc length between
poses. Corners that break a limit are rounded by fillets of radius
``1 / (0.97 kappa_max cos(5 deg))`` (about 6.2 m for the paper's car), then
widened, moved, merged, dropped or un-pruned, each step edge-checked.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import weakref
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple, Protocol

import numpy as np
import shapely
from numpy.lib.stride_tricks import sliding_window_view
from scipy.interpolate import BSpline

from rrtdrive.types import InputError, Pose, require_int, require_positive, wrap_angle

__all__ = [
    "EdgeChecker",
    "PathChecker",
    "prune",
    "is_sharp",
    "sharp_flags",
    "repair_sharp_angles",
    "supplement",
    "clamped_uniform_knots",
    "fit_bspline",
    "curvature",
    "spline_curvature",
    "quadratic_span_max_curvature",
    "parameter_grid",
    "sample_spline",
    "Fillet",
    "fillet_points",
    "SmoothingConfig",
    "SmoothingResult",
    "make_drivable",
]

logger = logging.getLogger(__name__)


class EdgeChecker(Protocol):
    """Anything with the fast edge test of :class:`~rrtdrive.collision.CollisionChecker`."""

    def edge_free(self, a: Sequence[float], b: Sequence[float]) -> bool:
        """True when the car driving straight from ``a`` to ``b`` is clear."""
        ...


class PathChecker(EdgeChecker, Protocol):
    """An edge checker that also has the exact sampled-path test."""

    def path_free(
        self, samples: np.ndarray, spacing: float = 0.1, clearance: float = 0.0
    ) -> tuple[bool, np.ndarray]:
        """Exact body test along ``samples``; returns ``(ok, bad segment indices)``."""
        ...


# ----------------------------------------------------------------------------- pruning


def _turn(ax: float, ay: float, bx: float, by: float) -> float:
    """Deflection in radians between directions ``a`` and ``b`` (0 when either is zero)."""
    return abs(math.atan2(ax * by - ay * bx, ax * bx + ay * by))


def prune(
    points: np.ndarray,
    checker: EdgeChecker,
    keep: Sequence[int] = (),
    *,
    max_turn: float | None = None,
    start_heading: Sequence[float] | None = None,
    end_heading: Sequence[float] | None = None,
) -> np.ndarray | None:
    """Shortcut a polyline: from each kept node jump to the farthest later node with a free edge.

    Paper Sec. 3.2.1, step 1. Starting at the first node, the edge to every later
    node is tried from the last one backwards; the first free one becomes the next
    node, until the last node is reached. Indices in ``keep`` are never skipped
    (each stretch between kept nodes is pruned on its own).

    With ``max_turn`` (beyond the paper) a jump must also not turn the path by more
    than ``max_turn`` at the node it leaves (the direction into the first node is
    ``start_heading``, when given) nor, when it lands on the last node, against
    ``end_heading``; when no free jump keeps to the limit, the farthest free one is
    taken. The post-processor uses it to avoid hairpins that no car can drive.

    Parameters
    ----------
    points : numpy.ndarray
        Polyline ``(N, 2)`` in driving order.
    checker : EdgeChecker
        Provides ``edge_free(a, b)``; if it also has ``blocked_from(a, bs)`` (a
        boolean array, True where the edge ``a -> b`` is proven to collide), those
        edges are skipped without calling ``edge_free``. The result is the same.
    keep : sequence of int, optional
        Indices that must stay (the ends always stay).
    max_turn : float, optional
        Largest turn in radians at a kept node; ``None`` (the paper) for no limit.
    start_heading, end_heading : sequence of float, optional
        Directions into the first and out of the last node, for ``max_turn``.

    Returns
    -------
    numpy.ndarray or None
        Increasing indices into ``points`` whose consecutive edges are all free,
        or ``None`` when some node has no free edge to any later node of its stretch.

    Examples
    --------
    >>> class Open:
    ...     def edge_free(self, a, b):
    ...         return True
    >>> pts = np.array([[0.0, 0.0], [10.0, 0.0], [12.0, 3.0], [10.0, 6.0], [0.0, 6.0]])
    >>> prune(pts, Open()).tolist()
    [0, 4]
    >>> prune(pts, Open(), max_turn=math.radians(60), start_heading=(1.0, 0.0)).tolist()
    [0, 3, 4]
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    n = len(pts)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    if n == 1:
        return np.zeros(1, dtype=np.int64)
    plist = pts.tolist()
    edge_free = checker.edge_free
    screen = getattr(checker, "blocked_from", None)
    anchors = sorted({0, n - 1, *(int(k) for k in keep if 0 <= int(k) < n)})
    out = [0]
    into = tuple(start_heading) if start_heading is not None else (0.0, 0.0)
    for first, last in zip(anchors[:-1], anchors[1:], strict=True):
        i = first
        while i < last:
            a = plist[i]
            # An optional exact screen: edges proven to collide are skipped.
            skip = screen(pts[i], pts[i + 2 : last + 1]) if screen and last > i + 1 else None
            fallback = -1
            for j in range(last, i, -1):
                if skip is not None and j >= i + 2 and skip[j - i - 2]:
                    continue
                if not edge_free(a, plist[j]):
                    continue
                if max_turn is None:
                    break
                if fallback < 0:
                    fallback = j
                dx, dy = plist[j][0] - a[0], plist[j][1] - a[1]
                ok = _turn(into[0], into[1], dx, dy) <= max_turn
                if ok and j == last:
                    # Landing on a kept node: its way on is known (the next kept node).
                    if j == n - 1:
                        after = end_heading
                    else:
                        nxt = anchors[anchors.index(j) + 1]
                        after = (plist[nxt][0] - plist[j][0], plist[nxt][1] - plist[j][1])
                    if after is not None:
                        ok = _turn(dx, dy, after[0], after[1]) <= max_turn
                if ok:
                    break
            else:
                if fallback < 0:
                    return None
                j = fallback
            out.append(j)
            into = (plist[j][0] - a[0], plist[j][1] - a[1])
            i = j
    return np.asarray(out, dtype=np.int64)


# ----------------------------------------------------------------------------- sharp angles


def is_sharp(prev: Sequence[float], point: Sequence[float], nxt: Sequence[float]) -> bool:
    """Eq. 12: the angle at ``point`` is at most 90 degrees (``a + b >= c`` in squared lengths).

    Examples
    --------
    >>> is_sharp((0, 0), (1, 0), (1, 1)), is_sharp((0, 0), (1, 0), (2, 0.5))
    (True, False)
    """
    ax, ay = point[0] - nxt[0], point[1] - nxt[1]
    bx, by = point[0] - prev[0], point[1] - prev[1]
    cx, cy = nxt[0] - prev[0], nxt[1] - prev[1]
    return ax * ax + ay * ay + bx * bx + by * by >= cx * cx + cy * cy


def sharp_flags(points: np.ndarray) -> np.ndarray:
    """Eq. 12 at every interior vertex (vectorised); the two ends are never sharp.

    Examples
    --------
    >>> sharp_flags(np.array([[0, 0], [1, 0], [1, 1], [3, 2]])).tolist()
    [False, True, False, False]
    """
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    out = np.zeros(len(p), dtype=bool)
    if len(p) < 3:
        return out
    a = np.sum((p[1:-1] - p[2:]) ** 2, axis=1)
    b = np.sum((p[1:-1] - p[:-2]) ** 2, axis=1)
    c = np.sum((p[2:] - p[:-2]) ** 2, axis=1)
    out[1:-1] = a + b >= c
    return out


def _segment_distances(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from each point to the segment a-b (the Douglas-Peucker chord distance)."""
    ab = b - a
    denom = float(ab @ ab)
    rel = points - a
    t = np.zeros(len(points)) if denom == 0.0 else np.clip(rel @ ab / denom, 0.0, 1.0)
    return np.hypot(*(rel - t[:, None] * ab).T)


def repair_sharp_angles(raw: np.ndarray, key: np.ndarray, checker: EdgeChecker) -> np.ndarray:
    """Insert raw tree-path nodes next to sharp key points (paper Sec. 3.2.1, step 2; SPEC item 6).

    For each interior key point ``q_i`` from the start towards the goal that is
    sharp by :func:`is_sharp`, the raw nodes strictly between ``q_{i-1}`` and
    ``q_i`` are tried in order of decreasing distance from the segment
    ``q_{i-1} q_i``; a node ``q_t`` is inserted when ``q_{i-1} -> q_t`` and
    ``q_t -> q_i`` are free and the angles at ``q_t`` and at ``q_i`` are obtuse.
    If none fits, the raw nodes between ``q_i`` and ``q_{i+1}`` are tried the same
    way (distance from ``q_i q_{i+1}``, inserted after ``q_i``). If none fits
    either, the point is kept as it is.

    Parameters
    ----------
    raw : numpy.ndarray
        The raw tree path ``(N, 2)``.
    key : numpy.ndarray
        Increasing indices into ``raw`` of the current key points (e.g. from
        :func:`prune`), including both ends.
    checker : EdgeChecker
        Provides ``edge_free(a, b)``.

    Returns
    -------
    numpy.ndarray
        The new increasing key indices.

    Examples
    --------
    >>> class Open:
    ...     def edge_free(self, a, b):
    ...         return True
    >>> raw = np.array([[0, 0], [2, 0], [4, 0.5], [5, 2], [4.5, 4.5], [0, 4]])
    >>> repair_sharp_angles(raw, np.array([0, 3, 5]), Open()).tolist()
    [0, 3, 4, 5]
    """
    raw = np.asarray(raw, dtype=float).reshape(-1, 2)
    idx = [int(k) for k in key]
    edge_free = checker.edge_free
    plist = raw.tolist()
    i = 1
    while i < len(idx) - 1:
        q_prev, q, q_next = plist[idx[i - 1]], plist[idx[i]], plist[idx[i + 1]]
        if not is_sharp(q_prev, q, q_next):
            i += 1
            continue
        inserted = False
        # Nodes between q_{i-1} and q_i, farthest from that segment first.
        cands = np.arange(idx[i - 1] + 1, idx[i])
        if len(cands):
            d = _segment_distances(raw[cands], raw[idx[i - 1]], raw[idx[i]])
            for t in cands[np.argsort(-d, kind="stable")].tolist():
                qt = plist[t]
                if (
                    not is_sharp(q_prev, qt, q)
                    and not is_sharp(qt, q, q_next)
                    and edge_free(q_prev, qt)
                    and edge_free(qt, q)
                ):
                    idx.insert(i, t)
                    i += 1  # q_i moved one place on
                    inserted = True
                    break
        if not inserted:
            cands = np.arange(idx[i] + 1, idx[i + 1])
            if len(cands):
                d = _segment_distances(raw[cands], raw[idx[i]], raw[idx[i + 1]])
                for t in cands[np.argsort(-d, kind="stable")].tolist():
                    qt = plist[t]
                    if (
                        not is_sharp(q_prev, q, qt)
                        and not is_sharp(q, qt, q_next)
                        and edge_free(q, qt)
                        and edge_free(qt, q_next)
                    ):
                        idx.insert(i + 1, t)
                        i += 1  # skip the inserted point: its angle is obtuse
                        break
        i += 1
    return np.asarray(idx, dtype=np.int64)


# ----------------------------------------------------------------------------- supplement


def _fractions(n: float) -> list[float]:
    """Interpolation fractions N, 2N, ... strictly below 1."""
    out = []
    k = 1
    while k * n < 1.0 - 1e-9:
        out.append(k * n)
        k += 1
    return out


def supplement(points: np.ndarray, delta: float = 5.66, n: float = 0.5) -> np.ndarray:
    """Control-point supplement (paper Sec. 3.2.3, Eq. 16).

    Every leg whose squared length is at least ``delta**2`` gets points by linear
    interpolation at the fractions ``N, 2N, ...`` below 1 (for ``N = 0.5``, one
    midpoint). Shorter legs are left alone.

    Parameters
    ----------
    points : numpy.ndarray
        Control polygon ``(M, 2)``.
    delta : float
        Distance threshold in metres (paper: 5.66, the diagonal of a 4 x 4 cell).
    n : float
        Distance multiple in ``(0, 1)`` (paper: 0.5).

    Returns
    -------
    numpy.ndarray
        The supplemented polygon.

    Examples
    --------
    >>> supplement(np.array([[0.0, 0.0], [10.0, 0.0], [12.0, 0.0]])).tolist()
    [[0.0, 0.0], [5.0, 0.0], [10.0, 0.0], [12.0, 0.0]]
    """
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(p) < 2:
        return p.copy()
    fr = np.asarray(_fractions(n))
    out = [p[:1]]
    d2 = np.sum(np.diff(p, axis=0) ** 2, axis=1)
    for i in range(len(p) - 1):
        if d2[i] >= delta * delta and len(fr):
            out.append(p[i] + fr[:, None] * (p[i + 1] - p[i]))
        out.append(p[i + 1 : i + 2])
    return np.concatenate(out)


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
    """Curvature of a planar spline at parameters ``u`` (see :func:`curvature`)."""
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


# ----------------------------------------------------------------------------- fillets


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
    corner: Sequence[float],
    u_in: Sequence[float],
    u_out: Sequence[float],
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


# ----------------------------------------------------------------------------- guarantee


@dataclass(frozen=True)
class SmoothingConfig:
    """Tunables of the post-processor.

    Parameters
    ----------
    kappa_max : float
        Largest admissible curvature in 1/m (the car's ``kappa_max``).
    degree : int
        B-spline degree, 2 (paper) or 3.
    prune, sharp_repair, supplement : bool
        Switch the paper's steps on or off.
    supplement_delta, supplement_n : float
        Eq. 16 threshold ``delta`` (m) and distance multiple ``N``.
    heading_leg : float
        Initial length of the straight legs along the start and goal headings (m);
        they grow when the turn after them needs more room.
    sample_spacing : float
        Largest arc-length gap between output samples (m).
    check_spacing : float
        Largest gap between the poses given to the exact body test (m).
    kappa_safety : float
        Fillets are designed for ``kappa_safety * kappa_max``.
    fillet_max_angle : float
        Largest turn per fillet vertex (radians).
    max_rounds : int
        Largest number of fit-check-repair rounds.
    clearance : float
        Distance the body must keep from obstacles along the curve (exact test).
    """

    kappa_max: float = 1.0 / 6.0
    degree: int = 2
    prune: bool = True
    sharp_repair: bool = True
    supplement: bool = True
    supplement_delta: float = 5.66
    supplement_n: float = 0.5
    heading_leg: float = 5.0
    sample_spacing: float = 0.25
    check_spacing: float = 0.1
    kappa_safety: float = 0.97
    fillet_max_angle: float = math.radians(10.0)
    max_rounds: int = 30
    clearance: float = 0.0

    def __post_init__(self) -> None:
        for name in (
            "kappa_max",
            "supplement_delta",
            "heading_leg",
            "sample_spacing",
            "check_spacing",
        ):
            require_positive(f"smoothing.{name}", getattr(self, name))
        if self.degree not in (2, 3):
            raise InputError(f"smoothing.degree: must be 2 or 3, got {self.degree!r}")
        if not 0.0 < self.supplement_n < 1.0:
            raise InputError(
                f"smoothing.supplement_n: must lie in (0, 1), got {self.supplement_n!r}"
            )
        if not 0.0 < self.kappa_safety <= 1.0:
            raise InputError(
                f"smoothing.kappa_safety: must lie in (0, 1], got {self.kappa_safety!r}"
            )
        if not 0.0 < self.fillet_max_angle <= math.pi / 2:
            raise InputError("smoothing.fillet_max_angle: must lie in (0, pi/2]")
        require_int("smoothing.max_rounds", self.max_rounds)


@dataclass(frozen=True, eq=False)
class SmoothingResult:
    """Outcome of :func:`make_drivable`.

    Attributes
    ----------
    ok : bool
        True when ``samples`` meet every guarantee.
    samples : numpy.ndarray
        ``(N, 4)`` rows ``[x, y, yaw, kappa]`` (empty when not ok).
    control_points : numpy.ndarray
        The final B-spline control points ``(M, 2)``.
    key_points : numpy.ndarray
        The key polygon after pruning, sharp-angle repair, heading legs and repairs.
    rounds : int
        Fit-check rounds used (1 when the first fit passed).
    max_curvature : float
        Largest ``|kappa|`` of the curve (exact per span for degree 2, dense samples for 3).
    message : str
        Why it failed, or an empty string.
    stats : dict
        Counters for the planner's statistics.
    """

    ok: bool
    samples: np.ndarray
    control_points: np.ndarray
    key_points: np.ndarray
    rounds: int
    max_curvature: float
    message: str = ""
    stats: dict[str, float] = field(default_factory=dict)


def _unit(dx: float, dy: float) -> tuple[float, float, float]:
    n = math.hypot(dx, dy)
    if n < 1e-12:
        return 0.0, 0.0, 0.0
    return dx / n, dy / n, n


# Moves tried, in order, for a corner whose rounded piece still collides (or whose
# legs are too short), each from the corner's original place: "back" moves it back
# along its outgoing line (the outgoing straight starts earlier), "ahead" on along
# its incoming line (the incoming straight lasts longer), "behind" back along its
# incoming line (the turn starts earlier), "out"/"in" along the bisector. Heading-leg corners move
# only along their ray (the start's ahead, the goal's back).
_MOVES: tuple[tuple[str, float], ...] = (
    ("back", 1.5), ("ahead", 1.5), ("behind", 2.0), ("out", 1.0),
    ("back", 3.0), ("ahead", 3.0), ("behind", 4.0), ("out", 2.0),
    ("back", 5.0), ("ahead", 5.0), ("behind", 7.0), ("out", 3.5), ("in", 1.0),
    ("back", 8.0), ("ahead", 8.0), ("behind", 10.0), ("back", 12.0), ("ahead", 12.0),
)  # fmt: skip
_RADIUS_STEPS = (1.0, 1.6)
# Turn limit of the hairpin-avoiding pruning (second attempt and un-pruning).
_UNPRUNE_TURN = math.radians(100.0)
# Moving a heading corner or lengthening its leg may not sharpen its turn beyond this.
_HAIRPIN = math.radians(135.0)
_END_GAP = 0.05


_UNIONS: weakref.WeakKeyDictionary[object, shapely.Geometry] = weakref.WeakKeyDictionary()


def _obstacle_union(checker: object) -> shapely.Geometry | None:
    """The prepared union of the checker's obstacles, cached per checker (None if unknown)."""
    obstacles = getattr(checker, "obstacles", None)
    if obstacles is None:
        return None
    try:
        union = _UNIONS.get(checker)
    except TypeError:  # not weak-referenceable
        return None
    if union is None:
        union = shapely.union_all([o.polygon() for o in obstacles])
        shapely.prepare(union)
        _UNIONS[checker] = union
    return union


class _EdgeCache:
    """Memoised ``edge_free``: the key polygon is rebuilt from the same tree nodes several times.

    With the checker's obstacles known, :meth:`blocked_from` proves collisions in
    bulk: an edge whose centre line meets an obstacle cannot be free, because the
    swept capsule of ``edge_free`` contains its centre line.
    """

    def __init__(self, checker: EdgeChecker) -> None:
        self._edge_free = checker.edge_free
        self._known: dict[tuple[float, float, float, float], bool] = {}
        self.checks = 0
        self._screens: dict[tuple[float, float, bytes], np.ndarray] = {}
        self._union = _obstacle_union(checker)
        if self._union is None:
            self.blocked_from = None  # type: ignore[assignment]

    def blocked_from(self, a: np.ndarray, bs: np.ndarray) -> np.ndarray:
        """True where the centre line ``a -> b`` crosses an obstacle (so the edge collides)."""
        if len(bs) == 0 or self._union.is_empty:
            return np.zeros(len(bs), dtype=bool)
        key = (float(a[0]), float(a[1]), bs.tobytes())
        hit = self._screens.get(key)
        if hit is None:
            coords = np.empty((len(bs), 2, 2))
            coords[:, 0] = a
            coords[:, 1] = bs
            hit = self._screens[key] = shapely.intersects(self._union, shapely.linestrings(coords))
        return hit

    def edge_free(self, a: Sequence[float], b: Sequence[float]) -> bool:
        key = (a[0], a[1], b[0], b[1])
        hit = self._known.get(key)
        if hit is None:
            self.checks += 1
            hit = self._known[key] = bool(self._edge_free(a, b))
        return hit


class _Smoother:
    """State of one :func:`make_drivable` call: the key polygon and each corner's treatment."""

    def __init__(
        self, raw: np.ndarray, start: Pose, goal: Pose, checker: PathChecker, cfg: SmoothingConfig
    ) -> None:
        self.raw = raw
        self.start = start
        self.goal = goal
        self.checker = checker
        self.edges = _EdgeCache(checker)
        self.cfg = cfg
        self.s = np.array([start.x, start.y])
        self.g = np.array([goal.x, goal.y])
        self.hs = np.array([math.cos(start.yaw), math.sin(start.yaw)])
        self.hg = np.array([math.cos(goal.yaw), math.sin(goal.yaw)])
        # Smallest fillet radius: max |kappa| = 1 / (R cos(phi/2)) <= safety * kappa_max.
        self.r_design = 1.0 / (
            cfg.kappa_max * cfg.kappa_safety * math.cos(cfg.fillet_max_angle / 2.0)
        )
        self.max_turn: float | None = None
        self._fillets: dict[tuple[float, ...], tuple[Fillet, list[list[float]]]] = {}
        self.rounds = 0
        self.merges = 0
        self.moves = 0
        self.drops = 0
        self.unprunes = 0
        self.pts: list[np.ndarray] = []
        # Bezier pieces (bytes of their three points) whose body test passed.
        self._free_pieces: set[bytes] = set()

    # ------------------------------------------------------------- key polygon

    def key_polygon(self, d_s: float, d_g: float) -> str | None:
        """Build the key polygon with heading legs ``d_s``, ``d_g``; a reason on failure.

        With ``self.max_turn`` set, the pruning avoids turns above it (a second
        attempt after the paper's pure pruning has failed).
        """
        cfg, edge = self.cfg, self.edges.edge_free
        s1 = self.s + d_s * self.hs
        g1 = self.g - d_g * self.hg
        aug = np.vstack([self.s, s1, self.raw[1:-1], g1, self.g])
        n = len(aug)
        if not edge(self.s.tolist(), s1.tolist()):
            return f"the start heading leg of {d_s:.2f} m is blocked"
        if not edge(g1.tolist(), self.g.tolist()):
            return f"the goal heading leg of {d_g:.2f} m is blocked"
        if cfg.prune:
            key = prune(
                aug,
                self.edges,
                keep=(1, n - 2),
                max_turn=self.max_turn,
                start_heading=self.hs,
                end_heading=self.hg,
            )
            if key is None:
                return "a heading-leg point has no free edge to the tree path"
        else:
            key = np.arange(n)
            if not all(edge(aug[i].tolist(), aug[i + 1].tolist()) for i in range(n - 1)):
                return "a heading-leg point has no free edge to the tree path"
        if cfg.sharp_repair:
            key = repair_sharp_angles(aug, key, self.edges)
        self.pts = [aug[k].copy() for k in key.tolist()]
        self.origin = [p.copy() for p in self.pts]
        self.kind = ["start", "start_leg"] + ["node"] * (len(key) - 4) + ["goal_leg", "goal"]
        self.radius = [0.0] * len(key)
        self.attempt = [0] * len(key)
        self.raw_idx = key.tolist()  # index into self.aug (kept through moves)
        self.aug = aug
        self.unpruned: set[tuple[int, int]] = set()
        self.grown: dict[int, int] = {}
        self.d_s, self.d_g = d_s, d_g
        return None

    def snapshot(self) -> dict[str, object]:
        """The key-polygon state, for :meth:`restore`."""
        names = (
            "pts",
            "origin",
            "kind",
            "radius",
            "attempt",
            "raw_idx",
            "aug",
            "unpruned",
            "grown",
        )
        return {k: getattr(self, k) for k in (*names, "d_s", "d_g")}

    def restore(self, state: dict[str, object]) -> None:
        """Go back to a :meth:`snapshot`."""
        for k, v in state.items():
            setattr(self, k, v)

    def heading_turns(self) -> tuple[float, float]:
        """Deflections at the start- and goal-leg corners (radians)."""
        p = self.pts
        return (
            self._deflection(p[0], p[1], p[2]),
            self._deflection(p[-3], p[-2], p[-1]),
        )

    def heading_reach(self) -> tuple[float, float]:
        """Guard reach the design fillets at the start- and goal-leg corners need."""
        p = self.pts
        out = []
        for c in (1, len(p) - 2):
            ux, uy, _ = _unit(*(p[c] - p[c - 1]))
            vx, vy, _ = _unit(*(p[c + 1] - p[c]))
            f = fillet_points(p[c], (ux, uy), (vx, vy), self.r_design, self.cfg.fillet_max_angle)
            out.append(self._reach(f))
        return out[0], out[1]

    def _reach(self, f: Fillet) -> float:
        """Distance from a corner to its outermost guard.

        One guard per side for degree 2, two for degree 3 (a cubic piece spans
        four control points).
        """
        return f.reach + 2.0 * f.half * (self.cfg.degree - 2)

    # ------------------------------------------------------------- control points

    def control_points(self) -> tuple[np.ndarray, np.ndarray, list[int]]:
        """Control points, the key corner owning each, and the legs too short for their fillets."""
        cfg = self.cfg
        # Plain floats throughout (the polygon is small; numpy per corner costs more).
        pts = [p.tolist() for p in self.pts]
        n = len(pts)
        dirs: list[tuple[float, float]] = []
        lengths: list[float] = []
        for i in range(n - 1):
            ux, uy, length = _unit(pts[i + 1][0] - pts[i][0], pts[i + 1][1] - pts[i][1])
            dirs.append((ux, uy))
            lengths.append(length)
        guard_steps = range(cfg.degree - 1)
        corner_pts: list[list[list[float]]] = [[pts[0]]]
        reach = [0.0] * n
        for c in range(1, n - 1):
            cx, cy = pts[c]
            if self.radius[c] > 0.0:
                key = (cx, cy, *dirs[c - 1], *dirs[c], self.radius[c])
                hit = self._fillets.get(key)
                if hit is None:
                    f = fillet_points(
                        pts[c], dirs[c - 1], dirs[c], self.radius[c], cfg.fillet_max_angle
                    )
                    hit = self._fillets[key] = (f, f.vertices.tolist())
                f, verts = hit
                r = self._reach(f)
                if r > 0.0 and math.isfinite(r):
                    (uix, uiy), (uox, uoy) = dirs[c - 1], dirs[c]
                    at = [f.reach + 2.0 * f.half * k for k in guard_steps]  # guard distances
                    corner_pts.append(
                        [[cx - d * uix, cy - d * uiy] for d in reversed(at)]
                        + verts
                        + [[cx + d * uox, cy + d * uoy] for d in at]
                    )
                else:
                    corner_pts.append(verts)
                reach[c] = r
            else:
                corner_pts.append([pts[c]])
        corner_pts.append([pts[-1]])
        conflicts: list[int] = []
        fr = _fractions(cfg.supplement_n)
        ctrl: list[list[float]] = [pts[0]]
        own: list[int] = [0]
        for i in range(n - 1):
            if i > 0:
                ctrl += corner_pts[i]
                own += [i] * len(corner_pts[i])
            s0, s1 = reach[i], lengths[i] - reach[i + 1]
            need = _END_GAP if (i == 0 and reach[1] > 0) or (i == n - 2 and reach[i] > 0) else 0.0
            if s1 - s0 < need - 1e-9:
                conflicts.append(i)
                continue
            if cfg.supplement and s1 - s0 >= cfg.supplement_delta and fr:
                ux, uy = dirs[i]
                px, py = pts[i]
                for f_k in fr:
                    along = s0 + f_k * (s1 - s0)
                    ctrl.append([px + along * ux, py + along * uy])
                    own.append(max(i, 1) if f_k < 0.5 else min(i + 1, n - 2))
        ctrl.append(pts[-1])
        own.append(n - 1)
        ctrl_a = np.array(ctrl)
        own_a = np.array(own, dtype=np.int64)
        keep = np.ones(len(ctrl_a), dtype=bool)
        keep[1:] = np.hypot(*np.diff(ctrl_a, axis=0).T) > 1e-9  # merged guards
        return ctrl_a[keep], own_a[keep], conflicts

    # ------------------------------------------------------------- checking

    def curvature_check(
        self, ctrl: np.ndarray, owner: np.ndarray
    ) -> tuple[list[int], float, BSpline]:
        """Corners whose pieces exceed ``kappa_max``, the largest ``|kappa|``, and the spline."""
        cfg = self.cfg
        spl = fit_bspline(ctrl, cfg.degree)
        if cfg.degree == 2:
            span_k = quadratic_span_max_curvature(ctrl)
            bad = np.flatnonzero(span_k > cfg.kappa_max)
            return self._owners(owner, bad), float(span_k.max(initial=0.0)), spl
        # Degree 3: a dense parameter grid (spacing / 8) between the output samples.
        u = parameter_grid(spl, cfg.sample_spacing / 8.0)
        k = np.abs(spline_curvature(spl, u))
        n_int = len(ctrl) - cfg.degree
        span = np.minimum((u * n_int).astype(np.int64), n_int - 1)
        return self._owners(owner, np.unique(span[k > cfg.kappa_max])), float(k.max()), spl

    def collision_check(self, spl: BSpline, owner: np.ndarray) -> tuple[list[int], np.ndarray]:
        """Corners whose pieces collide, and the dense rows (spacing <= check_spacing)."""
        cfg = self.cfg
        # Poses at most check_spacing apart (every `stride`-th is an output sample).
        self.stride = max(1, int(cfg.sample_spacing / cfg.check_spacing + 1e-9))
        step = min(cfg.check_spacing, cfg.sample_spacing / self.stride)
        u = parameter_grid(spl, step)
        d1 = spl(u, nu=1)
        dense = np.column_stack([spl(u), np.arctan2(d1[:, 1], d1[:, 0]), np.zeros(len(u))])
        self.dense_u = u
        dense[0, :2] = self.s
        dense[-1, :2] = self.g
        dense[0, 2] = wrap_angle(self.start.yaw)
        dense[-1, 2] = wrap_angle(self.goal.yaw)
        n_int = len(spl.c) - cfg.degree
        span = np.minimum((u * n_int).astype(np.int64), n_int - 1)
        # Backstop against cusps: between samples at most `step` apart the heading
        # of a curve with |kappa| <= kappa_max turns by at most kappa_max * step.
        turn = np.abs(wrap_angle(np.diff(dense[:, 2])))
        jump = np.flatnonzero(turn > cfg.kappa_max * step * 1.05 + 1e-9)
        if len(jump):
            return self._owners(owner, np.unique(span[jump])), dense
        free, bad_seg = self._body_check(spl, dense, span)
        if free:
            return [], dense
        hit = np.unique(
            np.concatenate([span[bad_seg], span[np.minimum(bad_seg + 1, len(span) - 1)]])
        )
        return self._owners(owner, hit), dense

    def _body_check(
        self, spl: BSpline, dense: np.ndarray, span: np.ndarray
    ) -> tuple[bool, np.ndarray]:
        """``checker.path_free`` of the dense poses, skipping pieces already proven free.

        A piece of a clamped uniform quadratic B-spline is the Bezier curve of
        three points derived from its control points alone
        (:func:`quadratic_span_max_curvature`), so a piece whose three points
        were checked free in an earlier round of this call is the same curve,
        already checked at poses at most ``check_spacing`` apart; its poses are
        not tested again. Everything else is tested exactly as by ``path_free``
        (the dense poses are already that close, which is checked).
        """
        cfg = self.cfg
        poses_free = getattr(self.checker, "poses_free", None)
        chord = np.hypot(*np.diff(dense[:, :2], axis=0).T)
        if cfg.degree != 2 or poses_free is None or not chord.max() <= cfg.check_spacing:
            return self.checker.path_free(
                dense, spacing=cfg.check_spacing, clearance=cfg.clearance
            )
        c = np.asarray(spl.c, dtype=float)
        mid = 0.5 * (c[:-1] + c[1:])
        a, b, e = mid[:-1].copy(), c[1:-1], mid[1:].copy()
        a[0], e[-1] = c[0], c[-1]
        keys = [row.tobytes() for row in np.hstack([a, b, e])]
        known = np.array([k in self._free_pieces for k in keys], dtype=bool)
        todo = np.flatnonzero(~known[span])
        ok = np.ones(len(dense), dtype=bool)
        if len(todo):
            ok[todo] = poses_free(dense[todo, :3], cfg.clearance)
        bad_pose = np.flatnonzero(~ok)
        failed = set(span[bad_pose].tolist())
        for j in np.unique(span[todo]).tolist():
            if j not in failed:
                self._free_pieces.add(keys[j])
        # As path_free: pose i stands for segment i (the last pose for the last one).
        return len(bad_pose) == 0, np.unique(np.minimum(bad_pose, len(dense) - 2))

    def _owners(self, owner: np.ndarray, spans: np.ndarray) -> list[int]:
        """Key corners whose control points shape the given knot spans."""
        k = self.cfg.degree
        last = len(self.pts) - 2
        out: set[int] = set()
        for j in np.asarray(spans, dtype=np.int64).tolist():
            # Degree 2: span j is the Bezier piece of control point j + 1; degree 3:
            # control points j .. j + 3 act on span j.
            window = owner[j + 1 : j + 2] if k == 2 else owner[j : j + k + 1]
            out.update(min(max(int(c), 1), last) for c in window.tolist())
        return sorted(out)

    # ------------------------------------------------------------- repairs

    def _free(self, a: np.ndarray, b: np.ndarray) -> bool:
        return self.edges.edge_free(a.tolist(), b.tolist())

    def _place(self, c: int, new: np.ndarray) -> bool:
        """Put corner ``c`` at ``new`` when both adjacent legs stay free."""
        if not (self._free(self.pts[c - 1], new) and self._free(new, self.pts[c + 1])):
            return False
        self.pts[c] = new
        self.moves += 1
        return True

    def _move(self, c: int, direction: str, dist: float) -> bool:
        o, prev, nxt = self.origin[c], self.pts[c - 1], self.pts[c + 1]
        kind = self.kind[c]
        if kind == "start_leg":
            # Along the start ray, and only while its turn does not become a hairpin.
            new = o + dist * self.hs
            if direction != "ahead" or not self._turn_ok(c, new):
                return False
            return self._place(c, new)
        if kind == "goal_leg":
            new = o - dist * self.hg
            if direction != "back" or not self._turn_ok(c, new):
                return False
            return self._place(c, new)
        uix, uiy, _ = _unit(*(o - prev))
        uox, uoy, _ = _unit(*(nxt - o))
        if direction == "back":
            d = np.array([-uox, -uoy])
        elif direction == "ahead":
            d = np.array([uix, uiy])
        elif direction == "behind":
            if dist >= 0.9 * float(np.hypot(*(o - prev))):
                return False
            d = np.array([-uix, -uiy])
        else:
            bx, by, norm = _unit(uix - uox, uiy - uoy)
            if norm == 0.0:
                return False
            d = np.array([bx, by]) * (1.0 if direction == "out" else -1.0)
        return self._place(c, o + dist * d)

    def advance(self, c: int) -> bool:
        """Next treatment for corner ``c``: plain -> fillets -> moves; False when exhausted."""
        while True:
            self.attempt[c] += 1
            a = self.attempt[c]
            if a <= len(_RADIUS_STEPS):
                self.radius[c] = self.r_design * _RADIUS_STEPS[a - 1]
                return True
            m = a - len(_RADIUS_STEPS) - 1
            if m >= len(_MOVES):
                return self.unprune(c) or self.drop(c)
            if self._move(c, *_MOVES[m]):
                self.radius[c] = self.r_design
                return True

    def _turn_ok(self, c: int, new: np.ndarray) -> bool:
        """Moving corner ``c`` to ``new`` keeps its turn below max(now, the hairpin limit)."""
        p = self.pts
        now = self._deflection(p[c - 1], p[c], p[c + 1])
        return self._deflection(p[c - 1], new, p[c + 1]) <= max(now, _HAIRPIN)

    def _deflection(self, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> float:
        ux, uy, _ = _unit(*(b - a))
        vx, vy, _ = _unit(*(c - b))
        return math.atan2(abs(ux * vy - uy * vx), ux * vx + uy * vy)

    def drop(self, c: int) -> bool:
        """Remove tree corner ``c`` when the edge joining its neighbours is free.

        Refused when it would leave a neighbour with a hairpin (a turn above 150
        degrees), which no fillet could round.
        """
        p = self.pts
        if self.kind[c] != "node" or not self._free(p[c - 1], p[c + 1]):
            return False
        limit = math.radians(150.0)
        if c - 2 >= 0 and self._deflection(p[c - 2], p[c - 1], p[c + 1]) > limit:
            return False
        if c + 2 < len(p) and self._deflection(p[c - 1], p[c + 1], p[c + 2]) > limit:
            return False
        for seq in self._lists():
            del seq[c]
        self.drops += 1
        return True

    def _lists(self) -> tuple[list, ...]:
        return (self.pts, self.kind, self.origin, self.radius, self.attempt, self.raw_idx)

    def unprune(self, c: int) -> bool:
        """Put back tree-path nodes between the neighbours of corner ``c`` (once per stretch)."""
        i0, i1 = self.raw_idx[c - 1], self.raw_idx[c + 1]
        if i0 < 0 or i1 < 0 or i1 - i0 < 3 or (i0, i1) in self.unpruned:
            return False
        self.unpruned.add((i0, i1))
        n_aug = len(self.aug)
        p = self.pts
        into = p[c - 1] - p[c - 2] if c >= 2 else self.hs
        after = p[c + 2] - p[c + 1] if c + 2 < len(p) else self.hg
        # The heading points (augmented indices 1 and n - 2) always stay.
        anchors = [k - i0 for k in (1, n_aug - 2) if i0 < k < i1]
        sub = prune(
            self.aug[i0 : i1 + 1],
            self.edges,
            keep=anchors,
            max_turn=_UNPRUNE_TURN,
            start_heading=into,
            end_heading=after,
        )
        if sub is None or len(sub) <= 2:
            return False
        idx = [i0 + int(k) for k in sub[1:-1]]
        new_pts = [self.aug[k].copy() for k in idx]
        kinds = ["start_leg" if k == 1 else "goal_leg" if k == n_aug - 2 else "node" for k in idx]
        self.pts[c : c + 1] = new_pts
        self.kind[c : c + 1] = kinds
        self.origin[c : c + 1] = [q.copy() for q in new_pts]
        self.radius[c : c + 1] = [0.0] * len(idx)
        self.attempt[c : c + 1] = [0] * len(idx)
        self.raw_idx[c : c + 1] = idx
        self.unprunes += 1
        return True

    def merge(self, i: int) -> bool:
        """Replace corners ``i`` and ``i + 1`` by the crossing of their outer legs, if free."""
        p, kind = self.pts, self.kind
        if kind[i] == "start_leg" and kind[i + 1] == "goal_leg":
            return False
        a0, a1, b0, b1 = p[i - 1], p[i], p[i + 1], p[i + 2]
        uax, uay, la = _unit(*(a1 - a0))
        ubx, uby, lb = _unit(*(b1 - b0))
        det = uax * uby - uay * ubx
        if abs(det) < 1e-9:
            return False
        dx, dy = b0[0] - a1[0], b0[1] - a1[1]
        s = (dx * uby - dy * ubx) / det
        t = (uax * dy - uay * dx) / det
        if s <= -la + 0.5 or t <= -lb + 0.5 or s > 60.0 or t > 60.0:
            return False
        y = np.array([a1[0] + s * uax, a1[1] + s * uay])
        if not (self._free(a0, y) and self._free(y, b1)):
            return False
        new_kind = kind[i] if kind[i] == "start_leg" else kind[i + 1]
        p[i : i + 2] = [y]
        self.raw_idx[i : i + 2] = [
            self.raw_idx[i] if new_kind == "start_leg" else self.raw_idx[i + 1]
        ]
        kind[i : i + 2] = [new_kind]
        self.origin[i : i + 2] = [y.copy()]
        self.radius[i : i + 2] = [self.r_design]
        self.attempt[i : i + 2] = [1]
        self.merges += 1
        return True

    def _leg_fits(self, leg: int) -> bool:
        """Whether leg ``leg`` is long enough for the fillets at both its ends."""
        p, n = self.pts, len(self.pts)
        need = 0.0
        for c in (leg, leg + 1):
            if 0 < c < n - 1 and self.radius[c] > 0.0:
                u = _unit(*(p[c] - p[c - 1]))[:2]
                v = _unit(*(p[c + 1] - p[c]))[:2]
                f = fillet_points(p[c], u, v, self.radius[c], self.cfg.fillet_max_angle)
                need += self._reach(f)
        gap = _END_GAP if leg in (0, n - 2) else 0.0
        return need + gap <= float(np.hypot(*(p[leg + 1] - p[leg])))

    def stretch(self, leg: int) -> bool:
        """Lengthen leg ``leg`` by moving a tree corner next to it along its other leg.

        The corner before the leg moves back along its incoming line, the one after
        it on along its outgoing line, until the fillets fit (edges checked).
        """
        p, n = self.pts, len(self.pts)
        moves: list[tuple[int, np.ndarray]] = []
        if leg == n - 2:
            # The goal leg: the turn at the goal-leg point eases when the corner
            # before it turns earlier.
            if n - 3 > 0 and self.kind[n - 3] == "node":
                back = _unit(*(p[n - 4] - p[n - 3]))[:2]
                moves += [(n - 3, np.asarray(back) * d) for d in (3.0, 6.0, 10.0)]
        elif leg == 0:
            if n > 3 and self.kind[2] == "node":
                on = _unit(*(p[3] - p[2]))[:2]
                moves += [(2, np.asarray(on) * d) for d in (3.0, 6.0, 10.0)]
        else:
            length = float(np.hypot(*(p[leg + 1] - p[leg])))
            for c, other in ((leg, leg - 1), (leg + 1, leg + 2)):
                if self.kind[c] != "node" or self.radius[c] <= 0.0:
                    continue
                away = _unit(*(p[other] - p[c]))[:2]
                moves += [(c, np.asarray(away) * d) for d in (0.5 * length, length, 2.0 * length)]
        for c, delta in moves:
            if c <= 0 or c >= n - 1:
                continue
            if float(np.hypot(*delta)) >= 0.9 * float(
                np.hypot(*(p[c - 1 if c == leg else c + 1] - p[c]))
            ):
                continue
            old = p[c].copy()
            if not self._place(c, old + delta):
                continue
            if self._leg_fits(leg) or (leg == n - 2 and self._leg_fits(leg - 1)):
                self.origin[c] = p[c].copy()
                return True
            p[c] = old
        return False

    def fix_conflict(self, leg: int) -> bool:
        """Make leg ``leg`` long enough for the fillets at its ends."""
        n = len(self.pts)
        corners = [c for c in (leg, leg + 1) if 0 < c < n - 1 and self.radius[c] > 0.0]
        # 1. Wider-than-design fillets shrink first.
        shrunk = False
        for c in corners:
            if self.radius[c] > self.r_design * (1.0 + 1e-9):
                self.radius[c] = self.r_design
                shrunk = True
        if shrunk:
            return True
        # 2. Heading legs grow to fit their fillet (twice at most: beyond that the
        #    turn after them has to change).
        heading = 1 if leg == 0 else n - 2 if leg == n - 2 else -1
        if heading > 0 and self.grown.get(heading, 0) < 2:
            c = heading
            self.grown[c] = self.grown.get(c, 0) + 1
            ray, end = (self.hs, self.s) if leg == 0 else (-self.hg, self.g)
            f = fillet_points(
                self.pts[c],
                _unit(*(self.pts[c] - self.pts[c - 1]))[:2],
                _unit(*(self.pts[c + 1] - self.pts[c]))[:2],
                self.radius[c],
                self.cfg.fillet_max_angle,
            )
            length = float(np.hypot(*(self.pts[c] - end)))
            new_length = self._reach(f) + 0.5 + 0.1 * length
            # Only while the fillet fits at all and the turn at the heading point
            # does not become a hairpin.
            new = end + new_length * ray if math.isfinite(new_length) else None
            if (
                new is not None
                and math.isfinite(f.reach)
                and self._turn_ok(c, new)
                and self._place(c, new)
            ):
                self.origin[c] = self.pts[c].copy()
                return True
        # 3. Stretch the leg: move a corner next to it along its other leg.
        if self.stretch(leg):
            return True
        # 4. Merge the two corners into one.
        if 0 < leg < n - 2 and self.merge(leg):
            return True
        if leg == 0 and n > 4 and self.merge(1):
            return True
        if leg == n - 2 and n > 4 and self.merge(n - 3):
            return True
        # 5. Put back the tree nodes around a hairpin, or drop one of the corners.
        for c in corners:
            if self._deflection(self.pts[c - 1], self.pts[c], self.pts[c + 1]) > math.radians(
                120.0
            ) and self.unprune(c):
                return True
        for c in corners:
            if self.drop(c):
                return True
        # 6. Move one of them; at a heading leg also the tree corner next to it.
        if heading > 0:
            near = 2 if heading == 1 else n - 3
            if self.kind[near] == "node" and self.radius[near] > 0.0:
                corners.append(near)
        for c in sorted(corners, key=lambda c: -self.radius[c]):
            if self.attempt[c] < len(_RADIUS_STEPS):
                self.attempt[c] = len(_RADIUS_STEPS)
            if self.advance(c):
                return True
        return False


def make_drivable(
    raw: np.ndarray,
    start: Pose,
    goal: Pose,
    checker: PathChecker,
    config: SmoothingConfig | None = None,
) -> SmoothingResult:
    """Turn a collision-free tree path into a drivable, curvature-bounded B-spline path.

    The chain (SPEC §3 items 5–9): straight legs along the start and goal headings
    are added (their points survive the pruning; they lengthen when the turn after
    them needs room), the path is pruned (:func:`prune`), sharp angles are repaired
    (:func:`repair_sharp_angles`), legs are supplemented by :func:`supplement`'s
    rule and the control points are fitted by a clamped uniform B-spline. Then
    the guarantee loop: the curvature is checked (exactly per span for degree 2,
    on a dense parameter grid for degree 3), then the exact body at poses at most
    ``check_spacing`` apart. Each key corner whose piece of curve breaks a limit
    gets its next treatment: a fillet of the design radius (:func:`fillet_points`),
    a wider one, then moves of the corner, each only when both new legs are free,
    and last its removal when the edge joining its neighbours is free. Legs too
    short for their fillets grow (heading legs), merge their corners into one
    (the crossing of the outer legs), drop one, or move one. When the rounds or a
    corner's options run out, the result is not ok and says why -- it never
    carries an unchecked path.

    Parameters
    ----------
    raw : numpy.ndarray
        Tree path ``(K, 2)`` from the start position to the goal position, every
        edge free for ``checker.edge_free`` in driving order.
    start, goal : Pose
        Rear-axle poses; the path leaves along ``start.yaw`` and arrives along ``goal.yaw``.
    checker : PathChecker
        The original map's checker (``edge_free`` and ``path_free``).
    config : SmoothingConfig, optional
        Tunables.

    Returns
    -------
    SmoothingResult

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> from rrtdrive.collision import CollisionChecker
    >>> m = builtin_map("overtake")
    >>> res = make_drivable(np.array([[5.0, 44.0], [40.0, 48.0], [92.0, 44.0]]),
    ...                     m.start, m.goal, CollisionChecker.for_map(m))
    >>> res.ok, bool(res.max_curvature <= 1 / 6)
    (True, True)
    """
    cfg = config or SmoothingConfig()
    raw = np.asarray(raw, dtype=float).reshape(-1, 2)
    empty = np.zeros((0, 4))

    def fail(
        msg: str, sm: _Smoother | None = None, ctrl: np.ndarray | None = None
    ) -> SmoothingResult:
        key = np.array(sm.pts) if sm is not None and sm.pts else np.zeros((0, 2))
        return SmoothingResult(
            False,
            empty,
            np.zeros((0, 2)) if ctrl is None else ctrl,
            key,
            0 if sm is None else sm.rounds,
            math.inf,
            f"post-processing failed: {msg}",
        )

    if len(raw) < 2:
        return fail("the tree path needs at least two points")
    rounds = 0
    message = "no heading legs fit"
    sm: _Smoother | None = None
    ctrl: np.ndarray | None = None
    # The paper's pruning first; if that cannot be made drivable, a pruning that
    # avoids hairpins (turns above 100 degrees) gets its own round budget.
    for max_turn in (None, _UNPRUNE_TURN) if cfg.prune else (None,):
        sm = _Smoother(raw, start, goal, checker, cfg)
        sm.max_turn = max_turn
        res, message, ctrl = _drive(sm)
        rounds += sm.rounds
        if res is not None:
            return dataclasses.replace(res, rounds=rounds)
    failed = fail(message, sm, ctrl)
    return dataclasses.replace(failed, rounds=rounds)


def _drive(sm: _Smoother) -> tuple[SmoothingResult | None, str, np.ndarray | None]:
    """One attempt of :func:`make_drivable` with the smoother's pruning setting."""
    cfg = sm.cfg
    straight = float(np.hypot(*(sm.g - sm.s)))
    reason = "no heading legs fit"
    built = False
    for d in (cfg.heading_leg, cfg.heading_leg / 2.0, cfg.heading_leg / 4.0, 0.5):
        d = min(d, 0.45 * straight) if straight > 0 else d
        if d <= 0.05:
            continue
        why = sm.key_polygon(d, d)
        if why is None:
            built = True
            break
        reason = why
    if not built:
        return None, reason, None
    # Lengthen the heading legs to what the turns after them need (a few re-prunes).
    for _ in range(3):
        reach_s, reach_g = sm.heading_reach()
        cap = 4.0 * sm.r_design  # a turn needing more is a hairpin: left to the repairs
        want_s = reach_s + 0.5 if reach_s + _END_GAP > sm.d_s and reach_s < cap else sm.d_s
        want_g = reach_g + 0.5 if reach_g + _END_GAP > sm.d_g and reach_g < cap else sm.d_g
        if want_s == sm.d_s and want_g == sm.d_g:
            break
        saved = sm.snapshot()
        before = sm.heading_turns()
        if sm.key_polygon(want_s, want_g) is not None or any(
            t > max(b, _HAIRPIN) for t, b in zip(sm.heading_turns(), before, strict=True)
        ):
            # Blocked, or the longer leg overshoots the next turn into a hairpin.
            sm.restore(saved)
            break

    ctrl = np.zeros((0, 2))
    message = f"no drivable curve within {cfg.max_rounds} repair rounds"
    while sm.rounds < cfg.max_rounds:
        sm.rounds += 1
        ctrl, owner, conflicts = sm.control_points()
        if conflicts:
            # From the last leg backwards, so that merges and drops keep the
            # indices of the legs still to fix.
            failed = None
            for leg in sorted(conflicts, reverse=True):
                if leg + 1 < len(sm.pts) and not sm.fix_conflict(leg):
                    failed = leg
                    break
            if failed is not None:
                a, b = sm.pts[failed], sm.pts[failed + 1]
                message = (
                    f"the turns at ({a[0]:.1f}, {a[1]:.1f}) and ({b[0]:.1f}, {b[1]:.1f}) "
                    "are too close for the car"
                )
                break
            continue
        if len(ctrl) <= cfg.degree:
            message = "too few control points"
            break
        bad, max_k, spl = sm.curvature_check(ctrl, owner)
        what = "curvature"
        if not bad:
            bad, dense = sm.collision_check(spl, owner)
            what = "collision"
            if not bad:
                pick = np.arange(0, len(dense), sm.stride)
                if pick[-1] != len(dense) - 1:
                    pick = np.append(pick, len(dense) - 1)
                samples = dense[pick]
                uu = sm.dense_u[pick]
                samples[:, 3] = curvature(spl(uu, nu=1), spl(uu, nu=2))
                stats = {
                    "fillets": float(sum(r > 0 for r in sm.radius)),
                    "merges": float(sm.merges),
                    "moves": float(sm.moves),
                    "drops": float(sm.drops),
                    "unprunes": float(sm.unprunes),
                    "edge_checks": float(sm.edges.checks),
                }
                ok = SmoothingResult(
                    True, samples, ctrl, np.array(sm.pts), sm.rounds, max_k, "", stats
                )
                return ok, "", ctrl
        stuck = None
        for c in sorted(bad, reverse=True):  # drops keep the smaller indices
            here = sm.pts[c].copy()
            if not sm.advance(c):
                stuck = here
                break
        if stuck is not None:
            message = f"could not repair a {what} violation near ({stuck[0]:.1f}, {stuck[1]:.1f})"
            break
    return None, message, ctrl
