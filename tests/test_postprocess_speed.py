"""Post-processing's memos give the old answers bit for bit.

What one ``make_drivable`` call shares between its two pruning attempts -- the
edge answers and screens (each attempt still counts its own ``edge_checks``),
the clothoid turns, sampled rows and the repairs' tangent lengths -- and
``Repairer.stretch`` working out each corner's shift limit once, against the old
code (caches of their own per attempt, the old ``stretch`` kept here, set up by
monkeypatching); on tree paths of the default planner for random starts of
parking_lot that fail post-processing with reverse, and random goals it solves
forward.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import rrtdrive.planning.improved.planner as improved_planner
from rrtdrive.maps import builtin_map
from rrtdrive.planning import PlanningProblem
from rrtdrive.planning.base import cached_checker
from rrtdrive.planning.improved import ImprovedRRTConnect
from rrtdrive.planning.smoothing import checks, drivable, make_drivable
from rrtdrive.planning.smoothing.repair import Repairer
from rrtdrive.pose_sets import random_free_poses
from rrtdrive.types import Budget


def _tree_paths() -> list[tuple]:
    """``(raw, start, goal, config)`` of every ``make_drivable`` call of a few queries."""
    calls: list[tuple] = []
    real = improved_planner.make_drivable

    def record(raw, start, goal, checker, cfg):  # noqa: ANN001, ANN202
        calls.append((np.array(raw), start, goal, cfg))
        return real(raw, start, goal, checker, cfg)

    base = builtin_map("parking_lot")
    starts = random_free_poses("parking_lot", 100, 1, "start")
    goals = random_free_poses("parking_lot", 100, 1, "goal")
    queries = [(dataclasses.replace(base, start=starts[i]), True) for i in (30, 31, 33, 44)]
    queries += [(dataclasses.replace(base, goal=goals[i]), False) for i in (3, 9, 12)]
    planner = ImprovedRRTConnect(escalation=False, dubins_fallback=False)
    improved_planner.make_drivable = record
    try:
        for m, reverse in queries:
            problem = PlanningProblem.from_map(m, reverse=reverse)
            planner.solve(problem, np.random.default_rng(0), Budget(max_time_s=60.0))
    finally:
        improved_planner.make_drivable = real
    return calls


@pytest.fixture(scope="module")
def tree_paths() -> list[tuple]:
    return _tree_paths()


def _same(a, b) -> None:  # noqa: ANN001 - two SmoothingResults
    assert (a.ok, a.message, a.rounds, a.stats) == (b.ok, b.message, b.rounds, b.stats)
    assert a.samples.tobytes() == b.samples.tobytes()
    assert np.asarray(a.key_points).tobytes() == np.asarray(b.key_points).tobytes()
    assert np.asarray(a.control_points).tobytes() == np.asarray(b.control_points).tobytes()
    assert repr(a.max_curvature) == repr(b.max_curvature)
    assert repr(a.max_sharpness) == repr(b.max_sharpness)


def _old_stretch(self, leg):  # noqa: ANN001, ANN202 - Repairer.stretch before the limits
    p, n = self.corners, len(self.corners)
    for c, delta in self._stretch_moves(leg):
        if c <= 0 or c >= n - 1:
            continue
        other = p[c - 1 if c == leg else c + 1].point
        if float(np.hypot(*delta)) >= 0.9 * float(np.hypot(*(other - p[c].point))):
            continue
        old = p[c].point.copy()
        if not self.place(c, old + delta):
            continue
        if self._leg_fits(leg) or (leg == n - 2 and self._leg_fits(leg - 1)):
            p[c].origin = p[c].point.copy()
            return True
        p[c].point = old
    return False


def _use_old_code(monkeypatch) -> None:  # noqa: ANN001
    """Caches of their own per attempt, no tangent memo, the old ``stretch``."""
    real_init = checks.EdgeCache.__init__
    real_attempt = drivable._attempt

    def own_memos(self, view) -> None:  # noqa: ANN001
        view.edge_memo, view.screen_memo = {}, {}
        real_init(self, view)

    def fresh_attempt(raw, ends, view, cfg, max_turn, shared):  # noqa: ANN001, ANN202
        return real_attempt(raw, ends, view, cfg, max_turn, drivable._Shared())

    class NoTangents(Repairer):
        def __init__(self, poly, ends, edges, cfg, tangents=None) -> None:  # noqa: ANN001
            super().__init__(poly, ends, edges, cfg, None)

        stretch = _old_stretch

    monkeypatch.setattr(checks.EdgeCache, "__init__", own_memos)
    monkeypatch.setattr(drivable, "_attempt", fresh_attempt)
    monkeypatch.setattr(drivable, "Repairer", NoTangents)


def test_shared_memos_give_the_old_results(tree_paths, monkeypatch) -> None:
    checker = cached_checker(builtin_map("parking_lot"))
    new = [make_drivable(raw, s, g, checker, cfg) for raw, s, g, cfg in tree_paths]
    assert any(not r.ok for r in new) and any(r.ok for r in new)
    _use_old_code(monkeypatch)
    old = [make_drivable(raw, s, g, checker, cfg) for raw, s, g, cfg in tree_paths]
    for a, b in zip(new, old, strict=True):
        _same(a, b)


def test_edge_caches_of_one_view_share_answers_and_count_their_own() -> None:
    checker = cached_checker(builtin_map("parking_lot"))
    asked: list[tuple] = []

    class Counting:
        def edge_free(self, a, b):  # noqa: ANN001, ANN202
            asked.append((*a, *b))
            return checker.edge_free(a, b)

    view = checks.CheckerView(Counting())
    rng = np.random.default_rng(2)
    edges = [rng.uniform(0.0, 40.0, 4).tolist() for _ in range(30)]
    first, second = checks.EdgeCache(view), checks.EdgeCache(view)
    for e in edges[:20]:
        assert first.edge_free(e[:2], e[2:]) == checker.edge_free(e[:2], e[2:])
    for e in edges[10:]:
        assert second.edge_free(e[:2], e[2:]) == checker.edge_free(e[:2], e[2:])
    assert (first.checks, second.checks) == (20, 20)  # as with caches of their own
    assert len(asked) == 30  # each edge asked of the checker once


def test_unit_between_is_unit_of_the_difference() -> None:
    from rrtdrive.planning.smoothing.corners import deflection, unit, unit_between

    rng = np.random.default_rng(6)
    pts = rng.uniform(-100.0, 100.0, (4000, 2)) * rng.choice([1e-13, 1e-7, 1.0, 1e3], (4000, 1))
    pts[::50] = pts[1::50]  # repeated points: the zero vector
    for a, b, c in zip(pts[:-2], pts[1:-1], pts[2:], strict=True):
        assert [repr(float(v)) for v in unit(*(b - a))] == [repr(v) for v in unit_between(a, b)]
        ux, uy, _ = unit(*(b - a))
        vx, vy, _ = unit(*(c - b))
        old = math.atan2(abs(ux * vy - uy * vx), ux * vx + uy * vy)
        assert repr(float(old)) == repr(deflection(a, b, c))


def test_leg_length_and_curve_pieces_give_the_old_floats() -> None:
    from rrtdrive.planning.smoothing.clothoid_curve import curve_pieces, polygon_turns
    from rrtdrive.planning.smoothing.corners import unit

    rng = np.random.default_rng(9)
    pts = rng.uniform(-100.0, 100.0, (3000, 2)) * rng.choice([1e-9, 1.0, 1e3], (3000, 1))
    for a, b in zip(pts[:-1], pts[1:], strict=True):
        (ax, ay), (bx, by) = a.tolist(), b.tolist()
        assert repr(float(np.hypot(*(b - a)))) == repr(float(np.hypot(bx - ax, by - ay)))

    def old_turn_piece(pts, turns, i):  # noqa: ANN001, ANN202 - curve_pieces' turn, as it was
        t = turns[i]
        (x0, y0), pu, pv = pts[i], pts[i - 1], pts[i]
        vx, vy, _ = unit(pv[0] - pu[0], pv[1] - pu[1])
        return (i, x0 - t.tangent * vx, y0 - t.tangent * vy, math.atan2(vy, vx), t.length, t)

    seen = 0
    for _ in range(300):
        n = int(rng.integers(3, 8))
        poly = np.cumsum(rng.uniform(-25.0, 25.0, (n, 2)), axis=0).tolist()
        turns, conflicts = polygon_turns(poly, [1 / 6] * n, np.array([0.08]), [True] * n, 0.0)
        if conflicts:
            continue
        got = [tuple(p) for p in curve_pieces(poly, turns) if p.turn is not None]
        want = [old_turn_piece(poly, turns, i) for i in range(1, n - 1) if turns[i] is not None]
        assert repr(got) == repr(want)
        seen += len(got)
    assert seen > 100
