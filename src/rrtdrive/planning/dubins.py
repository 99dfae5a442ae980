"""Dubins paths: the shortest forward paths of bounded curvature between two poses.

Used by the improved planner as a last resort (``dubins_fallback``): when its tree
paths cannot be made drivable, for example a goal that needs a U-turn or a sharp
approach in open space, the shortest Dubins path from the start pose to the goal
pose is tried, and accepted only when the exact body test clears it.

The six words (LSL, RSR, LSR, RSL, RLR, LRL) follow Shkel & Lumelsky (2001) in
the normalised frame (turning radius 1, the start at the origin, the goal on the
x axis). No well-kept Python package provides them (OMPL's ``DubinsStateSpace``
needs the optional ``ompl`` extra; the tests compare against it when installed),
so they are written here; every candidate is integrated segment by segment and
kept only when it ends at the goal pose, so a wrong formula cannot return a path
that does not connect.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rrtdrive.geometry import wrap_angle
from rrtdrive.types import InputError, Pose

__all__ = ["LOOP_SNAP", "WORD_NOISE", "DubinsPath", "dubins_paths", "shortest_dubins"]

_TWO_PI = 2.0 * math.pi
#: Segment types: +1 left turn, -1 right turn, 0 straight.
_WORDS: dict[str, tuple[int, int, int]] = {
    "LSL": (1, 0, 1),
    "RSR": (-1, 0, -1),
    "LSR": (1, 0, -1),
    "RSL": (-1, 0, 1),
    "RLR": (-1, 1, -1),
    "LRL": (1, -1, 1),
}


#: A word's arc this close under a full turn (radians) is float noise of 0: a goal 1.2 cm
#: straight ahead put the heading's atan2 1e-13 below it, and LSL drove a 37.7 m loop; a
#: goal on one arc left a straight of sqrt(1e-16) = 1e-8 and an arc 1.4e-8 under 2 pi.
#: Snapped, a word ends at most 3e-6 m and 5e-7 rad off, inside ``dubins_paths``' check.
LOOP_SNAP = 5e-7


#: Slack of the words' existence tests (radius 1): a goal on one arc makes the straight's
#: squared length 0, and float noise put it at -1e-16 (no word then, and the shortest
#: left was a 38 m loop). Every word found is checked to reach the goal (``tol``).
WORD_NOISE = 1e-10


def _mod2pi(a: float) -> float:
    return a % _TWO_PI


def _root(p2: float) -> float | None:
    """A straight's length from its square, ``None`` below :data:`WORD_NOISE` (no word)."""
    return None if p2 < -WORD_NOISE else math.sqrt(max(p2, 0.0))


def _cosine(c: float) -> float | None:
    """A middle arc's cosine clipped to [-1, 1], ``None`` beyond :data:`WORD_NOISE`."""
    return None if abs(c) > 1.0 + WORD_NOISE else min(1.0, max(-1.0, c))


def _unloop(arc: float) -> float:
    """An arc (radians) a hair under a full turn (:data:`LOOP_SNAP`) as 0.

    Only for a word's arcs once solved: a heading itself that is a hair under a full
    turn is a real angle (a goal 1e-5 m aside over 20 m is 5e-7 rad off the line).
    """
    return 0.0 if _TWO_PI - arc <= LOOP_SNAP else arc


@dataclass(frozen=True)
class DubinsPath:
    """One Dubins word from ``start`` with turning radius ``radius``.

    Attributes
    ----------
    start : Pose
        Rear-axle start pose.
    word : str
        ``"LSL"``, ``"RSR"``, ``"LSR"``, ``"RSL"``, ``"RLR"`` or ``"LRL"``.
    lengths : tuple of float
        Arc lengths of the three segments in metres.
    radius : float
        Turning radius of the arcs in metres.
    goal : Pose, optional
        The pose the word was solved for (:func:`dubins_paths` sets it after checking
        that the word reaches it); the last sample is then exactly this pose rather
        than the integrated end (which differs by ~1e-12).
    """

    start: Pose
    word: str
    lengths: tuple[float, float, float]
    radius: float
    goal: Pose | None = None

    @property
    def length(self) -> float:
        """Total length in metres."""
        return float(sum(self.lengths))

    def sample(self, spacing: float) -> np.ndarray:
        """Rows ``[x, y, yaw, kappa]`` at most ``spacing`` apart, both ends included.

        Positions are exact on the arcs and lines (closed-form integration); the
        curvature of a row is that of the segment it lies on (at a junction, of the
        segment that starts there); the last row, the goal, has curvature 0.
        """
        if not spacing > 0:
            raise InputError(f"spacing: must be > 0, got {spacing!r}")
        # Each segment's columns, written into one array (the rows column_stack and
        # vstack made, without their wrappers: a shot samples up to three words).
        cols: list[tuple[object, object, object, float, int]] = []
        x, y, yaw = self.start.x, self.start.y, self.start.yaw
        for turn, seg in zip(_WORDS[self.word], self.lengths, strict=True):
            if seg <= 1e-9:
                # A word's float noise (a straight ahead at heading 0.7 is LSL with
                # 5.6e-16 m arcs): as its own row, the end position came twice with
                # kappa 1/r then 0, a steering rate of 5.7e14 rad/m (a mutation audit).
                x, y, yaw = _advance(x, y, yaw, turn, seg, self.radius)
                continue
            n = max(1, math.ceil(seg / spacing))
            u = np.arange(n) * (seg / n)  # the segment's own end is the next one's start
            kappa = turn / self.radius
            if turn == 0:
                xs, ys = x + u * math.cos(yaw), y + u * math.sin(yaw)
                cols.append((xs, ys, yaw, kappa, n))
            else:
                yaws = yaw + u * kappa
                xs = x + (np.sin(yaws) - math.sin(yaw)) / kappa
                ys = y - (np.cos(yaws) - math.cos(yaw)) / kappa
                cols.append((xs, ys, yaws, kappa, n))
            x, y, yaw = _advance(x, y, yaw, turn, seg, self.radius)
        if not cols:  # a path of length 0: start and end are the same pose
            cols.append((x, y, yaw, 0.0, 1))
        out = np.empty((sum(c[4] for c in cols) + 1, 4))
        a = 0
        for xs, ys, yaws, kappa, n in cols:
            out[a : a + n, 0], out[a : a + n, 1], out[a : a + n, 2] = xs, ys, yaws
            out[a : a + n, 3] = kappa
            a += n
        if self.goal is not None:
            x, y, yaw = self.goal.x, self.goal.y, self.goal.yaw
        out[-1] = x, y, yaw, 0.0
        out[:, 2] = wrap_angle(out[:, 2])
        return out

    def joints(self) -> np.ndarray:
        """Positions ``(4, 2)``: the start, the two segment junctions and the end."""
        x, y, yaw = self.start.x, self.start.y, self.start.yaw
        out = [(x, y)]
        for turn, seg in zip(_WORDS[self.word], self.lengths, strict=True):
            x, y, yaw = _advance(x, y, yaw, turn, seg, self.radius)
            out.append((x, y))
        return np.array(out)

    def polygon(self, max_arc: float = 2.0 * math.pi / 3.0) -> np.ndarray:
        """The tangent polygon ``(K, 2)``: start, one vertex per (sub-)arc, end.

        Each arc is split into ``ceil(angle / max_arc)`` equal sub-arcs; a sub-arc's
        vertex is where the tangents at its ends meet, so the polygon's corners turn
        by at most ``max_arc`` and its legs hold the straight segment. A
        continuous-curvature path rounds these corners with clothoid turns
        (:mod:`rrtdrive.planning.smoothing.clothoid`).

        Examples
        --------
        >>> p = dubins_paths(Pose(0.0, 0.0, 0.0), Pose(0.0, 4.0, math.pi), 2.0)[0]
        >>> p.word, np.round(p.polygon(), 6).tolist()
        ('LSL', [[0.0, 0.0], [2.0, 0.0], [2.0, 4.0], [0.0, 4.0]])
        """
        if not 0.0 < max_arc < math.pi:
            raise InputError(f"max_arc: must lie in (0, pi), got {max_arc!r}")
        x, y, yaw = self.start.x, self.start.y, self.start.yaw
        out = [(x, y)]
        for turn, seg in zip(_WORDS[self.word], self.lengths, strict=True):
            if turn != 0 and seg > 1e-9:
                angle = seg / self.radius
                m = max(1, math.ceil(angle / max_arc - 1e-9))
                sub = seg / m
                reach = self.radius * math.tan(0.5 * angle / m)
                for _ in range(m):
                    out.append((x + reach * math.cos(yaw), y + reach * math.sin(yaw)))
                    x, y, yaw = _advance(x, y, yaw, turn, sub, self.radius)
            else:
                x, y, yaw = _advance(x, y, yaw, turn, seg, self.radius)
        end = (self.goal.x, self.goal.y) if self.goal is not None else (x, y)
        out.append(end)
        return np.array(out)

    def end(self) -> tuple[float, float, float]:
        """Pose ``(x, y, yaw)`` at the end of the path (yaw unwrapped)."""
        x, y, yaw = self.start.x, self.start.y, self.start.yaw
        for turn, seg in zip(_WORDS[self.word], self.lengths, strict=True):
            x, y, yaw = _advance(x, y, yaw, turn, seg, self.radius)
        return x, y, yaw


def _advance(
    x: float, y: float, yaw: float, turn: int, seg: float, radius: float
) -> tuple[float, float, float]:
    if turn == 0:
        return x + seg * math.cos(yaw), y + seg * math.sin(yaw), yaw
    kappa = turn / radius
    yaw1 = yaw + seg * kappa
    return (
        x + (math.sin(yaw1) - math.sin(yaw)) / kappa,
        y - (math.cos(yaw1) - math.cos(yaw)) / kappa,
        yaw1,
    )


def _normalised(word: str, a: float, b: float, d: float) -> tuple[float, float, float] | None:
    """Segment lengths (radius 1) of ``word`` from heading ``a`` to ``b`` over distance ``d``."""
    sa, sb, ca, cb = math.sin(a), math.sin(b), math.cos(a), math.cos(b)
    cab = math.cos(a - b)
    if word == "LSL":
        p = _root(2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb))
        if p is None:
            return None
        tmp = math.atan2(cb - ca, d + sa - sb)
        return _mod2pi(tmp - a), p, _mod2pi(b - tmp)
    if word == "RSR":
        p = _root(2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa))
        if p is None:
            return None
        tmp = math.atan2(ca - cb, d - sa + sb)
        return _mod2pi(a - tmp), p, _mod2pi(tmp - b)
    if word == "LSR":
        p = _root(-2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb))
        if p is None:
            return None
        tmp = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        return _mod2pi(tmp - a), p, _mod2pi(tmp - b)
    if word == "RSL":
        p = _root(-2.0 + d * d + 2.0 * cab - 2.0 * d * (sa + sb))
        if p is None:
            return None
        tmp = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        return _mod2pi(a - tmp), p, _mod2pi(b - tmp)
    if word == "RLR":
        cos_p = _cosine((6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb)) / 8.0)
        if cos_p is None:
            return None
        p = _mod2pi(_TWO_PI - math.acos(cos_p))
        t = _mod2pi(a - math.atan2(ca - cb, d - sa + sb) + p / 2.0)
        return t, p, _mod2pi(a - b - t + p)
    # LRL
    cos_p = _cosine((6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa)) / 8.0)
    if cos_p is None:
        return None
    p = _mod2pi(_TWO_PI - math.acos(cos_p))
    t = _mod2pi(-a + math.atan2(-ca + cb, d + sa - sb) + p / 2.0)
    return t, p, _mod2pi(b - a - t + p)


def dubins_paths(start: Pose, goal: Pose, radius: float, tol: float = 1e-6) -> list[DubinsPath]:
    """Every Dubins word that joins ``start`` to ``goal``, shortest first.

    Parameters
    ----------
    start, goal : Pose
        Rear-axle poses (forward driving from ``start`` to ``goal``).
    radius : float
        Turning radius of the arcs in metres (> 0).
    tol : float
        A candidate is kept only when its integrated end lies within ``tol`` metres
        and ``tol`` radians of ``goal``.

    Returns
    -------
    list of DubinsPath

    Examples
    --------
    >>> paths = dubins_paths(Pose(0.0, 0.0, 0.0), Pose(10.0, 0.0, 0.0), 2.0)
    >>> paths[0].word, round(paths[0].length, 6)
    ('LSL', 10.0)
    """
    if not (math.isfinite(radius) and radius > 0):
        raise InputError(f"radius: must be > 0, got {radius!r}")
    dx, dy = goal.x - start.x, goal.y - start.y
    d = math.hypot(dx, dy) / radius
    theta = math.atan2(dy, dx) if d > 0 else 0.0
    a = _mod2pi(start.yaw - theta)
    b = _mod2pi(goal.yaw - theta)
    out = []
    for word in _WORDS:
        seg = _normalised(word, a, b, d)
        if seg is None:
            continue
        t, p, q = (v if kind == "S" else _unloop(v) for kind, v in zip(word, seg, strict=True))
        path = DubinsPath(start, word, (t * radius, p * radius, q * radius), radius)
        x, y, yaw = path.end()
        dyaw = wrap_angle(yaw - goal.yaw)
        # No path is shorter than the straight line: a full-turn arc that rounds to 0
        # (acos(1)) left a word of 0 m to a goal microns behind, ending within the
        # tolerance, whose snapped end then ran backwards (an audit).
        if path.length < d * radius - 1e-9:
            continue
        if math.hypot(x - goal.x, y - goal.y) <= tol * max(1.0, radius) and abs(dyaw) <= tol:
            # dataclasses.replace(path, goal=goal), without its generic field copying.
            out.append(DubinsPath(start, word, path.lengths, radius, goal))
    out.sort(key=lambda p: p.length)
    return out


def shortest_dubins(start: Pose, goal: Pose, radius: float) -> DubinsPath | None:
    """The shortest of :func:`dubins_paths`, or ``None`` (never for valid input)."""
    paths = dubins_paths(start, goal, radius)
    return paths[0] if paths else None
