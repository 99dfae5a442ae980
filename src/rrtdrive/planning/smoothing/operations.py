"""The paper's polygon steps: pruning, sharp-angle repair and control-point supplement.

Paper Sec. 3.2.1 (steps 1 and 2, Eq. 12) and Sec. 3.2.3 (Eq. 16); SPEC §3 items 5–7.
All points are rear-axle positions; a segment ``a -> b`` is driven with the
heading along it, which is what ``checker.edge_free(a, b)`` tests.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rrtdrive.planning.smoothing.checks import EdgeChecker, edge_screen

__all__ = [
    "prune",
    "is_sharp",
    "sharp_flags",
    "repair_sharp_angles",
    "supplement",
]

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
    start_heading: Sequence[float] | np.ndarray | None = None,
    end_heading: Sequence[float] | np.ndarray | None = None,
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
    screen = edge_screen(checker)
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

    Parameters
    ----------
    prev, point, nxt : sequence of float
        Consecutive vertices ``(x, y, ...)`` of a polyline.

    Returns
    -------
    bool

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

    Parameters
    ----------
    points : numpy.ndarray
        ``(N, 2)`` polyline vertices.

    Returns
    -------
    numpy.ndarray
        Boolean ``(N,)``.

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


def supplement_fractions(n: float) -> list[float]:
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
    fr = np.asarray(supplement_fractions(n))
    out = [p[:1]]
    d2 = np.sum(np.diff(p, axis=0) ** 2, axis=1)
    for i in range(len(p) - 1):
        if d2[i] >= delta * delta and len(fr):
            out.append(p[i] + fr[:, None] * (p[i + 1] - p[i]))
        out.append(p[i + 1 : i + 2])
    return np.concatenate(out)
