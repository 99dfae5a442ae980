"""Plane-geometry primitives shared by the planner, the checker and the evaluators.

One copy of each: :func:`wrap_angle`, :func:`box_corners` (oriented rectangles),
:func:`densify` (a polyline or a pose sequence resampled to a maximum spacing)
and :func:`project_to_polyline` (nearest point and its arc length).

The module depends on numpy only, so that :mod:`rrtdrive.types` can re-export
:func:`wrap_angle` without an import cycle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import overload

import numpy as np

__all__ = [
    "wrap_angle",
    "box_corners",
    "Densified",
    "densify",
    "PolylineProjection",
    "project_to_polyline",
]

_TWO_PI = 2.0 * math.pi


@overload
def wrap_angle(angle: float) -> float: ...
@overload
def wrap_angle(angle: np.ndarray) -> np.ndarray: ...
def wrap_angle(angle: float | np.ndarray) -> float | np.ndarray:
    """Wrap an angle (or an array of angles) to ``[-pi, pi)``, up to rounding.

    An angle a hair below ``-pi`` (``-3.1415926535897936``) comes out as ``+pi``: the
    sum ``angle + pi`` rounds before the modulo. Compare wrapped angles with a tolerance
    (or wrap their difference), never ``== -pi``.

    Parameters
    ----------
    angle : float or numpy.ndarray
        Angle(s) in radians.

    Returns
    -------
    float or numpy.ndarray
        ``(angle + pi) mod 2 pi - pi``, the same type as ``angle``.

    Examples
    --------
    >>> round(wrap_angle(3.0 * math.pi / 2.0), 6)
    -1.570796
    >>> wrap_angle(np.array([0.0, 2.0 * math.pi])).round(6)
    array([0., 0.])
    """
    return (angle + math.pi) % _TWO_PI - math.pi


def box_corners(
    x: float | np.ndarray,
    y: float | np.ndarray,
    yaw: float | np.ndarray,
    back: float | np.ndarray,
    front: float | np.ndarray,
    half_width: float | np.ndarray,
    *,
    rotate_first: bool = False,
) -> np.ndarray:
    """Corners of oriented rectangles about a reference point.

    The rectangle spans ``back <= u <= front`` along the heading and
    ``|v| <= half_width`` across it, in the frame of the reference point
    ``(x, y)`` rotated by ``yaw``: ``back = -rear_overhang`` with a rear-axle
    reference, ``back = -length / 2`` for a centred box.

    Parameters
    ----------
    x, y, yaw : float or numpy.ndarray
        Reference point and heading; arrays broadcast against each other and
        against the extents.
    back, front : float or numpy.ndarray
        Longitudinal extents from the reference point (``back < front``).
    half_width : float or numpy.ndarray
        Half the width.
    rotate_first : bool
        Evaluate the corners as ``local @ R.T + (x, y)`` with ``math.cos`` /
        ``math.sin`` (scalar reference only), the order map obstacles have always
        used: the distance field is built from those corners, so they are kept
        bit for bit. The default adds the rotated offsets to the reference point.

    Returns
    -------
    numpy.ndarray
        Shape ``(..., 4, 2)``: rear-right, front-right, front-left, rear-left
        (counter-clockwise).

    Examples
    --------
    >>> box_corners(0.0, 0.0, 0.0, -1.0, 3.0, 1.0)
    array([[-1., -1.],
           [ 3., -1.],
           [ 3.,  1.],
           [-1.,  1.]])
    >>> c = box_corners(np.zeros(5), np.zeros(5), np.zeros(5), -1.0, 3.0, 1.0)
    >>> c.shape
    (5, 4, 2)
    """
    if rotate_first:
        local = np.array([[back, -half_width], [front, -half_width],
                          [front, half_width], [back, half_width]])
        c, s = math.cos(yaw), math.sin(yaw)  # type: ignore[arg-type]
        rot = np.array([[c, -s], [s, c]])
        return local @ rot.T + np.asarray((x, y))
    x, y, yaw = np.asarray(x, dtype=float), np.asarray(y, dtype=float), np.asarray(yaw, dtype=float)
    back, front, half_width = np.asarray(back), np.asarray(front), np.asarray(half_width)
    lx = np.stack(np.broadcast_arrays(back, front, front, back), axis=-1)
    ly = np.stack(np.broadcast_arrays(-half_width, -half_width, half_width, half_width), axis=-1)
    c, s = np.cos(yaw)[..., None], np.sin(yaw)[..., None]
    cx = x[..., None] + c * lx - s * ly
    cy = y[..., None] + s * lx + c * ly
    return np.stack([cx, cy], axis=-1)


@dataclass(frozen=True)
class Densified:
    """A densified polyline: the points and how many pieces each input segment became.

    Attributes
    ----------
    points : numpy.ndarray
        ``(M, D)`` rows; the input vertices are among them.
    pieces : numpy.ndarray
        ``(N - 1,)`` number of pieces of each input segment (at least 1).
    """

    points: np.ndarray
    pieces: np.ndarray

    @property
    def vertex_index(self) -> np.ndarray:
        """Index into :attr:`points` of each input vertex, shape ``(N,)``."""
        return np.concatenate([[0], np.cumsum(self.pieces)]).astype(np.int64)

    @property
    def segment(self) -> np.ndarray:
        """Input segment each row of :attr:`points` lies on (the last row: the last segment)."""
        n = len(self.pieces)
        if n == 0:
            return np.zeros(len(self.points), dtype=np.int64)
        return np.append(np.repeat(np.arange(n), self.pieces), n - 1)


def densify(
    points: np.ndarray,
    spacing: float,
    *,
    angle_column: int | None = None,
    rel_slack: float = 0.0,
    abs_slack: float = 0.0,
) -> Densified:
    """Linear interpolation so that consecutive rows are at most ``spacing`` apart in ``x, y``.

    Each segment of planar length ``d`` is cut into
    ``max(1, ceil(d / spacing * (1 + rel_slack) - abs_slack))`` equal pieces; every
    input row is kept and the last one ends the output.

    Parameters
    ----------
    points : numpy.ndarray
        ``(N, D)`` rows with ``D >= 2``; the first two columns are ``x, y``.
    spacing : float
        Largest gap between consecutive output rows (> 0).
    angle_column : int, optional
        A column holding angles: it is interpolated along the wrapped (shortest)
        difference, so values may leave ``[-pi, pi)``.
    rel_slack : float
        Relative slack on the piece count: a small positive value keeps a gap
        rounded a hair over (e.g. through JSON) from exceeding ``spacing``.
    abs_slack : float
        Absolute slack subtracted from the piece count: a small positive value
        keeps an exact multiple of ``spacing`` from gaining a piece through rounding.

    Returns
    -------
    Densified
        The points and the piece count of each segment.

    Examples
    --------
    >>> d = densify(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.5]]), 0.25)
    >>> d.points.shape, d.pieces.tolist(), d.vertex_index.tolist()
    ((7, 2), [4, 2], [0, 4, 6])
    >>> poses = np.array([[0.0, 0.0, 3.0], [1.0, 0.0, -3.0]])
    >>> densify(poses, 0.5, angle_column=2).points[1, 2].round(4)
    np.float64(3.1416)
    """
    p = np.asarray(points, dtype=float)
    if len(p) < 2:
        return Densified(p, np.zeros(0, dtype=np.int64))
    # Each segment's difference b - a once, gathered per output row (the same floats as
    # differences of the gathered rows), and the rows written in place: the arithmetic of
    # ``a + frac (b - a)`` in fewer numpy calls (a hot path of the planners' re-checks).
    step = p[1:] - p[:-1]
    count = np.hypot(step[:, 0], step[:, 1]) / spacing
    if rel_slack:  # x * (1 + 0) and x - 0 are x: the slack-free count skips them
        count *= 1 + rel_slack
    if abs_slack:
        count -= abs_slack
    pieces = np.maximum(1, np.ceil(count).astype(np.int64))
    owner = np.repeat(np.arange(len(step)), pieces)
    # take(), not fancy indexing: the same gather, several times faster on rows.
    first = (pieces.cumsum() - pieces).take(owner)
    frac = (np.arange(len(owner)) - first) / pieces.take(owner)
    out = np.empty((len(owner) + 1, p.shape[1]))
    body = out[:-1]
    np.multiply(frac[:, None], step.take(owner, axis=0), out=body)
    body += p.take(owner, axis=0)
    if angle_column is not None:
        k = angle_column
        np.multiply(frac, wrap_angle(step[:, k]).take(owner), out=body[:, k])
        body[:, k] += p[:, k].take(owner)
    out[-1] = p[-1]
    return Densified(out, pieces)


@dataclass(frozen=True)
class PolylineProjection:
    """Nearest points of a polyline to query points.

    Attributes
    ----------
    segment : numpy.ndarray
        ``(N,)`` index of the segment holding the nearest point (first on ties).
    fraction : numpy.ndarray
        ``(N,)`` position along that segment, in ``[0, 1]``.
    foot : numpy.ndarray
        ``(N, 2)`` the nearest points.
    distance : numpy.ndarray
        ``(N,)`` distance from each query point to its nearest point.
    s : numpy.ndarray
        ``(N,)`` arc length of the nearest point along the polyline.
    """

    segment: np.ndarray
    fraction: np.ndarray
    foot: np.ndarray
    distance: np.ndarray
    s: np.ndarray


def project_to_polyline(
    vertices: np.ndarray, points: np.ndarray, chunk: int = 256
) -> PolylineProjection:
    """Project points onto a polyline (its nearest point, by brute force over segments).

    Parameters
    ----------
    vertices : numpy.ndarray
        ``(M, 2)`` with ``M >= 2`` and no two consecutive vertices equal.
    points : numpy.ndarray
        ``(N, 2)`` (or ``(2,)``) query points.
    chunk : int
        Points per vectorised block (memory ``chunk * M``).

    Returns
    -------
    PolylineProjection

    Examples
    --------
    >>> line = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]])
    >>> pr = project_to_polyline(line, np.array([[1.0, 1.0], [5.0, 2.0]]))
    >>> pr.segment.tolist(), pr.s.tolist(), pr.distance.tolist()
    ([0, 1], [1.0, 6.0], [1.0, 1.0])
    """
    xy = np.asarray(vertices, dtype=float)[:, :2]
    a, d = xy[:-1], np.diff(xy, axis=0)
    len2 = np.einsum("ij,ij->i", d, d)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*d.T))])
    q_all = np.asarray(points, dtype=float).reshape(-1, 2)
    n = len(q_all)
    seg = np.empty(n, dtype=np.int64)
    frac = np.empty(n)
    foot = np.empty((n, 2))
    dist = np.empty(n)
    for lo in range(0, n, chunk):
        q = q_all[lo : lo + chunk]
        rel = q[:, None, :] - a[None, :, :]
        t = np.clip(np.einsum("nmj,mj->nm", rel, d) / len2[None, :], 0.0, 1.0)
        f = a[None, :, :] + t[..., None] * d[None, :, :]
        dist2 = np.sum((q[:, None, :] - f) ** 2, axis=-1)
        j = np.argmin(dist2, axis=1)
        rows = np.arange(len(q))
        seg[lo : lo + len(q)] = j
        frac[lo : lo + len(q)] = t[rows, j]
        foot[lo : lo + len(q)] = f[rows, j]
        dist[lo : lo + len(q)] = np.sqrt(dist2[rows, j])
    s = arc[seg] + frac * np.sqrt(len2[seg])
    return PolylineProjection(seg, frac, foot, dist, s)
