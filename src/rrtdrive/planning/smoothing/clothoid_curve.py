"""From the key polygon to a checked continuous-curvature curve: straight legs and clothoid turns.

Every interior corner becomes a symmetric clothoid turn (:mod:`.clothoid`) of its
corner's radius. Its sharpness is chosen per corner from
:func:`~rrtdrive.planning.smoothing.clothoid.sharpness_levels`: the gentlest whose
tangent length fits the corner's share of both its legs (two corners on one leg
split its spare length), or the tightest when the corner is ``tight``. A leg too
short for the tightest turns at its ends is a conflict for the repairs.

The guarantee is checked exactly: the curvature of each turn is its arc's, its
largest ``|d delta / ds|`` is ``L sigma`` (where ``kappa = 0``); the body with the
checker's exact test at poses at most ``check_spacing`` apart in arc length.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from rrtdrive.geometry import wrap_angle
from rrtdrive.planning.smoothing.checks import CheckerView
from rrtdrive.planning.smoothing.clothoid import (
    ClothoidTurn,
    clothoid_turn,
    clothoid_turns,
    sample_turn,
    sharpness_levels,
)
from rrtdrive.planning.smoothing.config import SmoothingConfig
from rrtdrive.planning.smoothing.corners import (
    Corner,
    Ends,
    polygon_legs,
    signed_deflection,
    unit,
)

__all__ = [
    "Piece",
    "ClothoidCurve",
    "ClothoidFitter",
    "polygon_turns",
    "polygon_curve",
    "sample_pieces",
]


class Piece(NamedTuple):
    """One piece of the curve: a line (``turn`` None) or a turn, from a start pose."""

    owner: int
    x: float
    y: float
    yaw: float
    length: float
    turn: ClothoidTurn | None

    def rows(self, s: np.ndarray) -> np.ndarray:
        """Rows ``[x, y, yaw, kappa]`` at arc lengths ``s`` into the piece."""
        c, sn = math.cos(self.yaw), math.sin(self.yaw)
        if self.turn is None:
            return np.column_stack(
                [self.x + s * c, self.y + s * sn, np.full(len(s), self.yaw), np.zeros(len(s))]
            )
        local = sample_turn(self.turn, s)
        out = np.empty_like(local)
        out[:, 0] = self.x + c * local[:, 0] - sn * local[:, 1]
        out[:, 1] = self.y + sn * local[:, 0] + c * local[:, 1]
        out[:, 2] = self.yaw + local[:, 2]
        out[:, 3] = local[:, 3]
        return out

    def key(self) -> bytes:
        """Identity of the piece's geometry, for the cache of pieces proven free."""
        t = self.turn
        extra = (0.0, 0.0, 0.0) if t is None else (t.theta, t.sigma, t.kappa)
        return np.array([self.x, self.y, self.yaw, self.length, *extra]).tobytes()


class ClothoidCurve(NamedTuple):
    """The pieces in driving order, the polygon they round, and their exact limits."""

    pieces: list[Piece]
    polygon: np.ndarray
    max_curvature: float
    max_sharpness: float


def sample_pieces(
    pieces: Sequence[Piece],
    spacing: float,
    cache: dict[tuple[bytes, float], np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Rows at most ``spacing`` apart in arc length (each piece's ends included), and owners.

    ``cache`` keeps each piece's rows (by its geometry and the spacing) between calls:
    a repair round changes a few corners and keeps the other pieces.
    """
    rows: list[np.ndarray] = []
    owners: list[np.ndarray] = []
    for k, piece in enumerate(pieces):
        full = None
        if cache is not None:
            key = (piece.key(), spacing)
            full = cache.get(key)
        if full is None:
            n = max(1, math.ceil(piece.length / spacing - 1e-9))
            full = piece.rows(np.linspace(0.0, piece.length, n + 1))
            if cache is not None:
                cache[key] = full
        part = full if k == 0 else full[1:]  # the previous piece ended at its start
        rows.append(part)
        owners.append(np.full(len(part), piece.owner, dtype=np.int64))
    return np.vstack(rows), np.concatenate(owners)


def polygon_turns(
    pts: Sequence[Sequence[float]],
    kappas: Sequence[float],
    levels: np.ndarray,
    tight: Sequence[bool],
    end_gap: float,
    cache: dict[tuple, list[ClothoidTurn]] | None = None,
    radius_steps: Sequence[float] = (1.0,),
) -> tuple[list[ClothoidTurn | None], list[int]]:
    """The turn at every corner of polygon ``pts``, or the legs too short for the tightest ones.

    Parameters
    ----------
    pts : sequence of (x, y)
        The polygon, start first.
    kappas : sequence of float
        Arc curvature per corner (entries 0 and -1 unused).
    levels : numpy.ndarray
        Sharpnesses to choose from, tightest first (:func:`sharpness_levels`).
    radius_steps : sequence of float
        Multiples of each corner's radius a turn that is not tight may use: it takes
        the combination of radius and sharpness with the longest tangent that fits
        its share of the legs (the gentlest turn there is room for).
    tight : sequence of bool
        Per corner: the tightest level only.
    end_gap : float
        Straight length kept at the start and the goal.
    cache : dict, optional
        Turns per ``(theta, kappa)`` (and the tightest alone per ``(theta, kappa,
        True)``), shared between calls.

    Returns
    -------
    (list, list of int)
        Per corner its turn (None at the ends and for straight corners) and the legs
        in conflict (then the turns are all None).
    """
    n = len(pts)
    cache = {} if cache is None else cache
    dirs, lengths = polygon_legs(pts)
    thetas: list[float | None] = [None] * n
    tmin = [0.0] * n
    for c in range(1, n - 1):
        thetas[c], tmin[c] = _corner_tightest(dirs, lengths, c, kappas[c], levels, cache)
    gaps = _end_gaps(tmin, end_gap)
    conflicts = [
        i for i in range(n - 1) if not tmin[i] + tmin[i + 1] + gaps[i] <= lengths[i] + 1e-9
    ]
    if conflicts:
        return [None] * n, conflicts
    # Only now the gentler options (most calls of a repair loop end in a conflict,
    # which the tightest turns alone decide).
    options: list[list[ClothoidTurn] | None] = [None] * n
    for c in range(1, n - 1):
        angle = thetas[c]
        if angle is None:
            continue
        if tight[c]:
            options[c] = [_tightest(cache, angle, kappas[c], levels)]
            continue
        key = (angle, float(kappas[c]))
        opts = cache.get(key)
        if opts is None:
            # Every radius step x sharpness level, by tangent length: the first, the
            # tightest (the corner's radius, the sharpest level), reaches least.
            tight_turn = _tightest(cache, angle, kappas[c], levels)
            steps = np.repeat(np.asarray(radius_steps, dtype=float), len(levels))
            rest = clothoid_turns(angle, kappas[c] / steps, np.tile(levels, len(radius_steps)))
            opts = cache[key] = [tight_turn] + sorted(
                (t for t in rest if t.tangent > tight_turn.tangent), key=lambda t: t.tangent
            )
        options[c] = opts
    chosen = [0.0] * n
    flexible = [o is not None and len(o) > 1 for o in options]
    # A fair first share: each flexible corner gets half the spare length of a leg it
    # shares with another flexible corner, all of it otherwise.
    for c in range(1, n - 1):
        opts = options[c]
        if opts is None or len(opts) == 1:  # one option: chosen[c] stays 0
            continue
        room = math.inf
        for leg, other in ((c - 1, c - 1), (c, c + 1)):
            spare = lengths[leg] - tmin[leg] - tmin[leg + 1] - gaps[leg]
            room = min(room, tmin[c] + (0.5 * spare if flexible[other] else spare))
        chosen[c] = _gentlest(opts, room)
    # Then each, in turn, takes what its neighbours left.
    for c in range(1, n - 1):
        opts = options[c]
        if opts is None or not flexible[c]:
            continue
        room = min(
            lengths[c - 1] - _tangent(options, chosen, c - 1) - gaps[c - 1],
            lengths[c] - _tangent(options, chosen, c + 1) - gaps[c],
        )
        chosen[c] = _gentlest(opts, room)
    turns: list[ClothoidTurn | None] = [None] * n
    for c in range(1, n - 1):
        opts = options[c]
        if opts is not None:
            turns[c] = opts[int(chosen[c])]
    return turns, []


def _corner_tightest(
    dirs: Sequence[tuple[float, float]],
    lengths: Sequence[float],
    c: int,
    kappa: float,
    levels: np.ndarray,
    cache: dict[tuple, list[ClothoidTurn]],
) -> tuple[float | None, float]:
    """Inner corner ``c``'s deflection (None when straight) and its tightest turn's tangent."""
    if lengths[c - 1] == 0.0 or lengths[c] == 0.0:
        return None, math.inf  # a repeated point: no direction to turn from
    theta = signed_deflection(dirs[c - 1], dirs[c])
    if abs(theta) < 1e-9:
        return None, 0.0
    return theta, _tightest(cache, theta, kappa, levels).tangent


def _end_gaps(tmin: Sequence[float], end_gap: float) -> list[float]:
    """Per leg, the straight kept before its turn: ``end_gap`` at the start and goal legs."""
    n = len(tmin)
    gaps = [0.0] * (n - 1)
    if n > 2:
        gaps[0] = end_gap if tmin[1] > 0.0 else 0.0
        gaps[-1] = end_gap if tmin[n - 2] > 0.0 else 0.0
    return gaps


def leg_room(
    pts: Sequence[Sequence[float]],
    kappas: Sequence[float],
    levels: np.ndarray,
    end_gap: float,
    leg: int,
    cache: dict[tuple, list[ClothoidTurn]] | None = None,
) -> tuple[float, float, float, float]:
    """Leg ``leg`` of polygon ``pts``: its length, what its turns need, and their angles.

    The need is :func:`polygon_turns`' test: the tightest turns' tangents at both its
    corners plus the straight kept at the start or goal. The angles are the signed
    deflections at the leg's two corners in radians (0 at an end or a straight corner).

    Examples
    --------
    >>> levels = np.array([0.08])
    >>> length, need, a, b = leg_room([(0, 0), (5, 0), (5, 5)], [0, 1 / 6, 0], levels, 0.5, 0)
    >>> length, bool(need > length), a, round(math.degrees(b))
    (5.0, True, 0.0, 90)
    """
    cache = {} if cache is None else cache
    n = len(pts)
    dirs, lengths = polygon_legs(pts)
    tmin, angles = [0.0] * n, [0.0] * n
    for c in range(1, n - 1):
        theta, tmin[c] = _corner_tightest(dirs, lengths, c, kappas[c], levels, cache)
        angles[c] = theta or 0.0
    need = tmin[leg] + tmin[leg + 1] + _end_gaps(tmin, end_gap)[leg]
    return lengths[leg], need, angles[leg], angles[leg + 1]


def _tightest(
    cache: dict[tuple, list[ClothoidTurn]], theta: float, kappa: float, levels: np.ndarray
) -> ClothoidTurn:
    """The tightest turn of a corner (its radius, the sharpest level), remembered in ``cache``."""
    opts = cache.get((theta, float(kappa)))
    if opts is None:
        tkey = (theta, float(kappa), True)
        opts = cache.get(tkey)
        if opts is None:
            opts = cache[tkey] = [clothoid_turn(theta, kappa, float(levels[0]))]
    return opts[0]


def _gentlest(opts: list[ClothoidTurn], room: float) -> int:
    """Index of the gentlest option whose tangent fits ``room`` (0, the tightest, always)."""
    best = 0
    for j, t in enumerate(opts):
        if t.tangent <= room + 1e-12:
            best = j
    return best


def _tangent(options: list[list[ClothoidTurn] | None], chosen: list[float], c: int) -> float:
    opts = options[c]
    return 0.0 if opts is None else opts[int(chosen[c])].tangent


def curve_pieces(
    pts: Sequence[Sequence[float]], turns: Sequence[ClothoidTurn | None]
) -> list[Piece]:
    """Lines and turns along polygon ``pts``; each line half is owned by its nearer corner."""
    n = len(pts)
    pieces: list[Piece] = []
    last = n - 2
    vx = vy = v_yaw = 0.0
    for i in range(n - 1):
        (x0, y0), (x1, y1) = pts[i], pts[i + 1]
        ux, uy, length = unit(x1 - x0, y1 - y0)
        yaw = math.atan2(uy, ux)
        here, after = turns[i], turns[i + 1]
        t0 = here.tangent if here is not None else 0.0
        t1 = after.tangent if after is not None else 0.0
        if i > 0 and here is not None:
            t = here
            # The incoming leg's direction and heading: the previous leg's (vx, vy, v_yaw).
            pieces.append(
                Piece(i, x0 - t.tangent * vx, y0 - t.tangent * vy, v_yaw, t.length, t)
            )
        straight = length - t0 - t1
        if straight > 1e-9:
            half = 0.5 * straight
            a = (x0 + t0 * ux, y0 + t0 * uy)
            pieces.append(Piece(min(max(i, 1), last), a[0], a[1], yaw, half, None))
            pieces.append(
                Piece(min(i + 1, last), a[0] + half * ux, a[1] + half * uy, yaw, half, None)
            )
        vx, vy, v_yaw = ux, uy, yaw
    return pieces


def polygon_curve(
    pts: np.ndarray, kappa: float, sigma: float, end_gap: float = 0.0
) -> list[Piece] | None:
    """The pieces rounding every corner of ``pts`` with the turn of ``kappa`` and ``sigma``.

    None when a leg is too short for the turns at its ends (plus ``end_gap`` at
    the first and last leg).

    Examples
    --------
    >>> pieces = polygon_curve(np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 20.0]]), 1 / 6, 0.08)
    >>> [p.turn is not None for p in pieces], round(sum(p.length for p in pieces), 3)
    ([False, False, True, False, False], 37.367)
    """
    p = np.asarray(pts, dtype=float).reshape(-1, 2).tolist()
    n = len(p)
    turns, conflicts = polygon_turns(
        p, [kappa] * n, np.array([sigma]), [True] * n, end_gap
    )
    return None if conflicts else curve_pieces(p, turns)


class ClothoidFitter:
    """Builds clothoid curves from corners and checks them, with caches for one call.

    Parameters
    ----------
    cfg : SmoothingConfig
        Tunables (``curve`` is ``CLOTHOID``).
    view : CheckerView
        The original map's checker.
    ends : Ends
        Start and goal of the path.
    turns, rows : dict, optional
        Caches of turns (:func:`polygon_turns`) and of sampled pieces
        (:func:`sample_pieces`) to share with other fitters of the same ``cfg``.
    """

    def __init__(
        self,
        cfg: SmoothingConfig,
        view: CheckerView,
        ends: Ends,
        turns: dict[tuple, list[ClothoidTurn]] | None = None,
        rows: dict[tuple[bytes, float], np.ndarray] | None = None,
    ) -> None:
        self.cfg = cfg
        self.view = view
        self.ends = ends
        self.levels = sharpness_levels(
            cfg.max_sharpness, cfg.min_sharpness, cfg.wheelbase, cfg.kappa_safety
        )
        self._turns: dict[tuple, list[ClothoidTurn]] = {} if turns is None else turns
        # Pieces proven free stay per fitter: a piece's first and last rows are pinned
        # to the end poses where it starts or ends the curve.
        self._free_pieces: set[bytes] = set()
        self._rows: dict[tuple[bytes, float], np.ndarray] = {} if rows is None else rows

    def build(self, corners: Sequence[Corner]) -> tuple[ClothoidCurve | None, list[int]]:
        """The curve of the corners, or None and the legs too short for their turns."""
        cfg = self.cfg
        pts = [c.point.tolist() for c in corners]
        r0 = cfg.design_radius
        kappas = [1.0 / (c.radius if c.radius > 0.0 else r0) for c in corners]
        turns, conflicts = polygon_turns(
            pts, kappas, self.levels, [c.tight for c in corners], cfg.end_gap, self._turns,
            cfg.gentle_radius_steps,
        )
        if conflicts:
            return None, conflicts
        pieces = curve_pieces(pts, turns)
        real = [t for t in turns if t is not None]
        max_k = max((t.kappa for t in real), default=0.0)
        max_sharp = max((cfg.wheelbase * t.sigma for t in real), default=0.0)
        return ClothoidCurve(pieces, np.array(pts), max_k, max_sharp), []

    def leg_room(self, corners: Sequence[Corner], leg: int) -> tuple[float, float, float, float]:
        """:func:`leg_room` of the corners' polygon (as :meth:`build` turns it)."""
        r0 = self.cfg.design_radius
        kappas = [1.0 / (c.radius if c.radius > 0.0 else r0) for c in corners]
        pts = [c.point.tolist() for c in corners]
        return leg_room(pts, kappas, self.levels, self.cfg.end_gap, leg, self._turns)

    def check_limits(self, curve: ClothoidCurve, n_corners: int) -> list[int]:
        """Corners whose turns exceed ``kappa_max`` or ``max_sharpness`` (exact per turn)."""
        cfg = self.cfg
        bad = {
            p.owner
            for p in curve.pieces
            if p.turn is not None
            and (p.turn.kappa > cfg.kappa_max or cfg.wheelbase * p.turn.sigma > cfg.max_sharpness)
        }
        return sorted(min(max(c, 1), n_corners - 2) for c in bad)

    def check_collision(
        self, curve: ClothoidCurve, n_corners: int
    ) -> tuple[list[int], np.ndarray]:
        """Corners whose pieces collide, and the dense poses (at most check_spacing apart)."""
        cfg, ends = self.cfg, self.ends
        dense, owner = sample_pieces(curve.pieces, cfg.check_spacing, self._rows)
        piece_of = np.concatenate(
            [np.full(max(1, math.ceil(p.length / cfg.check_spacing - 1e-9)) + (k == 0), k)
             for k, p in enumerate(curve.pieces)]
        )  # fmt: skip
        dense[0, :3] = (ends.start.x, ends.start.y, ends.start.yaw)
        dense[-1, :3] = (ends.goal.x, ends.goal.y, ends.goal.yaw)
        dense[:, 2] = wrap_angle(dense[:, 2])
        poses_free = self.view.poses_free()
        if poses_free is None:
            free, bad_seg = self.view.path_free(
                dense, spacing=cfg.check_spacing, clearance=cfg.clearance
            )
            if free:
                return [], dense
            hit = np.unique(np.concatenate([bad_seg, np.minimum(bad_seg + 1, len(dense) - 1)]))
            return self._owners(owner[hit], n_corners), dense
        keys = [p.key() for p in curve.pieces]
        known = np.array([k in self._free_pieces for k in keys], dtype=bool)
        todo = np.flatnonzero(~known[piece_of])
        ok = np.ones(len(dense), dtype=bool)
        if len(todo):
            ok[todo] = poses_free(dense[todo, :3], cfg.clearance)
        bad_pose = np.flatnonzero(~ok)
        failed = set(piece_of[bad_pose].tolist())
        for j in np.unique(piece_of[todo]).tolist():
            if j not in failed:
                self._free_pieces.add(keys[j])
        return self._owners(owner[bad_pose], n_corners), dense

    def output_samples(self, curve: ClothoidCurve) -> np.ndarray:
        """Rows at most ``sample_spacing`` apart with exact curvature; piece ends included."""
        rows, _ = sample_pieces(curve.pieces, self.cfg.sample_spacing, self._rows)
        ends = self.ends
        rows[0, :3] = (ends.start.x, ends.start.y, ends.start.yaw)
        rows[-1, :3] = (ends.goal.x, ends.goal.y, ends.goal.yaw)
        rows[:, 2] = wrap_angle(rows[:, 2])
        # Pieces shorter than a micrometre give rows on top of each other: keep the first.
        keep = np.ones(len(rows), dtype=bool)
        keep[1:] = np.hypot(*np.diff(rows[:, :2], axis=0).T) > 1e-6
        if not keep[-1]:  # the goal row stays, in place of the one just before it
            prev = int(np.flatnonzero(keep)[-1])
            keep[prev] = prev == 0
            keep[-1] = True
        return rows[keep]

    @staticmethod
    def _owners(owners: np.ndarray, n_corners: int) -> list[int]:
        last = n_corners - 2
        return sorted({min(max(int(c), 1), last) for c in np.unique(owners).tolist()})
