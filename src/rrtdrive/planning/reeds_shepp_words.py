"""The Reeds-Shepp words: the paper's formulas and their symmetries, at radius 1.

Reeds & Shepp (1990, "Optimal paths for a car that goes both forwards and backwards",
Pacific J. Math. 145(2)) show that a shortest path of a car with turning radius 1 that
may drive either way is one of five families of arcs (C) and lines (S) with at most
two cusps (``|``): CSC, CCC, CCCC, CCSC and CCSCC. Each family is solved in the
normalised frame (the start at the origin facing +x, the goal at ``(x, y, phi)``) by
the paper's formulas 8.1-8.11 for one base word; the other words follow from the
base by three symmetries of the problem:

* *timeflip* ``(x, y, phi) -> (-x, y, -phi)``: drive the word in the other gear
  (every segment length negated);
* *reflect* ``(x, y, phi) -> (x, -y, -phi)``: mirror left and right;
* *backwards* ``(x, y, phi) -> (x cos phi + y sin phi, x sin phi - y cos phi, phi)``:
  the word driven from the goal to the start (segment order reversed).

44 formula evaluations give the paper's 48 words (CSC 8, CCC 12, CCCC 8, CCSC 16,
CCSCC 4), the same set as OMPL's ``ReedsSheppStateSpace``, whose corrections of the
two misprints in the paper (formulas 8.3/8.4 and 8.11) are used here too.
:mod:`rrtdrive.planning.reeds_shepp` builds paths from these candidates.
"""

from __future__ import annotations

import math
from collections.abc import Callable

__all__ = ["candidates", "frames", "shortest_length"]

_PI = math.pi
_HALF_PI = 0.5 * math.pi
_TWO_PI = 2.0 * math.pi
#: Slack on the sign conditions of the formulas (radius 1). OMPL's 10 eps is too tight: a
#: segment of length 0 comes out as -1e-13 when float noise (1e-16 of the goal's frame)
#: is divided by a short neighbour (atan2(1e-15, 0.013)), and the word is lost (a straight
#: then an arc gave LRLR 7 % longer). A segment this short is dropped (``_tidy``'s 1e-10)
#: and every word is checked to reach the goal.
_ZERO = 1e-10
#: A goal's lateral offset or heading change (radius 1) within this of 0 is float noise
#: of the frame's cos and sin (2e-15 at 100 m, 3e-13 at 10 km from the origin): taken as 0.
_SNAP = 1e-12


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
#: Goal index: 4 * backwards + symmetry, see :func:`frames`.
_PLAN = tuple(
    (
        formula,
        4 * back + k,
        (_reflected(word) if refl else word)[:: -1 if back else 1],
        _transformed(lengths, flip, bool(back)),
        total,
    )
    for formula, word, lengths, total, has_backwards in _FAMILIES
    for back in ((0, 1) if has_backwards else (0,))
    for k, (flip, refl) in enumerate(_SYMMETRIES)
)


def frames(x: float, y: float, phi: float) -> list[tuple[float, float, float, float, float]]:
    """The goal ``(x, y, phi, sin phi, cos phi)`` under the eight symmetries of the problem.

    Index ``4 * backwards + k`` with ``k`` indexing :data:`_SYMMETRIES`: timeflip is
    ``(-x, y, -phi)``, reflect ``(x, -y, -phi)``; backwards first maps the goal to
    ``(x cos phi + y sin phi, x sin phi - y cos phi, phi)``. A ``y`` or ``phi`` (wrapped)
    within :data:`_SNAP` of 0 is taken as 0.

    Examples
    --------
    >>> frames(-0.0016, -1.5e-16, 0.0)[1][:3]  # a goal just behind, as cos/sin put it
    (0.0016, 0.0, -0.0)
    """
    # Float noise (1e-16 of a radius) in y or phi turns a short straight into no CSC word:
    # over a goal 0.01 m ahead, atan2(1e-16, 0.0016) fails the sign tests' _ZERO.
    if abs(y) <= _SNAP:
        y = 0.0
    if abs(_mod2pi(phi)) <= _SNAP:
        phi = 0.0
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


def candidates(x: float, y: float, phi: float) -> list[tuple[str, tuple[float, ...]]]:
    """Every word that the formulas solve, as (word, signed lengths at radius 1)."""
    goals = frames(x, y, phi)
    out: list[tuple[str, tuple[float, ...]]] = []
    for formula, index, word, lengths, _ in _PLAN:
        res = formula(*goals[index])
        if res is not None:
            out.append((word, lengths(*res)))
    return out


def shortest_length(x: float, y: float, phi: float) -> float:
    """The smallest total length (radius 1) over :func:`candidates`, without words."""
    goals = frames(x, y, phi)
    best = math.inf
    for formula, index, _, _, total in _PLAN:
        res = formula(*goals[index])
        if res is not None:
            length = total(*res)
            if length < best:
                best = length
    return best
