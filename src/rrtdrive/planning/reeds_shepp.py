"""Reeds-Shepp paths: the shortest paths of bounded curvature with forward and reverse gear.

The heuristic and the analytic expansion of a planner that reverses need the shortest
path between two poses for a car that may drive either way with turning radius ``r``
(Reeds & Shepp 1990, "Optimal paths for a car that goes both forwards and backwards",
Pacific J. Math. 145(2)). A shortest path is one of five families, ``C|C|C``-type
arcs and lines with at most two cusps: CSC, CCC, CCCC, CCSC and CCSCC. Each family
is solved in the normalised frame (radius 1, the start at the origin facing +x) by
the paper's formulas 8.1-8.11 for one base word; the other words of the family
follow from the base by three symmetries of the problem:

* *timeflip* ``(x, y, phi) -> (-x, y, -phi)``: drive the word in the other gear
  (every segment length negated);
* *reflect* ``(x, y, phi) -> (x, -y, -phi)``: mirror left and right;
* *backwards* ``(x, y, phi) -> (x cos phi + y sin phi, x sin phi - y cos phi, phi)``:
  the word driven from the goal to the start (segment order reversed).

These give the 48 words of the paper, the same set as OMPL's
``ReedsSheppStateSpace`` (the tests compare the lengths with it when ``ompl`` is
installed). As in :mod:`rrtdrive.planning.dubins`, every candidate is integrated in
closed form and kept only when it ends at the goal pose, so a wrong formula cannot
return a path that does not connect.

Conventions: a segment's signed length is positive in forward gear and negative in
reverse; ``yaw`` is where the nose points in both gears, and the curvature of a
segment is that of the steering (``+1/r`` left, ``-1/r`` right, ``0`` straight),
also in reverse, so that ``d yaw = kappa * ds`` with signed ``ds``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from operator import attrgetter, itemgetter

import numpy as np

from rrtdrive.geometry import wrap_angle
from rrtdrive.types import InputError, Pose

__all__ = [
    "ReedsSheppPath",
    "ReedsSheppSegment",
    "reeds_shepp_distance",
    "reeds_shepp_paths",
    "shortest_reeds_shepp",
]

_PI = math.pi
_HALF_PI = 0.5 * math.pi
_TWO_PI = 2.0 * math.pi
#: Slack on the sign conditions of the formulas (radius 1), as in OMPL.
_ZERO = 10.0 * np.finfo(float).eps
#: Segments shorter than this (radius 1) are dropped: they would only add spurious cusps.
_TINY = 1e-10
#: Candidates whose segment lengths agree to this (radius 1) are one path.
_SAME = 1e-9
#: Steering of a segment kind: +1 left, -1 right, 0 straight.
_TURN = {"L": 1, "S": 0, "R": -1}


def _mod2pi(a: float) -> float:
    """``a`` wrapped to ``[-pi, pi]`` (the formulas' sign tests need this range)."""
    v = math.fmod(a, _TWO_PI)
    if v < -_PI:
        return v + _TWO_PI
    if v > _PI:
        return v - _TWO_PI
    return v


# --- the base words of each family (Reeds & Shepp 1990, section 8) ----------------
# Each takes the goal (x, y, phi) in the normalised start frame with sin/cos of phi
# precomputed and returns (t, u, v) or None when the word does not reach the goal.


def _lsl(x: float, y: float, phi: float, sp: float, cp: float) -> tuple | None:
    """Formula 8.1, L+ S+ L+."""
    xi, eta = x - sp, y - 1.0 + cp
    u, t = math.hypot(xi, eta), math.atan2(eta, xi)
    if t < -_ZERO:
        return None
    v = _mod2pi(phi - t)
    return (t, u, v) if v >= -_ZERO else None


def _lsr(x: float, y: float, phi: float, sp: float, cp: float) -> tuple | None:
    """Formula 8.2, L+ S+ R+."""
    xi, eta = x + sp, y - 1.0 - cp
    rho2 = xi * xi + eta * eta
    if rho2 < 4.0:
        return None
    u = math.sqrt(rho2 - 4.0)
    t = _mod2pi(math.atan2(eta, xi) + math.atan2(2.0, u))
    v = _mod2pi(t - phi)
    return (t, u, v) if t >= -_ZERO and v >= -_ZERO else None


def _lrl(x: float, y: float, phi: float, sp: float, cp: float) -> tuple | None:
    """Formulas 8.3/8.4 (with the paper's typo corrected), L+ R- L."""
    xi, eta = x - sp, y - 1.0 + cp
    rho = math.hypot(xi, eta)
    if rho > 4.0:
        return None
    u = -2.0 * math.asin(0.25 * rho)
    t = _mod2pi(math.atan2(eta, xi) + 0.5 * u + _PI)
    v = _mod2pi(phi - t + u)
    return (t, u, v) if t >= -_ZERO and u <= _ZERO else None


def _tau_omega(u: float, v: float, xi: float, eta: float, phi: float) -> tuple[float, float]:
    """The first and last arc of the CCCC words from their two middle arcs ``u``, ``v``."""
    delta = _mod2pi(u - v)
    a = math.sin(u) - math.sin(delta)
    b = math.cos(u) - math.cos(delta) - 1.0
    t1 = math.atan2(eta * a - xi * b, xi * a + eta * b)
    t2 = 2.0 * (math.cos(delta) - math.cos(v) - math.cos(u)) + 3.0
    tau = _mod2pi(t1 + _PI) if t2 < 0 else _mod2pi(t1)
    return tau, _mod2pi(tau - u + v - phi)


def _lrlr_a(x: float, y: float, phi: float, sp: float, cp: float) -> tuple | None:
    """Formula 8.7, L+ R+u L-u R- (lengths t, u, -u, v)."""
    xi, eta = x + sp, y - 1.0 - cp
    rho = 0.25 * (2.0 + math.hypot(xi, eta))
    if rho > 1.0:
        return None
    u = math.acos(rho)
    t, v = _tau_omega(u, -u, xi, eta, phi)
    return (t, u, v) if t >= -_ZERO and v <= _ZERO else None


def _lrlr_b(x: float, y: float, phi: float, sp: float, cp: float) -> tuple | None:
    """Formula 8.8, L+ R-u L-u R+ (lengths t, u, u, v)."""
    xi, eta = x + sp, y - 1.0 - cp
    rho = (20.0 - xi * xi - eta * eta) / 16.0
    if not 0.0 <= rho <= 1.0:
        return None
    u = -math.acos(rho)
    if u < -_HALF_PI:
        return None
    t, v = _tau_omega(u, u, xi, eta, phi)
    return (t, u, v) if t >= -_ZERO and v >= -_ZERO else None


def _lrsl(x: float, y: float, phi: float, sp: float, cp: float) -> tuple | None:
    """Formula 8.9, L+ R-(pi/2) S- L-."""
    xi, eta = x - sp, y - 1.0 + cp
    rho2 = xi * xi + eta * eta
    if rho2 < 4.0:
        return None
    r = math.sqrt(rho2 - 4.0)
    u = 2.0 - r
    t = _mod2pi(math.atan2(eta, xi) + math.atan2(r, -2.0))
    v = _mod2pi(phi - _HALF_PI - t)
    return (t, u, v) if t >= -_ZERO and u <= _ZERO and v <= _ZERO else None


def _lrsr(x: float, y: float, phi: float, sp: float, cp: float) -> tuple | None:
    """Formula 8.10, L+ R-(pi/2) S- R-."""
    xi, eta = x + sp, y - 1.0 - cp
    rho = math.hypot(eta, xi)
    if rho < 2.0:
        return None
    t = math.atan2(xi, -eta)
    u = 2.0 - rho
    v = _mod2pi(t + _HALF_PI - phi)
    return (t, u, v) if t >= -_ZERO and u <= _ZERO and v <= _ZERO else None


def _lrslr(x: float, y: float, phi: float, sp: float, cp: float) -> tuple | None:
    """Formula 8.11 (with the paper's typo corrected), L+ R-(pi/2) S- L-(pi/2) R+."""
    xi, eta = x + sp, y - 1.0 - cp
    rho2 = xi * xi + eta * eta
    if rho2 < 4.0:
        return None
    u = 4.0 - math.sqrt(rho2 - 4.0)
    if u > _ZERO:
        return None
    t = _mod2pi(math.atan2((4.0 - u) * xi - 2.0 * eta, -2.0 * xi + (u - 4.0) * eta))
    v = _mod2pi(t - phi)
    return (t, u, v) if t >= -_ZERO and v >= -_ZERO else None


def _reflected(word: str) -> str:
    return word.translate(str.maketrans("LR", "RL"))


#: (formula, base word, segment lengths from (t, u, v), total length from (t, u, v),
#: whether the backwards symmetry adds words). Timeflip and reflect apply to every family.
_FAMILIES = (
    (_lsl, "LSL", lambda t, u, v: (t, u, v), lambda t, u, v: abs(t) + abs(u) + abs(v), False),
    (_lsr, "LSR", lambda t, u, v: (t, u, v), lambda t, u, v: abs(t) + abs(u) + abs(v), False),
    (_lrl, "LRL", lambda t, u, v: (t, u, v), lambda t, u, v: abs(t) + abs(u) + abs(v), True),
    (
        _lrlr_a,
        "LRLR",
        lambda t, u, v: (t, u, -u, v),
        lambda t, u, v: abs(t) + 2.0 * abs(u) + abs(v),
        False,
    ),
    (
        _lrlr_b,
        "LRLR",
        lambda t, u, v: (t, u, u, v),
        lambda t, u, v: abs(t) + 2.0 * abs(u) + abs(v),
        False,
    ),
    (
        _lrsl,
        "LRSL",
        lambda t, u, v: (t, -_HALF_PI, u, v),
        lambda t, u, v: abs(t) + abs(u) + abs(v) + _HALF_PI,
        True,
    ),
    (
        _lrsr,
        "LRSR",
        lambda t, u, v: (t, -_HALF_PI, u, v),
        lambda t, u, v: abs(t) + abs(u) + abs(v) + _HALF_PI,
        True,
    ),
    (
        _lrslr,
        "LRSLR",
        lambda t, u, v: (t, -_HALF_PI, u, -_HALF_PI, v),
        lambda t, u, v: abs(t) + abs(u) + abs(v) + _PI,
        False,
    ),
)
#: (timeflip, reflect) in the order OMPL tries them.
_SYMMETRIES = ((False, False), (True, False), (False, True), (True, True))


def _transformed(
    lengths: Callable[..., tuple[float, ...]], flip: bool, back: bool
) -> Callable[..., tuple[float, ...]]:
    """``lengths`` followed by the timeflip (negate) and backwards (reverse) symmetries."""
    if flip and back:
        return lambda t, u, v: tuple(-s for s in reversed(lengths(t, u, v)))
    if flip:
        return lambda t, u, v: tuple(-s for s in lengths(t, u, v))
    if back:
        return lambda t, u, v: lengths(t, u, v)[::-1]
    return lengths


#: The 44 (formula, symmetry) evaluations, flattened once: (formula, index of the
#: transformed goal, word, signed lengths from (t, u, v), total length from (t, u, v)).
#: Goal index: 4 * backwards + symmetry, see :func:`_frames`.
_PLAN = tuple(
    (
        formula,
        4 * back + k,
        (_reflected(word) if refl else word)[:: -1 if back else 1],
        _transformed(lengths, flip, back),
        total,
    )
    for formula, word, lengths, total, has_backwards in _FAMILIES
    for back in ((0, 1) if has_backwards else (0,))
    for k, (flip, refl) in enumerate(_SYMMETRIES)
)


def _frames(x: float, y: float, phi: float) -> list[tuple[float, float, float, float, float]]:
    """The goal ``(x, y, phi, sin phi, cos phi)`` under the eight symmetries of the problem.

    Index ``4 * backwards + k`` with ``k`` indexing :data:`_SYMMETRIES`: timeflip is
    ``(-x, y, -phi)``, reflect ``(x, -y, -phi)``; backwards first maps the goal to
    ``(x cos phi + y sin phi, x sin phi - y cos phi, phi)``.
    """
    sp, cp = math.sin(phi), math.cos(phi)
    xb, yb = x * cp + y * sp, x * sp - y * cp
    return [
        (x, y, phi, sp, cp),
        (-x, y, -phi, -sp, cp),
        (x, -y, -phi, -sp, cp),
        (-x, -y, phi, sp, cp),
        (xb, yb, phi, sp, cp),
        (-xb, yb, -phi, -sp, cp),
        (xb, -yb, -phi, -sp, cp),
        (-xb, -yb, phi, sp, cp),
    ]


def _raw_candidates(x: float, y: float, phi: float) -> list[tuple[str, tuple[float, ...]]]:
    """Every word that the formulas solve, as (word, signed lengths at radius 1)."""
    goals = _frames(x, y, phi)
    out: list[tuple[str, tuple[float, ...]]] = []
    for formula, index, word, lengths, _ in _PLAN:
        res = formula(*goals[index])
        if res is not None:
            out.append((word, lengths(*res)))
    return out


def _shortest_length(x: float, y: float, phi: float) -> float:
    """The smallest total length (radius 1) over :func:`_raw_candidates`, without words."""
    goals = _frames(x, y, phi)
    best = math.inf
    for formula, index, _, _, total in _PLAN:
        res = formula(*goals[index])
        if res is not None:
            length = total(*res)
            if length < best:
                best = length
    return best


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
        g = self.gears
        return sum(1 for a, b in zip(g, g[1:], strict=False) if a != b)

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
        with the last segment's curvature and gear; a path of length 0 is one row with
        curvature 0 and gear +1. ``yaw`` is the nose heading, wrapped to ``[-pi, pi)``.

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
    start: Pose, goal: Pose, radius: float, tol: float = 1e-6
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
    candidates = []
    for word, lengths in _raw_candidates(x, y, phi):
        word, lengths = _tidy(word, lengths)
        candidates.append((sum(map(abs, lengths)), word, lengths))
    candidates.sort(key=itemgetter(0))  # stable: ties keep the order of _PLAN (OMPL's)
    kept: list[tuple[float, str, tuple[float, ...]]] = []
    for cand in candidates:
        if _is_copy(cand, kept) or _misses(cand[1], cand[2], x, y, phi, pos_tol, tol):
            continue
        kept.append(cand)
    out = [
        ReedsSheppPath(start, word, tuple(s * radius for s in lengths), radius, goal)
        for _, word, lengths in kept
    ]
    out.sort(key=attrgetter("length"))  # in metres: scaling may swap near-equal lengths
    return out


def _is_copy(
    cand: tuple[float, str, tuple[float, ...]], kept: list[tuple[float, str, tuple[float, ...]]]
) -> bool:
    """Whether ``cand`` equals (to 1e-9) one of ``kept``, sorted by length before it.

    Families overlap (a CCSC word whose line has length 0 is a CCC word, and the
    backwards symmetry of a symmetric word is the word itself).
    """
    total, word, lengths = cand
    for other_total, other_word, other_lengths in reversed(kept):
        if total - other_total > _SAME:
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
    return _shortest_length(*_normalised_goal(start, goal, radius)) * radius
