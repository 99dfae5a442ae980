"""Repairs of the key polygon, as named operations that each say whether they changed it.

A corner whose piece of curve breaks a limit gets its next treatment
(:meth:`Repairer.advance`): a fillet of the design radius, a wider one, then
moves of the corner, and last the putting back of pruned tree nodes or its
removal. A leg too short for the fillets at its ends is fixed by
:meth:`Repairer.fix_conflict`, which tries, in order: shrinking wide fillets,
growing a heading leg, stretching the leg, merging its corners, un-pruning or
dropping one, and moving one. Every change keeps the adjacent edges free.
"""

from __future__ import annotations

import math

import numpy as np

from rrtdrive.planning.smoothing.checks import EdgeCache
from rrtdrive.planning.smoothing.config import SmoothingConfig
from rrtdrive.planning.smoothing.corners import (
    Corner,
    CornerKind,
    Ends,
    KeyPolygon,
    deflection,
    kind_of,
    turn_reach,
    unit,
    unit_between,
)
from rrtdrive.planning.smoothing.operations import prune

__all__ = ["Repairer"]

_NODE = CornerKind.NODE
_START_LEG = CornerKind.START_LEG
_GOAL_LEG = CornerKind.GOAL_LEG


class Repairer:
    """The repair operations on one key polygon, with their counters.

    Parameters
    ----------
    poly : KeyPolygon
        The polygon to repair (changed in place).
    ends : Ends
        Start and goal of the path.
    edges : EdgeCache
        The memoised edge test.
    cfg : SmoothingConfig
        Tunables.
    tangents : dict, optional
        Clothoid tangent lengths per deflection and radius (:func:`turn_reach`'s
        memo), shared by the repairs of one ``make_drivable`` call.
    """

    def __init__(
        self,
        poly: KeyPolygon,
        ends: Ends,
        edges: EdgeCache,
        cfg: SmoothingConfig,
        tangents: dict[tuple[float, float], float] | None = None,
    ) -> None:
        self.poly = poly
        self.ends = ends
        self.edges = edges
        self.cfg = cfg
        self.tangents = tangents
        self.r_design = cfg.design_radius
        self.merges = 0
        self.moves = 0
        self.drops = 0
        self.unprunes = 0
        self._give_turns()

    def _give_turns(self) -> None:
        """Clothoid curves round every corner: a plain corner gets the design radius."""
        if self.cfg.clothoid:
            for corner in self.corners[1:-1]:
                if corner.radius <= 0.0:
                    corner.radius = self.r_design

    @property
    def corners(self) -> list[Corner]:
        """The polygon's corners (the list itself)."""
        return self.poly.corners

    # ------------------------------------------------------------- helpers

    def _free(self, a: np.ndarray, b: np.ndarray) -> bool:
        return self.edges.edge_free(a.tolist(), b.tolist())

    def _turn_at(self, c: int) -> float:
        p = self.corners
        return deflection(p[c - 1].point, p[c].point, p[c + 1].point)

    def _turn_ok(self, c: int, new: np.ndarray) -> bool:
        """Moving corner ``c`` to ``new`` keeps its turn below max(now, the hairpin limit)."""
        p = self.corners
        now = self._turn_at(c)
        return deflection(p[c - 1].point, new, p[c + 1].point) <= max(now, self.cfg.hairpin_turn)

    def _reach(self, c: int) -> float:
        """How far along each leg the turn of corner ``c`` (current radius) reaches."""
        p = self.corners
        return turn_reach(
            self.cfg,
            p[c].point,
            unit_between(p[c - 1].point, p[c].point)[:2],
            unit_between(p[c].point, p[c + 1].point)[:2],
            p[c].radius,
            self.tangents,
        )

    def _leg_length(self, leg: int) -> float:
        p = self.poly.corners
        # np.hypot(*(b - a)) with the difference taken in Python floats (the same values).
        (ax, ay), (bx, by) = p[leg].point.tolist(), p[leg + 1].point.tolist()
        return float(np.hypot(bx - ax, by - ay))

    # ------------------------------------------------------------- corner operations

    def place(self, c: int, new: np.ndarray) -> bool:
        """Put corner ``c`` at ``new`` when both adjacent legs stay free."""
        p = self.corners
        if not (self._free(p[c - 1].point, new) and self._free(new, p[c + 1].point)):
            return False
        p[c].point = new
        self.moves += 1
        return True

    def move(self, c: int, direction: str, dist: float) -> bool:
        """Move corner ``c`` by ``dist`` from its origin in ``direction`` (see the config)."""
        corner = self.corners[c]
        o, prev, nxt = corner.origin, self.corners[c - 1].point, self.corners[c + 1].point
        if corner.kind is _START_LEG:
            # Along the start ray, and only while its turn does not become a hairpin.
            new = o + dist * self.ends.hs
            if direction != "ahead" or not self._turn_ok(c, new):
                return False
            return self.place(c, new)
        if corner.kind is _GOAL_LEG:
            new = o - dist * self.ends.hg
            if direction != "back" or not self._turn_ok(c, new):
                return False
            return self.place(c, new)
        uix, uiy, _ = unit_between(prev, o)
        uox, uoy, _ = unit_between(o, nxt)
        if direction == "back":
            d = np.array([-uox, -uoy])
        elif direction == "ahead":
            d = np.array([uix, uiy])
        elif direction == "behind":
            if dist >= 0.9 * float(np.hypot(*(o - prev))):
                return False
            d = np.array([-uix, -uiy])
        else:
            bx, by, norm = unit(uix - uox, uiy - uoy)
            if norm == 0.0:
                return False
            d = np.array([bx, by]) * (1.0 if direction == "out" else -1.0)
        return self.place(c, o + dist * d)

    def advance(self, c: int) -> bool:
        """Next treatment for corner ``c``: plain -> fillets -> moves; False when exhausted."""
        steps, moves = self.cfg.radius_steps, self.cfg.corner_moves
        corner = self.corners[c]
        if self.cfg.clothoid and not corner.tight:
            # The gentlest clothoids that fit cut across the corner most: tighten first.
            corner.tight = True
            corner.attempt = max(corner.attempt, 1)
            return True
        while True:
            corner.attempt += 1
            a = corner.attempt
            if a <= len(steps):
                corner.radius = self.r_design * steps[a - 1]
                return True
            m = a - len(steps) - 1
            if m >= len(moves):
                return self.unprune(c) or self.drop(c)
            if self.move(c, *moves[m]):
                corner.radius = self.r_design
                return True

    def drop(self, c: int) -> bool:
        """Remove tree corner ``c`` when the edge joining its neighbours is free.

        Refused when it would leave a neighbour with a hairpin (a turn above
        ``drop_hairpin_turn``), which no fillet could round.
        """
        p = self.poly.points()
        if self.corners[c].kind is not _NODE or not self._free(p[c - 1], p[c + 1]):
            return False
        limit = self.cfg.drop_hairpin_turn
        if c - 2 >= 0 and deflection(p[c - 2], p[c - 1], p[c + 1]) > limit:
            return False
        if c + 2 < len(p) and deflection(p[c - 1], p[c + 1], p[c + 2]) > limit:
            return False
        del self.corners[c]
        self.drops += 1
        return True

    def unprune(self, c: int) -> bool:
        """Put back tree-path nodes between the neighbours of corner ``c`` (once per stretch)."""
        poly = self.poly
        i0, i1 = self.corners[c - 1].raw_index, self.corners[c + 1].raw_index
        if i0 < 0 or i1 < 0 or i1 - i0 < 3 or (i0, i1) in poly.unpruned:
            return False
        poly.unpruned.add((i0, i1))
        n_aug = len(poly.aug)
        p = poly.points()
        into = p[c - 1] - p[c - 2] if c >= 2 else self.ends.hs
        after = p[c + 2] - p[c + 1] if c + 2 < len(p) else self.ends.hg
        # The heading points (augmented indices 1 and n - 2) always stay.
        anchors = [k - i0 for k in (1, n_aug - 2) if i0 < k < i1]
        sub = prune(
            poly.aug[i0 : i1 + 1],
            self.edges,
            keep=anchors,
            max_turn=self.cfg.unprune_turn,
            start_heading=into,
            end_heading=after,
        )
        if sub is None or len(sub) <= 2:
            return False
        idx = [i0 + int(k) for k in sub[1:-1]]
        self.corners[c : c + 1] = [Corner.at(poly.aug[k], kind_of(k, n_aug), k) for k in idx]
        self._give_turns()
        self.unprunes += 1
        return True

    def merge(self, i: int) -> bool:
        """Replace corners ``i`` and ``i + 1`` by the crossing of their outer legs, if free."""
        p = self.corners
        kind_a, kind_b = p[i].kind, p[i + 1].kind
        if kind_a is _START_LEG and kind_b is _GOAL_LEG:
            return False
        a0, a1, b0, b1 = p[i - 1].point, p[i].point, p[i + 1].point, p[i + 2].point
        uax, uay, la = unit_between(a0, a1)
        ubx, uby, lb = unit_between(b0, b1)
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
        new_kind = kind_a if kind_a is _START_LEG else kind_b
        raw_index = p[i].raw_index if new_kind is _START_LEG else p[i + 1].raw_index
        p[i : i + 2] = [Corner(y, y.copy(), new_kind, raw_index, self.r_design, 1)]
        self.merges += 1
        return True

    # ------------------------------------------------------------- leg operations

    def _leg_fits(self, leg: int) -> bool:
        """Whether leg ``leg`` is long enough for the fillets at both its ends."""
        n = len(self.corners)
        need = 0.0
        for c in (leg, leg + 1):
            if 0 < c < n - 1 and self.corners[c].radius > 0.0:
                need += self._reach(c)
        gap = self.cfg.end_gap if leg in (0, n - 2) else 0.0
        return need + gap <= self._leg_length(leg)

    def _stretch_moves(self, leg: int) -> list[tuple[int, np.ndarray]]:
        """Candidate shifts ``(corner, delta)`` that lengthen leg ``leg``, in order."""
        p, n = self.corners, len(self.corners)
        moves: list[tuple[int, np.ndarray]] = []
        if leg == n - 2:
            # The goal leg: the turn at the goal-leg point eases when the corner
            # before it turns earlier.
            if n - 3 > 0 and p[n - 3].kind is _NODE:
                back = unit_between(p[n - 3].point, p[n - 4].point)[:2]
                moves += [(n - 3, np.asarray(back) * d) for d in (3.0, 6.0, 10.0)]
        elif leg == 0:
            if n > 3 and p[2].kind is _NODE:
                on = unit_between(p[2].point, p[3].point)[:2]
                moves += [(2, np.asarray(on) * d) for d in (3.0, 6.0, 10.0)]
        else:
            length = self._leg_length(leg)
            for c, other in ((leg, leg - 1), (leg + 1, leg + 2)):
                if p[c].kind is not _NODE or p[c].radius <= 0.0:
                    continue
                away = unit_between(p[c].point, p[other].point)[:2]
                moves += [(c, np.asarray(away) * d) for d in (0.5 * length, length, 2.0 * length)]
        return moves

    def stretch(self, leg: int) -> bool:
        """Lengthen leg ``leg`` by moving a tree corner next to it along its other leg.

        The corner before the leg moves back along its incoming line, the one after
        it on along its outgoing line, until the fillets fit (edges checked).
        """
        p, n = self.corners, len(self.corners)
        # Per corner, 0.9 times the leg it shifts along: a failed shift puts the corner
        # back, so the limit is the same for all its shifts.
        limits: dict[int, float] = {}
        for c, delta in self._stretch_moves(leg):
            if c <= 0 or c >= n - 1:
                continue
            limit = limits.get(c)
            if limit is None:
                other = p[c - 1 if c == leg else c + 1].point
                limit = limits[c] = 0.9 * float(np.hypot(*(other - p[c].point)))
            if float(np.hypot(*delta)) >= limit:
                continue
            old = p[c].point.copy()
            if not self.place(c, old + delta):
                continue
            if self._leg_fits(leg) or (leg == n - 2 and self._leg_fits(leg - 1)):
                p[c].origin = p[c].point.copy()
                return True
            p[c].point = old
        return False

    def _conflict_corners(self, leg: int) -> list[int]:
        n = len(self.corners)
        return [c for c in (leg, leg + 1) if 0 < c < n - 1 and self.corners[c].radius > 0.0]

    def shrink_wide_fillets(self, leg: int) -> bool:
        """Give the filleted corners at the ends of leg ``leg`` the design radius again."""
        shrunk = False
        for c in self._conflict_corners(leg):
            corner = self.corners[c]
            if corner.radius > self.r_design * (1.0 + 1e-9):
                corner.radius = self.r_design
                shrunk = True
        return shrunk

    def grow_heading_leg(self, leg: int) -> bool:
        """Lengthen a heading leg (``leg`` first or last) to fit its fillet, twice at most.

        Beyond that the turn after it has to change. Only while the fillet fits at
        all and the turn at the heading point does not become a hairpin.
        """
        n = len(self.corners)
        c = 1 if leg == 0 else n - 2 if leg == n - 2 else -1
        grown = self.poly.grown
        if c < 0 or grown.get(c, 0) >= 2:
            return False
        grown[c] = grown.get(c, 0) + 1
        ray, end = (self.ends.hs, self.ends.s) if leg == 0 else (-self.ends.hg, self.ends.g)
        corner = self.corners[c]
        reach = self._reach(c)
        length = float(np.hypot(*(corner.point - end)))
        new_length = reach + 0.5 + 0.1 * length
        new = end + new_length * ray if math.isfinite(new_length) else None
        if (
            new is not None
            and self._turn_ok(c, new)
            and self.place(c, new)
        ):
            corner.origin = corner.point.copy()
            return True
        return False

    def merge_at(self, leg: int) -> bool:
        """Merge the corners at the ends of leg ``leg`` (at a heading leg: the next two)."""
        n = len(self.corners)
        if 0 < leg < n - 2 and self.merge(leg):
            return True
        if leg == 0 and n > 4 and self.merge(1):
            return True
        return leg == n - 2 and n > 4 and self.merge(n - 3)

    def unprune_or_drop(self, leg: int) -> bool:
        """Put back the tree nodes around a hairpin at leg ``leg``, or drop one of its corners."""
        corners = self._conflict_corners(leg)
        for c in corners:
            if self._turn_at(c) > self.cfg.unprune_hairpin_turn and self.unprune(c):
                return True
        return any(self.drop(c) for c in corners)

    def advance_at(self, leg: int) -> bool:
        """Move one corner of leg ``leg``; at a heading leg also the tree corner next to it."""
        n = len(self.corners)
        corners = self._conflict_corners(leg)
        heading = 1 if leg == 0 else n - 2 if leg == n - 2 else -1
        if heading > 0:
            near = 2 if heading == 1 else n - 3
            if self.corners[near].kind is _NODE and self.corners[near].radius > 0.0:
                corners.append(near)
        n_steps = len(self.cfg.radius_steps)
        for c in sorted(corners, key=lambda c: -self.corners[c].radius):
            corner = self.corners[c]
            if corner.attempt < n_steps:
                corner.attempt = n_steps  # straight to the moves
            corner.tight = True  # a gentler turn only needs more room
            if self.advance(c):
                return True
        return False

    def fix_conflict(self, leg: int) -> bool:
        """Make leg ``leg`` long enough for the fillets at its ends; False when nothing helps."""
        return (
            self.shrink_wide_fillets(leg)
            or self.grow_heading_leg(leg)
            or self.stretch(leg)
            or self.merge_at(leg)
            or self.unprune_or_drop(leg)
            or self.advance_at(leg)
        )
