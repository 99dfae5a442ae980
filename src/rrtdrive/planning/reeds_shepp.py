"""Reeds-Shepp paths: the shortest paths of bounded curvature with forward and reverse gear.

The heuristic and the analytic expansion of a planner that reverses need the shortest
path between two poses for a car that may drive either way with turning radius ``r``
(Reeds & Shepp 1990). The candidate words and their lengths at radius 1 come from
:mod:`rrtdrive.planning.reeds_shepp_words` (the paper's formulas with the timeflip,
reflect and backwards symmetries, the 48 words of OMPL's ``ReedsSheppStateSpace``;
the tests compare the lengths with OMPL's when ``ompl`` is installed). This module
scales them, drops zero-length segments and copies, and, as
:mod:`rrtdrive.planning.dubins` does, integrates every candidate in closed form and
keeps it only when it ends at the goal pose, so a wrong formula cannot return a path
that does not connect. For many lengths at once, or a cached table of them for a
heuristic, see :mod:`rrtdrive.planning.reeds_shepp_table`.

Conventions: a segment's signed length is positive in forward gear and negative in
reverse; ``yaw`` is where the nose points in both gears, and the curvature of a
segment is that of the steering (``+1/r`` left, ``-1/r`` right, ``0`` straight),
also in reverse, so that ``d yaw = kappa * ds`` with signed ``ds``.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from operator import itemgetter

import numpy as np

from rrtdrive.geometry import wrap_angle
from rrtdrive.planning.reeds_shepp_words import candidates, shortest_length
from rrtdrive.types import InputError, Pose

__all__ = [
    "ReedsSheppPath",
    "ReedsSheppSegment",
    "reeds_shepp_distance",
    "reeds_shepp_paths",
    "shortest_reeds_shepp",
]

#: Segments shorter than this (radius 1) are dropped: they would only add spurious cusps.
_TINY = 1e-10
#: Candidates whose segment lengths agree to this (radius 1) are one path.
_SAME = 1e-9
#: Relative slack of ``limit`` in :func:`reeds_shepp_paths` (far above float rounding).
_LIMIT_SLACK = 1e-9
#: Steering of a segment kind: +1 left, -1 right, 0 straight.
_TURN = {"L": 1, "S": 0, "R": -1}


def _tidy(word: str, lengths: tuple[float, ...]) -> tuple[str, tuple[float, ...]]:
    """Drop zero-length segments and merge neighbours of the same kind and gear."""
    kinds = ""
    segs: list[float] = []
    for k, s in zip(word, lengths, strict=True):
        if -_TINY <= s <= _TINY:
            continue
        if kinds and kinds[-1] == k and (segs[-1] > 0) == (s > 0):
            segs[-1] += s
        else:
            kinds += k
            segs.append(s)
    return kinds, tuple(segs)


def _advance(
    x: float, y: float, yaw: float, kind: str, seg: float, radius: float
) -> tuple[float, float, float]:
    """The pose after a segment of signed length ``seg`` (closed form)."""
    if kind == "S":
        return x + seg * math.cos(yaw), y + seg * math.sin(yaw), yaw
    kappa = _TURN[kind] / radius
    yaw1 = yaw + seg * kappa
    return (
        x + (math.sin(yaw1) - math.sin(yaw)) / kappa,
        y - (math.cos(yaw1) - math.cos(yaw)) / kappa,
        yaw1,
    )


@dataclass(frozen=True)
class ReedsSheppSegment:
    """One arc or line of a Reeds-Shepp path.

    Attributes
    ----------
    kind : str
        ``"L"`` (steering left), ``"S"`` (straight) or ``"R"`` (steering right).
    length : float
        Signed length in metres: positive in forward gear, negative in reverse.
    """

    kind: str
    length: float

    def __post_init__(self) -> None:
        if self.kind not in _TURN:
            raise InputError(f"kind: must be 'L', 'S' or 'R', got {self.kind!r}")
        if not (math.isfinite(self.length) and self.length != 0.0):
            raise InputError(f"length: must be finite and non-zero, got {self.length!r}")

    @property
    def gear(self) -> int:
        """``+1`` forward, ``-1`` reverse."""
        return 1 if self.length > 0 else -1


@dataclass(frozen=True)
class ReedsSheppPath:
    """One Reeds-Shepp word from ``start`` with turning radius ``radius``.

    Attributes
    ----------
    start : Pose
        Rear-axle start pose.
    word : str
        Segment kinds in driving order, e.g. ``"LSR"`` or ``"LRSL"`` (empty for a path
        of length 0).
    lengths : tuple of float
        Signed segment lengths in metres (negative in reverse), one per letter of
        ``word``; none is zero.
    radius : float
        Turning radius of the arcs in metres.
    goal : Pose, optional
        The pose the word was solved for (:func:`reeds_shepp_paths` sets it after
        checking that the word reaches it); the last sample is then exactly this pose
        rather than the integrated end (which differs by ~1e-12).
    """

    start: Pose
    word: str
    lengths: tuple[float, ...]
    radius: float
    goal: Pose | None = None

    def __post_init__(self) -> None:
        if len(self.word) != len(self.lengths):
            raise InputError(
                f"lengths: {len(self.lengths)} values for the {len(self.word)} segments "
                f"of word {self.word!r}"
            )
        if not (math.isfinite(self.radius) and self.radius > 0):
            raise InputError(f"radius: must be > 0, got {self.radius!r}")

    @property
    def segments(self) -> tuple[ReedsSheppSegment, ...]:
        """The segments in driving order (kind, signed length, gear)."""
        return tuple(ReedsSheppSegment(k, s) for k, s in zip(self.word, self.lengths, strict=True))

    @property
    def length(self) -> float:
        """Total length in metres (reverse segments count positively)."""
        return float(sum(abs(s) for s in self.lengths))

    @property
    def gears(self) -> tuple[int, ...]:
        """Gear of each segment, ``+1`` forward, ``-1`` reverse."""
        return tuple(1 if s > 0 else -1 for s in self.lengths)

    @property
    def gear_changes(self) -> int:
        """Number of cusps (changes of gear between consecutive segments)."""
        return _gear_changes(self.lengths)

    def end(self) -> tuple[float, float, float]:
        """Pose ``(x, y, yaw)`` at the end of the path, integrated (yaw unwrapped)."""
        x, y, yaw = self.start.x, self.start.y, self.start.yaw
        for kind, seg in zip(self.word, self.lengths, strict=True):
            x, y, yaw = _advance(x, y, yaw, kind, seg, self.radius)
        return x, y, yaw

    def sample(self, spacing: float) -> np.ndarray:
        """Rows ``[x, y, yaw, kappa, gear]``, at most ``spacing`` apart along each segment.

        Both ends of every segment are included. Within a gear, a junction is one row
        carrying the curvature of the segment that starts there; at a cusp the end row
        of the segment before (its curvature, its gear) is followed by the same position
        with the next segment's curvature and gear. The last row is the goal (when set)
        with the last segment's curvature and gear; a path of length 0 (a goal within
        1e-10 radius of the start) is one row, the start, with curvature 0 and gear +1.
        ``yaw`` is the nose heading, wrapped to ``[-pi, pi)``.

        Parameters
        ----------
        spacing : float
            Largest arc length between consecutive rows, in metres (> 0).

        Returns
        -------
        numpy.ndarray
            Shape ``(N, 5)``.

        Examples
        --------
        >>> p = shortest_reeds_shepp(Pose(0.0, 0.0, 0.0), Pose(-3.0, 0.0, 0.0), 5.0)
        >>> p.sample(1.0)[[0, -1]].round(6).tolist()
        [[0.0, 0.0, 0.0, 0.0, -1.0], [-3.0, 0.0, 0.0, 0.0, -1.0]]
        """
        if not spacing > 0:
            raise InputError(f"spacing: must be > 0, got {spacing!r}")
        x, y, yaw = self.start.x, self.start.y, self.start.yaw
        if not self.word:
            return np.array([[x, y, wrap_angle(yaw), 0.0, 1.0]])
        blocks = []
        last = len(self.word) - 1
        for i, (kind, seg) in enumerate(zip(self.word, self.lengths, strict=True)):
            gear = 1.0 if seg > 0 else -1.0
            kappa = _TURN[kind] / self.radius
            n = max(1, math.ceil(abs(seg) / spacing))
            # Rows 0..n-1 of the segment; its own end row is the next one's start,
            # or repeated explicitly at a cusp and at the end of the path.
            ends_here = i == last or (self.lengths[i + 1] > 0) != (seg > 0)
            u = np.arange(n + 1 if ends_here else n) * (seg / n)
            if kind == "S":
                xs, ys = x + u * math.cos(yaw), y + u * math.sin(yaw)
                yaws = np.full(len(u), yaw)
            else:
                yaws = yaw + u * kappa
                xs = x + (np.sin(yaws) - math.sin(yaw)) / kappa
                ys = y - (np.cos(yaws) - math.cos(yaw)) / kappa
            block = np.empty((len(u), 5))
            block[:, 0], block[:, 1], block[:, 2] = xs, ys, yaws
            block[:, 3], block[:, 4] = kappa, gear
            x, y, yaw = _advance(x, y, yaw, kind, seg, self.radius)
            if ends_here:  # the closed-form end, not the sampled one (they agree to ~1e-15)
                block[-1, :3] = x, y, yaw
            blocks.append(block)
        out = np.vstack(blocks)
        if self.goal is not None:
            out[-1, :3] = self.goal.x, self.goal.y, self.goal.yaw
        out[:, 2] = wrap_angle(out[:, 2])
        return out


def _normalised_goal(start: Pose, goal: Pose, radius: float) -> tuple[float, float, float]:
    if not (math.isfinite(radius) and radius > 0):
        raise InputError(f"radius: must be > 0, got {radius!r}")
    dx, dy = goal.x - start.x, goal.y - start.y
    c, s = math.cos(start.yaw), math.sin(start.yaw)
    return (c * dx + s * dy) / radius, (c * dy - s * dx) / radius, goal.yaw - start.yaw


def reeds_shepp_paths(
    start: Pose,
    goal: Pose,
    radius: float,
    tol: float = 1e-6,
    limit: int | None = None,
    cusp_cost: float = 0.0,
) -> list[ReedsSheppPath]:
    """Every Reeds-Shepp word that joins ``start`` to ``goal``, shortest first.

    Parameters
    ----------
    start, goal : Pose
        Rear-axle poses; ``yaw`` is the nose heading in both gears.
    radius : float
        Turning radius of the arcs in metres (> 0).
    tol : float
        A candidate is kept only when its integrated end lies within
        ``tol * max(1, radius)`` metres and ``tol`` radians of ``goal``.
    limit : int, optional
        Only the first ``limit`` of the list are needed: candidates clearly longer
        than the ``limit``-th kept one are neither checked nor built (the first
        ``limit`` paths are those of the full list).
    cusp_cost : float, optional
        Metres added to a word's length per cusp for the order (and ``limit``): of
        two words within ``cusp_cost`` of each other, the one with fewer gear
        changes comes first. 0: by length alone.

    Returns
    -------
    list of ReedsSheppPath
        Distinct candidates (zero-length segments dropped, equal neighbours merged),
        sorted by length; never empty for valid input.

    Examples
    --------
    >>> paths = reeds_shepp_paths(Pose(0.0, 0.0, 0.0), Pose(0.0, 2.0, 0.0), 4.0)
    >>> best = paths[0]
    >>> best.gear_changes > 0, round(best.length, 6) == round(reeds_shepp_distance(
    ...     Pose(0.0, 0.0, 0.0), Pose(0.0, 2.0, 0.0), 4.0), 6)
    (True, True)
    """
    x, y, phi = _normalised_goal(start, goal, radius)
    pos_tol = tol * max(1.0, radius) / radius  # in the normalised frame
    found = []
    per_cusp = cusp_cost / radius  # in the normalised frame
    for word, lengths in candidates(x, y, phi):
        word, lengths = _tidy(word, lengths)
        cost = sum(map(abs, lengths))
        if per_cusp:
            cost += per_cusp * _gear_changes(lengths)
        found.append((cost, word, lengths))
    found.sort(key=itemgetter(0))  # stable: ties keep the order of the words (OMPL's)
    kept: list[tuple[float, str, tuple[float, ...]]] = []
    bound = math.inf
    for cand in found:
        if cand[0] > bound:
            break
        if _is_copy(cand, kept) or _misses(cand[1], cand[2], x, y, phi, pos_tol, tol):
            continue
        kept.append(cand)
        if limit is not None and len(kept) == limit:
            # Lengths in metres are these times the radius, to a few ulp: beyond this
            # margin no later candidate can sort before the ``limit``-th.
            bound = cand[0] * (1.0 + _LIMIT_SLACK) + _LIMIT_SLACK
    out = [
        ReedsSheppPath(start, word, tuple(s * radius for s in lengths), radius, goal)
        for _, word, lengths in kept
    ]
    # In metres: scaling may swap near-equal lengths (cusp_cost 0 adds exactly 0).
    out.sort(key=lambda p: p.length + cusp_cost * p.gear_changes)
    return out


def _gear_changes(lengths: tuple[float, ...]) -> int:
    """Cusps of a word: consecutive signed segment lengths of opposite signs."""
    return sum(1 for a, b in itertools.pairwise(lengths) if (a > 0) != (b > 0))


def _is_copy(
    cand: tuple[float, str, tuple[float, ...]], kept: list[tuple[float, str, tuple[float, ...]]]
) -> bool:
    """Whether ``cand`` equals (to 1e-9) one of ``kept``, sorted by length before it.

    Families overlap (a CCSC word whose line has length 0 is a CCC word, and the
    backwards symmetry of a symmetric word is the word itself).
    """
    total, word, lengths = cand
    for other_total, other_word, other_lengths in reversed(kept):
        if total - other_total > 5 * _SAME:  # 5 segments, each within _SAME
            return False
        if other_word == word and all(
            abs(a - b) <= _SAME for a, b in zip(lengths, other_lengths, strict=True)
        ):
            return True
    return False


def _misses(
    word: str,
    lengths: tuple[float, ...],
    x: float,
    y: float,
    phi: float,
    pos_tol: float,
    tol: float,
) -> bool:
    """Whether the word, integrated from the origin at radius 1, misses the goal ``(x, y, phi)``."""
    ex = ey = eyaw = 0.0
    for kind, seg in zip(word, lengths, strict=True):
        if kind == "S":
            ex += seg * math.cos(eyaw)
            ey += seg * math.sin(eyaw)
        else:
            turn = _TURN[kind]
            yaw1 = eyaw + seg * turn
            ex += (math.sin(yaw1) - math.sin(eyaw)) * turn
            ey -= (math.cos(yaw1) - math.cos(eyaw)) * turn
            eyaw = yaw1
    return math.hypot(ex - x, ey - y) > pos_tol or abs(wrap_angle(eyaw - phi)) > tol


def shortest_reeds_shepp(start: Pose, goal: Pose, radius: float) -> ReedsSheppPath | None:
    """The shortest of :func:`reeds_shepp_paths`, or ``None`` (never for valid input).

    Examples
    --------
    >>> p = shortest_reeds_shepp(Pose(0.0, 0.0, 0.0), Pose(10.0, 0.0, 0.0), 2.0)
    >>> p.word, p.lengths, p.gear_changes
    ('S', (10.0,), 0)
    """
    paths = reeds_shepp_paths(start, goal, radius)
    return paths[0] if paths else None


def reeds_shepp_distance(start: Pose, goal: Pose, radius: float) -> float:
    """Length in metres of the shortest Reeds-Shepp path, without building paths.

    The same minimum as :func:`shortest_reeds_shepp` (``.length``), for heuristics
    that need only the number.

    Examples
    --------
    >>> round(reeds_shepp_distance(Pose(0.0, 0.0, 0.0), Pose(-3.0, 0.0, 0.0), 5.0), 6)
    3.0
    """
    return shortest_length(*_normalised_goal(start, goal, radius)) * radius
