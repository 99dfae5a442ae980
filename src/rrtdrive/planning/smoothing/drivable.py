"""The guarantee (SPEC §3 items 9-10): a tree path in, a drivable curve or an honest failure out.

:func:`make_drivable` builds the key polygon (:mod:`.corners`), then runs one
orchestrating loop: fit the curve -- clothoid turns (:mod:`.clothoid_curve`, the
default) or the control points and the B-spline (:mod:`.curve`) -- check the
curvature (and, for clothoids, the sharpness) and the body, and hand every corner
or leg that breaks a limit to its next repair (:mod:`.repair`), until the curve
passes or the rounds or the repairs run out.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from rrtdrive.planning.smoothing.checks import CheckerView, EdgeCache, PathChecker
from rrtdrive.planning.smoothing.clothoid import ClothoidTurn
from rrtdrive.planning.smoothing.clothoid_curve import ClothoidFitter
from rrtdrive.planning.smoothing.config import SmoothingConfig, SmoothingResult
from rrtdrive.planning.smoothing.corners import (
    Corner,
    CornerKind,
    Ends,
    KeyPolygon,
    build_key_polygon,
)
from rrtdrive.planning.smoothing.curve import CurveFitter
from rrtdrive.planning.smoothing.repair import Repairer
from rrtdrive.types import Pose

__all__ = ["make_drivable"]

@dataclass(frozen=True, eq=False)
class _Attempt:
    """Outcome of one pruning setting: the result when it passed, else why not."""

    result: SmoothingResult | None
    message: str
    control_points: np.ndarray | None
    key_points: np.ndarray
    rounds: int


@dataclass(frozen=True, eq=False)
class _Shared:
    """Memos of one :func:`make_drivable` call, shared by its attempts (one config)."""

    turns: dict[tuple, list[ClothoidTurn]] = field(default_factory=dict)
    rows: dict[tuple[bytes, float], np.ndarray] = field(default_factory=dict)
    tangents: dict[tuple[float, float], float] = field(default_factory=dict)


def make_drivable(
    raw: np.ndarray,
    start: Pose,
    goal: Pose,
    checker: PathChecker,
    config: SmoothingConfig | None = None,
) -> SmoothingResult:
    """Turn a collision-free tree path into a drivable, curvature-bounded path.

    With ``config.curve = CurveKind.CLOTHOID`` (the default) every corner of the
    key polygon becomes a symmetric clothoid turn: the curvature is continuous, 0
    at both ends, at most ``kappa_safety * kappa_max``, and the steering rate per
    metre ``|d delta / ds|`` at most ``max_sharpness`` (both exact per turn; each
    turn takes the gentlest of :func:`sharpness_levels` that fits its legs, and the
    tightest after a collision). The loop and the repairs below are the same, with
    the turn's tangent length as its reach. ``CurveKind.BSPLINE`` is the paper's:

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
    >>> res.ok, bool(res.max_curvature <= 1 / 6), bool(res.max_sharpness <= 0.2)
    (True, True, True)
    """
    cfg = config or SmoothingConfig()
    raw = np.asarray(raw, dtype=float).reshape(-1, 2)
    if len(raw) < 2:
        return _failure("the tree path needs at least two points", None, np.zeros((0, 2)), 0)
    ends = Ends.of(start, goal)
    view = CheckerView(checker)
    # The attempts below share the clothoid turns and sampled rows (pure functions of
    # their keys) and the repairs' tangent lengths: the second meets many of the first's.
    shared = _Shared()
    rounds = 0
    last: _Attempt | None = None
    # The paper's pruning first; if that cannot be made drivable, a pruning that
    # avoids hairpins (turns above unprune_turn) gets its own round budget.
    for max_turn in (None, cfg.unprune_turn) if cfg.prune else (None,):
        last = _attempt(raw, ends, view, cfg, max_turn, shared)
        rounds += last.rounds
        if last.result is not None:
            return dataclasses.replace(last.result, rounds=rounds)
    assert last is not None
    return _failure(last.message, last.control_points, last.key_points, rounds)


def _failure(
    msg: str, ctrl: np.ndarray | None, key_points: np.ndarray, rounds: int
) -> SmoothingResult:
    return SmoothingResult(
        False,
        np.zeros((0, 4)),
        np.zeros((0, 2)) if ctrl is None else ctrl,
        key_points,
        rounds,
        math.inf,
        f"post-processing failed: {msg}",
    )


def _attempt(
    raw: np.ndarray,
    ends: Ends,
    view: CheckerView,
    cfg: SmoothingConfig,
    max_turn: float | None,
    shared: _Shared,
) -> _Attempt:
    """One attempt of :func:`make_drivable` with the pruning turn limit ``max_turn``."""
    edges = EdgeCache(view)
    poly = _initial_polygon(raw, ends, edges, cfg, max_turn)
    if isinstance(poly, str):
        return _Attempt(None, poly, None, np.zeros((0, 2)), 0)
    poly = _lengthen_heading_legs(poly, raw, ends, edges, cfg, max_turn)
    repairer = Repairer(poly, ends, edges, cfg, shared.tangents)
    if cfg.clothoid:
        fitter = ClothoidFitter(cfg, view, ends, turns=shared.turns, rows=shared.rows)
        return _clothoid_loop(repairer, fitter, cfg)
    return _repair_loop(repairer, CurveFitter(cfg, view, ends), cfg)


def _initial_polygon(
    raw: np.ndarray, ends: Ends, edges: EdgeCache, cfg: SmoothingConfig, max_turn: float | None
) -> KeyPolygon | str:
    """The key polygon with the longest heading legs that fit, or why none does."""
    straight = float(np.hypot(*(ends.g - ends.s)))
    reason = "no heading legs fit"
    for d in (cfg.heading_leg, cfg.heading_leg / 2.0, cfg.heading_leg / 4.0, 0.5):
        d = min(d, 0.45 * straight) if straight > 0 else d
        if d <= 0.05:
            continue
        poly = build_key_polygon(raw, ends, d, d, edges, cfg, max_turn)
        if not isinstance(poly, str):
            return poly
        reason = poly
    return reason


def _lengthen_heading_legs(
    poly: KeyPolygon,
    raw: np.ndarray,
    ends: Ends,
    edges: EdgeCache,
    cfg: SmoothingConfig,
    max_turn: float | None,
) -> KeyPolygon:
    """Lengthen the heading legs to what the turns after them need (a few re-prunes)."""
    r_design = cfg.design_radius
    for _ in range(3):
        reach_s, reach_g = poly.heading_reach(r_design, cfg)
        cap = 4.0 * r_design  # a turn needing more is a hairpin: left to the repairs
        want_s = reach_s + 0.5 if reach_s + cfg.end_gap > poly.d_s and reach_s < cap else poly.d_s
        want_g = reach_g + 0.5 if reach_g + cfg.end_gap > poly.d_g and reach_g < cap else poly.d_g
        if want_s == poly.d_s and want_g == poly.d_g:
            break
        before = poly.heading_turns()
        longer = build_key_polygon(raw, ends, want_s, want_g, edges, cfg, max_turn)
        if isinstance(longer, str) or any(
            t > max(b, cfg.hairpin_turn)
            for t, b in zip(longer.heading_turns(), before, strict=True)
        ):
            # Blocked, or the longer leg overshoots the next turn into a hairpin.
            break
        poly = longer
    return poly


def _repair_loop(repairer: Repairer, fitter: CurveFitter, cfg: SmoothingConfig) -> _Attempt:
    """Fit, check, repair, until the curve passes or the rounds or repairs run out."""
    corners = repairer.corners
    ctrl = np.zeros((0, 2))
    message = f"no drivable curve within {cfg.max_rounds} repair rounds"
    rounds = 0
    while rounds < cfg.max_rounds:
        rounds += 1
        ctrl, owner, conflicts = fitter.control_points(corners)
        if conflicts:
            failed = _fix_conflicts(repairer, conflicts)
            if failed is not None:
                message = turns_too_close(corners, failed, fitter.leg_room(corners, failed))
                break
            continue
        if len(ctrl) <= cfg.degree:
            message = "too few control points"
            break
        bad, max_k, spl = fitter.check_curvature(ctrl, owner, len(corners))
        what = "curvature"
        if not bad:
            bad, dense, u = fitter.check_collision(spl, owner, len(corners))
            what = "collision"
            if not bad:
                samples = fitter.output_samples(spl, dense, u)
                key = _key_points(repairer)
                ok = SmoothingResult(True, samples, ctrl, key, rounds, max_k, "", _stats(repairer))
                return _Attempt(ok, "", ctrl, ok.key_points, rounds)
        stuck = _advance_all(repairer, bad)
        if stuck is not None:
            message = _unrepaired(what, stuck)
            break
    return _Attempt(None, message, ctrl, _key_points(repairer), rounds)


def _clothoid_loop(repairer: Repairer, fitter: ClothoidFitter, cfg: SmoothingConfig) -> _Attempt:
    """:func:`_repair_loop` for clothoid curves: build, check limits and body, repair."""
    corners = repairer.corners
    message = f"no drivable curve within {cfg.max_rounds} repair rounds"
    rounds = 0
    while rounds < cfg.max_rounds:
        rounds += 1
        curve, conflicts = fitter.build(corners)
        if curve is None:
            failed = _fix_conflicts(repairer, conflicts)
            if failed is not None:
                message = turns_too_close(corners, failed, fitter.leg_room(corners, failed))
                message += slow_steering_note(cfg)
                break
            continue
        bad = fitter.check_limits(curve, len(corners))
        what = "curvature or sharpness"
        if not bad:
            bad, _ = fitter.check_collision(curve, len(corners))
            what = "collision"
            if not bad:
                samples = fitter.output_samples(curve)
                key = _key_points(repairer)
                stats = _stats(repairer)
                stats["tight_turns"] = float(sum(c.tight for c in corners[1:-1]))
                ok = SmoothingResult(
                    True, samples, key, key, rounds, curve.max_curvature, "", stats,
                    curve.max_sharpness,
                )  # fmt: skip
                return _Attempt(ok, "", key, key, rounds)
        stuck = _advance_all(repairer, bad)
        if stuck is not None:
            message = _unrepaired(what, stuck)
            break
    key = _key_points(repairer)
    return _Attempt(None, message, key, key, rounds)


def turns_too_close(
    corners: Sequence[Corner], leg: int, room: tuple[float, float, float, float]
) -> str:
    """The failure message of a leg too short for the turns at its ends, with the numbers.

    ``room``: the leg's length, what its turns need and their signed angles
    (:meth:`~.clothoid_curve.ClothoidFitter.leg_room`). The start's and the goal's
    corners do not turn: there the need is the one turn's room from (or to) the pose's
    heading (it read "the turns at (3.0, 6.0) and (9.9, 6.0) are too close", the first
    one the start; a new user's find).

    Examples
    --------
    >>> import numpy as np
    >>> pts = [(3.0, 6.0), (9.8, 6.0), (10.0, 13.4)]
    >>> kinds = [CornerKind.START, CornerKind.NODE, CornerKind.GOAL]
    >>> cs = [Corner.at(np.array(p), k, i) for i, (p, k) in enumerate(zip(pts, kinds))]
    >>> print(turns_too_close(cs, 0, (6.8, 7.4, 0.0, 1.54)))  # doctest: +NORMALIZE_WHITESPACE
    the path the tree found turns 88 deg left at (9.8, 6.0), 6.8 m after the start; from
    the start's heading the car's tightest turn needs 7.4 m
    """
    length, need, turn_a, turn_b = room
    a, b = corners[leg].point, corners[leg + 1].point
    at_a, at_b = f"({a[0]:.1f}, {a[1]:.1f})", f"({b[0]:.1f}, {b[1]:.1f})"
    if not math.isfinite(need):  # a repeated point: no direction to turn from
        return f"the turns at {at_a} and {at_b} are too close for the car"
    found = "the path the tree found turns"
    if corners[leg].kind is CornerKind.START and turn_b:
        return (
            f"{found} {_turn_words(turn_b)} at {at_b}, {length:.1f} m after the start; "
            + _hairpin(
                turn_b, f"from the start's heading the car's tightest turn needs {need:.1f} m"
            )
        )
    if corners[leg + 1].kind is CornerKind.GOAL and turn_a:
        return (
            f"{found} {_turn_words(turn_a)} at {at_a}, {length:.1f} m before the goal; "
            + _hairpin(
                turn_a, f"onto the goal's heading the car's tightest turn needs {need:.1f} m"
            )
        )
    return (
        f"{found} {_turn_words(turn_a)} at {at_a} and {_turn_words(turn_b)} at {at_b}, "
        f"{length:.1f} m apart; "
        + _hairpin(
            max(turn_a, turn_b, key=abs),
            f"the car's tightest turns need {need:.1f} m between them",
        )
    )


def slow_steering_note(cfg: SmoothingConfig) -> str:
    """Why the turns need that much room, when it is the steering rate: else ``""``.

    The wheels turn at most ``max_sharpness`` radians a metre (a slow actuator's rate
    at the planning speed), so a turn spends metres getting to full lock and back; a
    0.01 rad/s car's bay failed on "turns need 68.7 m" without naming its steering.
    Said when going from straight to full lock takes longer than the turning radius.

    Examples
    --------
    >>> slow = SmoothingConfig(kappa_max=1 / 6, wheelbase=2.5, max_sharpness=0.005,
    ...                        min_sharpness=0.005)
    >>> print(slow_steering_note(slow))  # doctest: +NORMALIZE_WHITESPACE
    (the car's steering rate bounds the turns: 0.005 rad of steering a metre, so 79 m
    of road from straight to full lock; a faster actuator turns in less)
    >>> slow_steering_note(SmoothingConfig(kappa_max=1 / 6, wheelbase=2.5))
    ''
    """
    full_lock = math.atan(cfg.wheelbase * cfg.kappa_max)
    run = full_lock / cfg.max_sharpness
    if run <= 1.0 / cfg.kappa_max:
        return ""
    return (
        f" (the car's steering rate bounds the turns: {cfg.max_sharpness:g} rad of steering "
        f"a metre, so {run:.0f} m of road from straight to full lock; a faster actuator "
        "turns in less)"
    )


#: A corner deflecting this much or more is a hairpin: rounding it needs a tangent of
#: R tan(deflection / 2), which grows without bound (6177.8 m was quoted at 179.9 deg).
HAIRPIN = math.radians(150.0)


def _hairpin(turn: float, otherwise: str) -> str:
    """``otherwise``, or for a hairpin ``turn`` the words that say no turn rounds it."""
    if abs(turn) < HAIRPIN:
        return otherwise
    return (
        f"a corner of {abs(math.degrees(turn)):.0f} deg doubles back: the car turns round "
        "only in a loop of at least its turning circle, or with gear changes"
    )


def _turn_words(angle: float) -> str:
    """A signed deflection in words: ``'88 deg left'``."""
    return f"{abs(math.degrees(angle)):.0f} deg {'left' if angle > 0 else 'right'}"


def _unrepaired(what: str, where: np.ndarray) -> str:
    """The failure message of a violation the repairs ran out of treatments for."""
    return f"could not repair a {what} violation near ({where[0]:.1f}, {where[1]:.1f})"


def _fix_conflicts(repairer: Repairer, conflicts: list[int]) -> int | None:
    """Fix every too-short leg; the first leg that cannot be fixed, or None."""
    # From the last leg backwards, so that merges and drops keep the indices of the
    # legs still to fix.
    for leg in sorted(conflicts, reverse=True):
        if leg + 1 < len(repairer.corners) and not repairer.fix_conflict(leg):
            return leg
    return None


def _advance_all(repairer: Repairer, bad: list[int]) -> np.ndarray | None:
    """Give every bad corner its next treatment; where the first exhausted one was, or None."""
    for c in sorted(bad, reverse=True):  # drops keep the smaller indices
        here = repairer.corners[c].point.copy()
        if not repairer.advance(c):
            return here
    return None


def _key_points(repairer: Repairer) -> np.ndarray:
    return np.array(repairer.poly.points())


def _stats(repairer: Repairer) -> dict[str, float]:
    """The repair counters of a passed attempt, for the planner's statistics."""
    return {
        "fillets": float(sum(c.radius > 0 for c in repairer.corners)),
        "merges": float(repairer.merges),
        "moves": float(repairer.moves),
        "drops": float(repairer.drops),
        "unprunes": float(repairer.unprunes),
        "edge_checks": float(repairer.edges.checks),
    }
